/* hybrid.c -- the hybrid model against the fully resolved discrete model, and the discrete
 * model's speed.
 *
 *   hybrid --validation [--curves FILE]  max |hybrid - full| over the mean gap, with its error
 *                        bar, for the Fig. 6 spectrum (D = 2.2, k1 = 1, k2 = 8) at m0 = 0.1,
 *                        0.218, 0.3 and k_split = 2, 3, 4, in three settings: L = 2π with the
 *                        grids 128 (full) and 32 (hybrid), with and without match_m0,
 *                        and L = 8π (full 256, hybrid 64: both converged in n); the theory's own
 *                        distance from the full model; the run times and their ratio. FILE gets
 *                        the curves (full, hybrid, theory at each gap) for the plot.
 *   hybrid --fine-alone  the band (3, 8] of that spectrum alone: full model (n = 128, L = 2π)
 *                        against the theory at each gap
 *   hybrid --speed       the hybrid at k_split = k2/4 against the full model at the same
 *                        resolution of its band (n/4 points: the same points per shortest
 *                        wave), m0 = 0.218, one thread each: median wall times and their ratio.
 *   hybrid --fftw        FFTW_ESTIMATE against FFTW_MEASURE at n = 256 and 512: planning time and
 *                        the median time of an r2c + c2r pair
 *   hybrid --discrete    seconds per mean gap of the plain model at n = 256 (L = 8π) and 512
 *                        (L = 16π), and at L = 2π, four realizations on 1 and 2 threads.
 *
 * The error bar of a difference is the standard error of the paired differences over
 * realizations (the hybrid's coarse surfaces are the full model's without their fine waves:
 * common seeds) plus both models' systematic error (error.sigma less its standard error).
 * Figures, not assertions; timings are medians (bench.h) on a shared machine.
 */
#include "bench.h"
#include "core.h" /* ljgap__now */
#include "ljgap_sim.h"

#include <fftw3.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define NG 15
static const double gaps[NG] = {0.9, 1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6,
                                1.7, 1.8, 2.0, 2.2, 2.5, 2.8, 3.2};
static const double m0s[3] = {0.1, 0.218, 0.3}, splits[3] = {2, 3, 4};

static ljgap_psd fig6(double m0)
{
    ljgap_psd p;
    ljgap_psd_power(&p, 2.2, 1.0, 8.0, LJGAP_LEVEL_M0, m0);
    return p;
}

/* One run: a job for bench_median_ms. */
typedef struct {
    ljgap_psd p;
    ljgap_sim_opts o;
    const double *g;
    size_t n;
    ljgap_sim_result r;
    int have;
} job;

static int job_run(void *ctx, int i)
{
    job *j = ctx;
    ljgap_warnings w = {0};
    if (j->have) ljgap_sim_result_free(&j->r);
    int st = ljgap_sim_run(&j->p, &j->o, j->g, j->n, &j->r, &w);
    j->have = st == LJGAP_OK;
    for (int k = 0; st && k < w.n; k++)
        fprintf(stderr, "sim: %s\n", w.msg[k]);
    return st;
}

static double timed(job *j, int repeat)
{
    double ms;
    int reps;
    if (!repeat) {
        double t = ljgap__now();
        if (job_run(j, 0)) return NAN;
        return 1e3 * (ljgap__now() - t);
    }
    return bench_median_ms(job_run, NULL, j, &ms, &reps) ? NAN : ms;
}

static double syst(const ljgap_sim_result *r, size_t i)
{
    return r->sigma_err[i] - r->sigma_std[i] / sqrt((double)r->realizations);
}

