/* speed.c -- the speed figures of the numerical core (printed, never asserted).
 *
 *   speed            medians over repeated runs of: the Fig. 4 adhesion at the default
 *                    tolerance; a 200-point traction curve; the paper's iteration at
 *                    Vmax = 1/400 against the PDE at equal error (wall-time ratio).
 *   speed --once     one Fig. 4 adhesion, for instruction counting under callgrind.
 *
 * Fig. 4 case: D = 2.5, k1 = 1, k2 = ∞, C = 1/(4π) (theory.md §4).
 */
#include "ljgap.h"

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RUNS 15

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* Wall time (ms) of one adhesion or traction computation; the summary in *s. */
static double run(const ljgap_psd *p, const ljgap_opts *o, const double *g, size_t n,
                  ljgap_est *sig, ljgap_summary *s, int *warned)
{
    ljgap_warnings w = {0};
    double t = ljgap_now();
    int st = ljgap_traction(p, o, g, n, sig, s, &w);
    t = ljgap_now() - t;
    if (st) {
        fprintf(stderr, "speed: %s\n", ljgap_strerror(st));
        exit(1);
    }
    if (warned) *warned = w.n;
    return 1e3 * t;
}

int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    ljgap_psd p;
    ljgap_psd_power(&p, 2.5, 1.0, INFINITY, LJGAP_LEVEL_C, 1.0 / (4.0 * M_PI));
    ljgap_opts o;
    ljgap_opts_default(&o);
    ljgap_summary s;
    if (argc > 1 && strcmp(argv[1], "--once") == 0) {
        run(&p, &o, NULL, 0, NULL, &s, NULL);
        printf("g_eq %.8f sigma_max %.8f dgamma_eff %.8f\n", s.g_eq.value, s.sigma_max.value,
               s.dgamma_eff.value);
        return 0;
    }
    double t[RUNS];
    for (int i = 0; i < RUNS; i++) t[i] = run(&p, &o, NULL, 0, NULL, &s, NULL);
    printf("fig4_adhesion_ms_median %.2f (tol 1e-6, %d runs; g_eq %.7f ± %.1e, dgamma_eff "
           "%.7f ± %.1e)\n",
           median(t, RUNS), RUNS, s.g_eq.value, s.g_eq.err, s.dgamma_eff.value, s.dgamma_eff.err);

    double g[200];
    ljgap_est sig[200];
    for (int i = 0; i < 200; i++) g[i] = 0.8 + (6.0 - 0.8) * i / 199.0;
    for (int i = 0; i < RUNS; i++) t[i] = run(&p, &o, g, 200, sig, &s, NULL);
    printf("traction_200_points_ms_median %.2f\n", median(t, RUNS));

    /* the paper's iteration at Vmax = 1/400 against the PDE at the same error, on sigma_bar
     * at one mean gap (the paper's iteration answers one point per forward run) */
    double gp = 2.0;
    ljgap_est ref, e;
    o.tol = 1e-10;
    run(&p, &o, &gp, 1, &ref, NULL, NULL);
    ljgap_opts op = o;
    op.method = LJGAP_METHOD_PAPER;
    op.vmax = 1.0 / 400.0;
    op.tol = 1.0; /* no refinement beyond the first comparison */
    int warned = 0;
    double tp = run(&p, &op, &gp, 1, &e, NULL, &warned);
    double err_paper = fabs(e.value - ref.value);
    ljgap_opts oe = o;
    oe.tol = err_paper;
    double tq[RUNS];
    for (int i = 0; i < RUNS; i++) tq[i] = run(&p, &oe, &gp, 1, &e, NULL, NULL);
    double tpde = median(tq, RUNS);
    printf("paper_vs_pde: sigma_bar(g=%.1f) paper(Vmax=1/400) error %.2e in %.0f ms; pde at "
           "tol %.1e: error %.2e in %.2f ms; ratio %.0f\n",
           gp, err_paper, tp, err_paper, fabs(e.value - ref.value), tpde, tp / tpde);
    return 0;
}
