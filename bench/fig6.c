/* fig6.c -- the paper's Fig. 6: the discrete numerical model (core/sim/sim.c) against the
 * statistical theory (ljgap_traction, PDE method) for D = 2.2, k1 = 1, k2 = 8 and
 * m0 = 0.1, 0.218, 0.3, four realizations (theory.md §5).
 *
 *   fig6 [--n N] [--realizations R] [--L L] [--no-match] [--no-header]   the table (CSV)
 *   fig6 --convergence                                          convergence in n and in R
 *
 * The table has, per m0 and mean gap: the numerical mean traction averaged over the
 * realizations, its standard deviation and error estimate, the theory with its error, the
 * difference, the largest solver residual and the jump flag; '#' lines carry the timings and
 * the realized variances. The convergence table repeats m0 = 0.218 at a few gaps for
 * n = 32..256 at L = 2π (four realizations: the same surfaces on finer grids), for R = 1..16
 * (n = 64), and for L = 2π, 4π, 8π at the same spacing (n = 64, 128, 256).
 */
#include "ljgap_sim.h"
#include "core.h" /* ljgap__now */

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double fig_m0[] = {0.1, 0.218, 0.3};

static int make_psd(ljgap_psd *p, double m0)
{
    return ljgap_psd_power(p, 2.2, 1.0, 8.0, LJGAP_LEVEL_M0, m0);
}

static int theory(const ljgap_psd *p, const double *g, size_t n, ljgap_est *out)
{
    ljgap_opts o;
    ljgap_opts_default(&o);
    o.max_seconds = 120;
    ljgap_warnings w = {0};
    int st = ljgap_traction(p, &o, g, n, out, NULL, &w);
    for (int i = 0; i < w.n; i++)
        fprintf(stderr, "theory: %s\n", w.msg[i]);
    return st;
}

static int run(const ljgap_psd *p, const ljgap_sim_opts *o, const double *g, size_t n,
               ljgap_sim_result *res, double *secs)
{
    ljgap_warnings w = {0};
    double t = ljgap__now();
    int st = ljgap_sim_run(p, o, g, n, res, &w);
    *secs = ljgap__now() - t;
    for (int i = 0; i < w.n; i++)
        fprintf(stderr, "sim: %s\n", w.msg[i]);
    if (st) fprintf(stderr, "sim: %s\n", ljgap_strerror(st));
    return st;
}

static int table(const ljgap_sim_opts *o, int header)
{
    enum { NG = 23 };
    double g[NG];
    for (int i = 0; i < NG; i++)
        g[i] = 0.8 + 0.1 * i; /* 0.8 .. 3.0 */
    if (header)
        printf("L,m0,g_ave,sigma_num,sigma_std,sigma_err,sigma_theory,theory_err,diff,residual,"
               "jump\n");
    for (size_t k = 0; k < sizeof fig_m0 / sizeof fig_m0[0]; k++) {
        ljgap_psd p;
        ljgap_est th[NG];
        ljgap_sim_result r;
        double secs;
        if (make_psd(&p, fig_m0[k]) || theory(&p, g, NG, th) || run(&p, o, g, NG, &r, &secs))
            return 1;
        printf("# m0 = %g: n = %d, L = %.6g, R = %d, %.2f s, m0_grid = %.6g, m0_realized =", p.m0,
               r.n, r.L, r.realizations, secs, r.m0_grid);
        for (int i = 0; i < r.realizations; i++)
            printf(" %.6g", r.m0_realized[i]);
        printf("\n");
        for (int i = 0; i < NG; i++)
            printf("%.4f,%g,%.3f,%.6f,%.6f,%.6f,%.6f,%.2g,%.6f,%.2g,%d\n", r.L, p.m0, g[i],
                   r.sigma[i], r.sigma_std[i], r.sigma_err[i], th[i].value, th[i].err,
                   r.sigma[i] - th[i].value, r.residual[i], r.jump[i]);
        fflush(stdout);
        ljgap_sim_result_free(&r);
    }
    return 0;
}

static int convergence(void)
{
    enum { NG = 5 };
    const double g[NG] = {1.0, 1.2, 1.5, 2.0, 2.5};
    ljgap_psd p;
    ljgap_est th[NG];
    if (make_psd(&p, 0.218) || theory(&p, g, NG, th)) return 1;
    printf("study,n,L,realizations,seconds");
    for (int i = 0; i < NG; i++)
        printf(",sigma_%.1f,err_%.1f,diff_%.1f", g[i], g[i], g[i]);
    printf("\n");
    printf("theory,,,,");
    for (int i = 0; i < NG; i++)
        printf(",%.6f,%.2g,0", th[i].value, th[i].err);
    printf("\n");
    /* n at L = 2π (the same surfaces, finer grids); R at n = 64; L at a fixed spacing */
    const int ns[] = {32, 64, 128, 256}, Rs[] = {1, 2, 4, 8, 16}, Ls[] = {1, 2, 4};
    static const char *study[] = {"n", "realizations", "L"};
    for (int pass = 0; pass < 3; pass++) {
        int cnt = pass == 0 ? 4 : pass == 1 ? 5 : 3;
        for (int k = 0; k < cnt; k++) {
            ljgap_sim_opts o;
            ljgap_sim_opts_default(&o);
            o.n = pass == 0 ? ns[k] : pass == 1 ? 64 : 64 * Ls[k];
            o.realizations = pass == 1 ? Rs[k] : 4;
            o.L = pass == 2 ? 2 * M_PI * Ls[k] : 0.0;
            ljgap_sim_result r;
            double secs;
            if (run(&p, &o, g, NG, &r, &secs)) return 1;
            printf("%s,%d,%.4f,%d,%.2f", study[pass], o.n, r.L, o.realizations, secs);
            for (int i = 0; i < NG; i++)
                printf(",%.6f,%.6f,%.6f", r.sigma[i], r.sigma_err[i], r.sigma[i] - th[i].value);
            printf("\n");
            fflush(stdout);
            ljgap_sim_result_free(&r);
        }
    }
    return 0;
}

int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    ljgap_sim_opts o;
    ljgap_sim_opts_default(&o);
    int conv = 0, header = 1;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--convergence"))
            conv = 1;
        else if (!strcmp(argv[i], "--no-header"))
            header = 0;
        else if (!strcmp(argv[i], "--no-match"))
            o.match_m0 = 0;
        else if (!strcmp(argv[i], "--n") && i + 1 < argc)
            o.n = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--realizations") && i + 1 < argc)
            o.realizations = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--L") && i + 1 < argc)
            o.L = atof(argv[++i]);
        else {
            fprintf(stderr, "usage: fig6 [--n N] [--realizations R] [--L L] [--no-match] "
                            "[--no-header] | "
                            "--convergence\n");
            return 2;
        }
    }
    return conv ? convergence() : table(&o, header);
}
