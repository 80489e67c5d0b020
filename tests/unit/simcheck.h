/* simcheck.h -- what the tests of the discrete model share (include after cmocka.h):
 * the Fig. 6 spectrum, options of a small run, a run that prints the warnings of a failure,
 * and a progress callback. */
#ifndef LJGAP_TEST_SIMCHECK_H
#define LJGAP_TEST_SIMCHECK_H

#include "ljgap_sim.h"

/* D = 2.2, k1 = 1, k2 (may be INFINITY), level m0 (theory.md §5) */
static inline ljgap_psd fig6_psd(double m0, double k2)
{
    ljgap_psd p;
    assert_int_equal(ljgap_psd_power(&p, 2.2, 1.0, k2, LJGAP_LEVEL_M0, m0), LJGAP_OK);
    return p;
}

/* The defaults with n, R realizations, k_split (0: the plain model) and a 60 s cap. */
static inline ljgap_sim_opts sim_opts(int n, int R, double k_split)
{
    ljgap_sim_opts o;
    ljgap_sim_opts_default(&o);
    o.n = n;
    o.realizations = R;
    o.max_seconds = 60;
    o.k_split = k_split;
    return o;
}

static inline int run(const ljgap_psd *p, const ljgap_sim_opts *o, const double *g, size_t n,
                      ljgap_sim_result *r)
{
    ljgap_warnings w = {0};
    int st = ljgap_sim_run(p, o, g, n, r, &w);
    if (st != LJGAP_OK)
        for (int i = 0; i < w.n; i++)
            print_error("%s\n", w.msg[i]);
    return st;
}

/* A progress callback that counts its calls, notes a fraction going back or past 1, and sets
 * *cancel when given one. */
typedef struct {
    volatile int *cancel;
    double last;
    int calls, backwards;
} prog_ctx;

static inline void on_progress(void *ctx, double f)
{
    prog_ctx *c = ctx;
    if (f < c->last || f > 1.0) c->backwards = 1;
    c->last = f;
    c->calls++;
    if (c->cancel) *c->cancel = 1;
}

#endif
