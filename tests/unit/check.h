/* check.h -- a numeric assertion and a sleep shared by the cmocka test programs (include after
 * cmocka.h). */
#ifndef LJGAP_TEST_CHECK_H
#define LJGAP_TEST_CHECK_H

#include <math.h>
#include <time.h>

/* |a - b| <= tol, printing both at full precision when not */
#define assert_close(a, b, tol)                                                                    \
    do {                                                                                           \
        double a_ = (a), b_ = (b), t_ = (tol);                                                     \
        if (!(fabs(a_ - b_) <= t_)) {                                                              \
            print_error("%s = %.17g, %s = %.17g, |diff| = %.3g > %.3g\n", #a, a_, #b, b_,          \
                        fabs(a_ - b_), t_);                                                        \
            fail();                                                                                \
        }                                                                                          \
    } while (0)

static inline void sleep_ms(int ms)
{
    struct timespec t = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&t, NULL);
}

#endif
