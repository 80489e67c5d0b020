/* clock.c -- deadlines on the monotonic clock (clock.h). */
#include "clock.h"

#include <math.h>

struct timespec ljgap__deadline_in(double s)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    if (!(s > 0)) return t;
    if (s > 1e6) s = 1e6;
    t.tv_sec += (time_t)s;
    t.tv_nsec += (long)((s - floor(s)) * 1e9);
    if (t.tv_nsec >= 1000000000L) {
        t.tv_sec++;
        t.tv_nsec -= 1000000000L;
    }
    return t;
}

int ljgap__cond_init_monotonic(pthread_cond_t *c)
{
    pthread_condattr_t ca;
    int e = pthread_condattr_init(&ca);
    if (e) return e;
    e = pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    if (!e) e = pthread_cond_init(c, &ca);
    pthread_condattr_destroy(&ca);
    return e;
}

double ljgap__clock_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double ljgap__clock_since(const struct timespec *t0)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)(t.tv_sec - t0->tv_sec) + 1e-9 * (double)(t.tv_nsec - t0->tv_nsec);
}