static int validation(FILE *curves)
{
    static const struct {
        const char *name;
        double L;
        int nf, nh, match, R;
    } set[] = {{"L=2pi", 2 * M_PI, 128, 32, 1, 8},
               {"L=2pi-raw", 2 * M_PI, 128, 32, 0, 8},
               {"L=8pi", 8 * M_PI, 256, 64, 1, 4}};
    printf("setting,m0,k_split,n_full,n_hyb,R,max_diff,max_diff_err,at_g,theory_diff,"
           "theory_at_g,removed,t_full_s,t_hyb_s,ratio\n");
    if (curves) fprintf(curves, "setting,m0,k_split,g,full,full_err,hybrid,hybrid_err,theory\n");
    for (size_t s = 0; s < sizeof set / sizeof set[0]; s++)
        for (int m = 0; m < 3; m++) {
            job f = {fig6(m0s[m]), {0}, gaps, NG, {0}, 0};
            ljgap_sim_opts_default(&f.o);
            f.o.n = set[s].nf, f.o.L = set[s].L, f.o.match_m0 = set[s].match;
            f.o.realizations = set[s].R, f.o.threads = 1, f.o.max_seconds = 3600;
            double tf = timed(&f, 0);
            ljgap_est th[NG];
            ljgap_opts to;
            ljgap_opts_default(&to);
            ljgap_warnings w = {0};
            if (!isfinite(tf) || ljgap_traction(&f.p, &to, gaps, NG, th, NULL, &w)) return 1;
            double dt = 0.0, gt = 0.0;
            for (int i = 0; i < NG; i++)
                if (fabs(th[i].value - f.r.sigma[i]) > dt)
                    dt = fabs(th[i].value - f.r.sigma[i]), gt = gaps[i];
            for (int k = 0; k < 3; k++) {
                job h = f;
                h.have = 0;
                h.o.n = set[s].nh, h.o.k_split = splits[k];
                double th_ms = timed(&h, 0);
                if (!isfinite(th_ms)) return 1;
                double dmax = -1, derr = 0, gat = 0;
                const int R = set[s].R;
                for (int i = 0; i < NG; i++) {
                    double md = 0, v = 0;
                    for (int r = 0; r < R; r++)
                        md += (h.r.sigma_each[r * NG + i] - f.r.sigma_each[r * NG + i]) / R;
                    for (int r = 0; r < R; r++)
                        v += pow(h.r.sigma_each[r * NG + i] - f.r.sigma_each[r * NG + i] - md, 2);
                    double e = sqrt(v / (R - 1) / R) + syst(&h.r, i) + syst(&f.r, i);
                    if (fabs(md) > dmax) dmax = fabs(md), derr = e, gat = gaps[i];
                    if (curves)
                        fprintf(curves, "%s,%g,%g,%g,%.6f,%.2g,%.6f,%.2g,%.6f\n", set[s].name,
                                m0s[m], splits[k], gaps[i], f.r.sigma[i], f.r.sigma_err[i],
                                h.r.sigma[i], h.r.sigma_err[i], th[i].value);
                }
                printf("%s,%g,%g,%d,%d,%d,%.4f,%.4f,%g,%.4f,%g,%.2f,%.3f,%.3f,%.1f\n", set[s].name,
                       m0s[m], splits[k], set[s].nf, set[s].nh, R, dmax, derr, gat, dt, gt,
                       1 - dmax / dt, tf / 1e3, th_ms / 1e3, tf / th_ms);
                fflush(stdout);
                ljgap_sim_result_free(&h.r);
            }
            ljgap_sim_result_free(&f.r);
        }
    return 0;
}

/* The fine band alone: the full model of the Fig. 6 spectrum's band (3, 8] (its C, so m0 =
 * 0.0142 of m0 = 0.1) against the theory of that band. */
static int fine_alone(void)
{
    job f = {fig6(0.1), {0}, gaps, NG, {0}, 0};
    ljgap_psd_power(&f.p, 2.2, 3.0, 8.0, LJGAP_LEVEL_C, f.p.C);
    ljgap_sim_opts_default(&f.o);
    f.o.n = 128, f.o.L = 2 * M_PI, f.o.threads = 2;
    ljgap_est th[NG];
    ljgap_opts to;
    ljgap_opts_default(&to);
    ljgap_warnings w = {0};
    if (!isfinite(timed(&f, 0)) || ljgap_traction(&f.p, &to, gaps, NG, th, NULL, &w)) return 1;
    printf("band,m0,n,L,R,g,full,full_err,theory,diff\n");
    for (int i = 0; i < NG; i++)
        printf("(3,8],%.6g,%d,%.4f,%d,%g,%.6f,%.2g,%.6f,%+.4f\n", f.p.m0, f.o.n, f.r.L,
               f.o.realizations, gaps[i], f.r.sigma[i], f.r.sigma_err[i], th[i].value,
               f.r.sigma[i] - th[i].value);
    ljgap_sim_result_free(&f.r);
    return 0;
}

