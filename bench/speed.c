/* speed.c -- the speed figures of the numerical core (printed, never asserted).
 *
 *   speed              medians over repeated runs of: the Fig. 4 adhesion at the default
 *                      tolerance; a 200-point traction curve (g_ave 1.5..6, with the summary);
 *                      the paper's iteration at Vmax = 1/400 against the PDE at equal error
 *                      (wall-time ratio); and the actual errors of the default answers against
 *                      a tol-1e-10 run.
 *   speed --once CASE  one computation of CASE (fig4 or curve), for instruction counting
 *                      under callgrind (bench/run.sh counts ljgap_traction and what it calls).
 *
 * Fig. 4 case: D = 2.5, k1 = 1, k2 = ∞, C = 1/(4π) (theory.md §4).
 */
#include "bench.h"
#include "core.h" /* ljgap__now */
#include "ljgap.h"

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RUNS 15
#define NCURVE 200

/* One case: the adhesion alone, or the curve at NCURVE mean gaps with the summary. */
typedef struct {
    ljgap_psd psd;
    ljgap_opts o;
    size_t n;            /* mean gaps (0: the adhesion) */
    double g[NCURVE];    /* mean gaps */
    ljgap_est s[NCURVE]; /* tractions */
    ljgap_summary sum;   /* adhesion summary */
    int want_sum;        /* ask for the summary */
    int warned;          /* warnings of the last run */
} speed_case;

static void case_init(speed_case *c, size_t n)
{
    memset(c, 0, sizeof *c);
    ljgap_psd_power(&c->psd, 2.5, 1.0, INFINITY, LJGAP_LEVEL_C, 1.0 / (4.0 * M_PI));
    ljgap_opts_default(&c->o);
    c->n = n;
    c->want_sum = 1;
    for (size_t i = 0; i < n; i++)
        c->g[i] = 1.5 + 4.5 * (double)i / (double)(n - 1);
}

/* Wall time (ms) of one computation of c. */
static double run(speed_case *c)
{
    ljgap_warnings w = {0};
    double t = ljgap__now();
    int st = ljgap_traction(&c->psd, &c->o, c->g, c->n, c->s, c->want_sum ? &c->sum : NULL, &w);
    t = ljgap__now() - t;
    if (st) {
        fprintf(stderr, "speed: %s\n", ljgap_strerror(st));
        exit(1);
    }
    c->warned = w.n;
    return 1e3 * t;
}

static double median_ms(speed_case *c)
{
    double t[RUNS];
    for (int i = 0; i < RUNS; i++)
        t[i] = run(c);
    return bench_median(t, RUNS);
}

/* Largest |value - reference| / max(1, |reference|) and actual/estimated error over the four
 * summary quantities and the tractions of c, against ref (the same case at tol 1e-10). */
static void actual_errors(const speed_case *c, const speed_case *ref, double *rel, double *ratio)
{
    const ljgap_est *a = &c->sum.g_eq, *b = &ref->sum.g_eq;
    *rel = *ratio = 0;
    for (size_t q = 0; q < 4 + c->n; q++) {
        const ljgap_est *x = q < 4 ? &a[q] : &c->s[q - 4], *y = q < 4 ? &b[q] : &ref->s[q - 4];
        double d = fabs(x->value - y->value);
        *rel = fmax(*rel, d / fmax(1.0, fabs(y->value)));
        *ratio = fmax(*ratio, d / x->err);
    }
}

int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    static speed_case fig4, curve, ref;
    case_init(&fig4, 0);
    case_init(&curve, NCURVE);
    if (argc > 2 && strcmp(argv[1], "--once") == 0) {
        speed_case *c = strcmp(argv[2], "curve") == 0 ? &curve : &fig4;
        run(c);
        printf("%s: g_eq %.8f sigma_max %.8f dgamma_eff %.8f\n", argv[2], c->sum.g_eq.value,
               c->sum.sigma_max.value, c->sum.dgamma_eff.value);
        return 0;
    }
    double t4 = median_ms(&fig4);
    printf("fig4_adhesion_ms_median %.2f (tol 1e-6, %d runs; g_eq %.7f ± %.1e, dgamma_eff "
           "%.7f ± %.1e)\n",
           t4, RUNS, fig4.sum.g_eq.value, fig4.sum.g_eq.err, fig4.sum.dgamma_eff.value,
           fig4.sum.dgamma_eff.err);
    double tc = median_ms(&curve);
    printf("traction_200_points_ms_median %.2f (g_ave 1.5..6 and the summary, %d runs)\n", tc,
           RUNS);

    /* the default answers against tol 1e-10 */
    case_init(&ref, NCURVE);
    ref.o.tol = 1e-10;
    ref.o.max_work *= 100;
    ref.o.max_seconds = 600;
    run(&ref);
    double rel, ratio;
    actual_errors(&fig4, &ref, &rel, &ratio);
    printf("fig4_actual_error %.1e (largest of the four, relative; reference tol 1e-10%s), "
           "largest actual/estimated %.2f\n",
           rel, ref.warned ? ", warned" : "", ratio);
    actual_errors(&curve, &ref, &rel, &ratio);
    printf("traction_200_actual_error %.1e (largest of the tractions and the summary, "
           "relative), largest actual/estimated %.2f\n",
           rel, ratio);

    /* the paper's iteration at Vmax = 1/400 against the PDE at the same error, on sigma_bar
     * at one mean gap (the paper's iteration answers one point per forward run) */
    speed_case one;
    case_init(&one, 0);
    one.n = 1;
    one.g[0] = 2.0;
    one.want_sum = 0;
    one.o.tol = 1e-10;
    run(&one);
    double exact = one.s[0].value;
    one.o.method = LJGAP_METHOD_PAPER;
    one.o.vmax = 1.0 / 400.0;
    one.o.tol = 1.0; /* no refinement beyond the first comparison */
    double tp = run(&one);
    double err_paper = fabs(one.s[0].value - exact);
    one.o.method = LJGAP_METHOD_PDE;
    one.o.tol = err_paper;
    double tpde = median_ms(&one);
    printf("paper_vs_pde: sigma_bar(g=%.1f) paper(Vmax=1/400) error %.2e in %.0f ms; pde at "
           "tol %.1e: error %.2e in %.2f ms; ratio %.0f\n",
           one.g[0], err_paper, tp, err_paper, fabs(one.s[0].value - exact), tpde, tp / tpde);
    return 0;
}
