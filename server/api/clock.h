/* clock.h -- deadlines on the monotonic clock, for the server's timed waits.
 *
 * Every thread of the server that waits with a time limit waits on a condition variable timed
 * on CLOCK_MONOTONIC (so a change of the wall clock cannot stretch or cut a wait), and takes its
 * deadline from here. Used by the job runner (jobs.c), the PostgreSQL job store
 * (jobstore_pg.c) and the daemon (pool.c, conns.c).
 */
#ifndef LJGAP_CLOCK_H
#define LJGAP_CLOCK_H

#include <pthread.h>
#include <time.h>

/* Seconds on CLOCK_MONOTONIC: timings and deadlines of the server (the core keeps its own). */
double ljgap__clock_now(void);
/* Seconds since t0 (a CLOCK_MONOTONIC reading). */
double ljgap__clock_since(const struct timespec *t0);

/* The absolute CLOCK_MONOTONIC time s seconds from now (s <= 0 or NaN: now; at most 1e6 s). */
struct timespec ljgap__deadline_in(double s);

/* Initialises c as a condition variable whose timed waits use CLOCK_MONOTONIC (0, or the
 * pthread error). */
int ljgap__cond_init_monotonic(pthread_cond_t *c);

#endif