static int speed(void)
{
    printf("setting,m0,k_split,n_full,n_hyb,R,gaps,t_full_ms,t_hyb_ms,ratio (medians, 1 "
           "thread each)\n");
    static const struct {
        const char *name;
        double L;
        int nf;
    } set[] = {{"L=8pi", 8 * M_PI, 256}, {"L=2pi", 2 * M_PI, 128}};
    for (int s = 0; s < 2; s++) {
        job f = {fig6(0.218), {0}, gaps, NG, {0}, 0};
        ljgap_sim_opts_default(&f.o);
        f.o.n = set[s].nf, f.o.L = set[s].L, f.o.threads = 1, f.o.max_seconds = 3600;
        job h = f;
        h.o.n = set[s].nf / 4, h.o.k_split = 8.0 / 4;
        double tf = timed(&f, 1), th = timed(&h, 1);
        printf("%s,0.218,2,%d,%d,%d,%d,%.1f,%.1f,%.1f\n", set[s].name, f.o.n, h.o.n,
               f.o.realizations, NG, tf, th, tf / th);
        fflush(stdout);
        if (f.have) ljgap_sim_result_free(&f.r);
        if (h.have) ljgap_sim_result_free(&h.r);
    }
    return 0;
}

static int discrete(void)
{
    static const double g[11] = {3.0, 2.8, 2.6, 2.4, 2.2, 2.0, 1.8, 1.6, 1.4, 1.2, 1.0};
    static const struct {
        int n;
        double L;
    } set[] = {{256, 8 * M_PI}, {512, 16 * M_PI}, {256, 2 * M_PI}, {512, 2 * M_PI}};
    printf("n,L,R,gaps,passes,threads,median_s,s_per_gap,s_per_gap_per_realization\n");
    for (int s = 0; s < 4; s++)
        for (int t = 1; t <= 2; t++) {
            job j = {fig6(0.218), {0}, g, 11, {0}, 0};
            ljgap_sim_opts_default(&j.o);
            j.o.n = set[s].n, j.o.L = set[s].L, j.o.threads = t, j.o.max_seconds = 3600;
            double ms = timed(&j, 1);
            /* the outward sweep doubles the solves when 2π/L <= k0 */
            int passes = 2 * M_PI / set[s].L > ljgap_k0() ? 1 : 2;
            printf("%d,%.4f,%d,11,%d,%d,%.2f,%.3f,%.3f\n", set[s].n, set[s].L, j.o.realizations,
                   passes, t, ms / 1e3, ms / 1e3 / 11, ms / 1e3 / 11 / j.o.realizations);
            fflush(stdout);
            if (j.have) ljgap_sim_result_free(&j.r);
        }
    return 0;
}

/* FFTW's planner flags at the model's sizes: planning time, and the median time of one r2c + c2r
 * pair (what the model does three times per conjugate-gradient iteration) over 7 runs of 50. */
static int fftw_flags(void)
{
    printf("n,flag,plan_s,pair_ms_median\n");
    for (int n = 256; n <= 512; n *= 2) {
        double *a = fftw_alloc_real((size_t)n * n);
        fftw_complex *c = fftw_alloc_complex((size_t)n * (n / 2 + 1));
        if (!a || !c) return 1;
        static const unsigned flags[2] = {FFTW_ESTIMATE, FFTW_MEASURE};
        static const char *names[2] = {"estimate", "measure"};
        for (int f = 0; f < 2; f++) {
            double t0 = ljgap__now();
            fftw_plan p = fftw_plan_dft_r2c_2d(n, n, a, c, flags[f]);
            fftw_plan q = fftw_plan_dft_c2r_2d(n, n, c, a, flags[f]);
            double tp = ljgap__now() - t0, t[7];
            for (int r = 0; r < 7; r++) {
                for (size_t i = 0; i < (size_t)n * n; i++)
                    a[i] = (double)(i % 7);
                t0 = ljgap__now();
                for (int k = 0; k < 50; k++) {
                    fftw_execute(p);
                    fftw_execute(q);
                }
                t[r] = (ljgap__now() - t0) / 50 * 1e3;
            }
            printf("%d,%s,%.3f,%.3f\n", n, names[f], tp, bench_median(t, 7));
            fftw_destroy_plan(p);
            fftw_destroy_plan(q);
        }
        fftw_free(a);
        fftw_free(c);
    }
    return 0;
}

int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    if (argc >= 2 && !strcmp(argv[1], "--validation")) {
        FILE *c = NULL;
        if (argc == 4 && !strcmp(argv[2], "--curves") && !(c = fopen(argv[3], "w"))) return 2;
        int st = validation(c);
        if (c) fclose(c);
        return st;
    }
    if (argc == 2 && !strcmp(argv[1], "--speed")) return speed();
    if (argc == 2 && !strcmp(argv[1], "--fine-alone")) return fine_alone();
    if (argc == 2 && !strcmp(argv[1], "--fftw")) return fftw_flags();
    if (argc == 2 && !strcmp(argv[1], "--discrete")) return discrete();
    fprintf(stderr,
            "usage: hybrid --validation [--curves FILE] | --fine-alone | --speed | --discrete | "
            "--fftw\n");
    return 2;
}
