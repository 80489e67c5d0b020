/* stability.c -- stiff and extreme inputs: result, error estimate, actual error, time.
 *
 *   stability OUT.csv   writes OUT.csv (one row per case and quantity) and prints the
 *                       honesty summary: actual / estimated error over all rows.
 *
 * Each case runs the default solver (PDE, tol 1e-6; time = median of bench_repeats runs) and
 * a finer run of the same solver (tol 1e-8, work cap x10, 60 s) whose value is taken as the
 * truth: actual = |value - value_fine|. The finer run's own estimate is in ref_err; a row is
 * "decisive" when ref_err is at most 0.3 of the estimate being judged (otherwise the finer run
 * cannot tell whether the estimate holds and the row is left out of the ratio statistics, and
 * says so). The finer run shares the method with the default one, so a bias common to both
 * (the same model of the wall region, say) is not seen here; bench/errtime.c checks the
 * method against Monte Carlo and the paper's iteration on the Fig. 4 and Fig. 2 cases.
 *
 * Cases (power laws (6); the rest as Fig. 4: D = 2.5, k1 = 1, k2 = ∞, m0 = 0.5):
 *   k1 from just above k0 = 0.469779 to 0.6; D from 2.01 to 2.99; m0 from 1e-6 to 100; k2
 *   right above k1, moderate (5 and 8: the figures' spectra) and very large (up to
 *   LJGAP_K_MAX); the traction at g_ave deep in compression (down to LJGAP_G_MIN) and far
 *   out (up to LJGAP_G_MAX).
 * Then a sweep of 108 spectra, every combination of D 2.2/2.5/2.8, k1 0.5/1/3, k2/k1
 * 2/8/50/∞ and m0 0.1/0.5/2 (the adhesion summary): ordinary inputs, where a term that the
 * extrapolation does not remove would show.
 */
#include "bench.h"
#include "core.h" /* ljgap__now */
#include "ljgap.h"

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define TOL_FINE 1e-8
#define NQ 4         /* quantities of the summary */
#define DECISIVE 0.3 /* the finer run judges an estimate when its own is below this share */

typedef struct {
    const char *name;        /* what is stressed */
    double D, k1, k2, m0, g; /* g: NAN for the adhesion summary, else the traction at g */
} stab_case;

static const stab_case cases[] = {
    {"fig4", 2.5, 1, INFINITY, 0.5, NAN},
    {"k1_near_k0", 2.5, 0.4698, INFINITY, 0.5, NAN},
    {"k1", 2.5, 0.47, INFINITY, 0.5, NAN},
    {"k1", 2.5, 0.48, INFINITY, 0.5, NAN},
    {"k1", 2.5, 0.5, INFINITY, 0.5, NAN},
    {"k1", 2.5, 0.55, INFINITY, 0.5, NAN},
    {"k1", 2.5, 0.6, INFINITY, 0.5, NAN},
    {"D", 2.01, 1, INFINITY, 0.5, NAN},
    {"D", 2.05, 1, INFINITY, 0.5, NAN},
    {"D", 2.95, 1, INFINITY, 0.5, NAN},
    {"D", 2.99, 1, INFINITY, 0.5, NAN},
    {"D_k2", 2.99, 1, 100, 0.5, NAN},
    {"m0", 2.5, 1, INFINITY, 1e-6, NAN},
    {"m0", 2.5, 1, INFINITY, 1e-4, NAN},
    {"m0", 2.5, 1, INFINITY, 1e-2, NAN},
    {"m0", 2.5, 1, INFINITY, 1, NAN},
    {"m0", 2.5, 1, INFINITY, 10, NAN},
    {"m0", 2.5, 1, INFINITY, 100, NAN},
    {"k2_near_k1", 2.5, 1, 1.000001, 0.5, NAN},
    {"k2_near_k1", 2.5, 1, 1.001, 0.5, NAN},
    {"k2_near_k1", 2.5, 1, 1.1, 0.5, NAN},
    {"k2_mid", 2.5, 1, 5, 0.4, NAN}, /* the Fig. 2 spectrum */
    {"k2_mid", 2.5, 1, 8, 0.5, NAN}, /* the handler tests' */
    {"k2_mid", 2.2, 1, 8, 0.1, NAN}, /* the Fig. 6 spectrum */
    {"k2_large", 2.5, 1, 1e6, 0.5, NAN},
    {"k2_large", 2.5, 1, 1e10, 0.5, NAN},
    {"k2_large", 2.5, 1, 1e15, 0.5, NAN},
    {"g_compression", 2.5, 1, INFINITY, 0.5, 1e-3},
    {"g_compression", 2.5, 1, INFINITY, 0.5, 1e-2},
    {"g_compression", 2.5, 1, INFINITY, 0.5, 0.1},
    {"g_compression", 2.5, 1, INFINITY, 0.5, 0.5},
    {"g_far", 2.5, 1, INFINITY, 0.5, 20},
    {"g_far", 2.5, 1, INFINITY, 0.5, 100},
    {"g_far", 2.5, 1, INFINITY, 0.5, 1e4},
    {"g_far", 2.5, 1, INFINITY, 0.5, 1e6},
};
#define NCASE (sizeof cases / sizeof cases[0])

/* The sweep: every combination of these (k2 as a multiple of k1), the adhesion summary. */
static const double sweep_D[] = {2.2, 2.5, 2.8}, sweep_k1[] = {0.5, 1, 3},
                    sweep_k2[] = {2, 8, 50, INFINITY}, sweep_m0[] = {0.1, 0.5, 2};
#define NSWEEP 108 /* 3 x 3 x 4 x 3 */

/* Case c of the list, then of the sweep. */
static stab_case case_at(size_t c)
{
    if (c < NCASE) return cases[c];
    c -= NCASE;
    double k1 = sweep_k1[c / 12 % 3];
    return (stab_case){"sweep", sweep_D[c / 36], k1, k1 * sweep_k2[c / 3 % 4], sweep_m0[c % 3],
                       NAN};
}

static const char *qname[NQ] = {"g_eq", "sigma_max", "g_at_max", "dgamma_eff"};

/* One computation of a case with given options. */
typedef struct {
    const stab_case *c;
    ljgap_psd psd;
    ljgap_opts o;
    ljgap_est v[NQ]; /* the summary's four, or v[0] = the traction */
    ljgap_warnings w;
} stab_run;

static int run_case(void *ctx, int i)
{
    stab_run *R = ctx;
    (void)i;
    R->w.n = 0;
    if (isnan(R->c->g)) {
        ljgap_summary s;
        int st = ljgap_traction(&R->psd, &R->o, NULL, 0, NULL, &s, &R->w);
        memcpy(R->v, &s.g_eq, sizeof R->v);
        return st;
    }
    return ljgap_traction(&R->psd, &R->o, &R->c->g, 1, R->v, NULL, &R->w);
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The warnings joined by " | ", with commas and quotes made CSV-safe. */
static void warn_text(const ljgap_warnings *w, char *buf, size_t len)
{
    buf[0] = 0;
    for (int i = 0; i < w->n; i++) {
        size_t l = strlen(buf);
        snprintf(buf + l, len - l, "%s%s", i ? " | " : "", w->msg[i]);
    }
    for (char *p = buf; *p; p++)
        if (*p == ',' || *p == '"') *p = ';';
}

int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    if (argc != 2) {
        fprintf(stderr, "usage: stability OUT.csv\n");
        return 2;
    }
    FILE *f = fopen(argv[1], "w");
    if (!f) {
        perror(argv[1]);
        return 1;
    }
    fprintf(f, "case,D,k1,k2,m0,g_ave,quantity,value,est_err,actual_err,ratio,ref_err,"
               "decisive,elapsed_ms,ref_elapsed_ms,warnings\n");
    static double ratio[(NCASE + NSWEEP) * NQ];
    int nr = 0, nrow = 0, dishonest = 0;
    static char bad[8192]; /* the rows with actual > estimate, listed at the end */
    for (size_t c = 0; c < NCASE + NSWEEP; c++) {
        const stab_case KC = case_at(c), *K = &KC;
        stab_run A, B;
        memset(&A, 0, sizeof A);
        A.c = K;
        int st = ljgap_psd_power(&A.psd, K->D, K->k1, K->k2, LJGAP_LEVEL_M0, K->m0);
        if (st) {
            fprintf(stderr, "stability: case %zu: %s\n", c, ljgap_strerror(st));
            return 1;
        }
        ljgap_opts_default(&A.o);
        B = A;
        B.o.tol = TOL_FINE;
        B.o.max_work = 10 * A.o.max_work;
        B.o.max_seconds = 60;
        double ms = 0, ms_fine = 0;
        int reps;
        st = bench_median_ms(run_case, NULL, &A, &ms, &reps);
        if (st == LJGAP_OK) { /* the finer run once */
            double t0 = ljgap__now();
            st = run_case(&B, 0);
            ms_fine = 1e3 * (ljgap__now() - t0);
        }
        int nq = isnan(K->g) ? NQ : 1;
        char wt[2 * LJGAP_MAX_WARN * LJGAP_WARN_LEN];
        warn_text(&A.w, wt, sizeof wt);
        if (st) {
            fprintf(f, "%s,%g,%g,%g,%g,%g,-,,,,,,,,,failed: %s\n", K->name, K->D, K->k1, K->k2,
                    K->m0, K->g, ljgap_strerror(st));
            printf("%-14s D=%g k1=%g k2=%g m0=%g g=%g: FAILED %s\n", K->name, K->D, K->k1, K->k2,
                   K->m0, K->g, ljgap_strerror(st));
            continue;
        }
        for (int q = 0; q < nq; q++) {
            double est = A.v[q].err, act = fabs(A.v[q].value - B.v[q].value);
            double r = est > 0 ? act / est : (act > 0 ? INFINITY : 0);
            int dec = B.v[q].err <= DECISIVE * est;
            if (dec) {
                ratio[nr++] = r;
                if (r > 1) {
                    dishonest++;
                    size_t l = strlen(bad);
                    snprintf(bad + l, sizeof bad - l,
                             "  %s D=%g k1=%g k2=%g m0=%g g=%g %s: %.10g ± %.2e, actual %.2e "
                             "(%.2fx)\n",
                             K->name, K->D, K->k1, K->k2, K->m0, K->g,
                             nq == 1 ? "sigma_bar" : qname[q], A.v[q].value, est, act, r);
                }
            }
            const char *qn = nq == 1 ? "sigma_bar" : qname[q];
            fprintf(f, "%s,%g,%g,%g,%g,%g,%s,%.12g,%.3e,%.3e,%.3g,%.3e,%d,%.2f,%.2f,%s\n", K->name,
                    K->D, K->k1, K->k2, K->m0, K->g, qn, A.v[q].value, est, act, r, B.v[q].err, dec,
                    ms, ms_fine, wt);
            printf("%-14s D=%-4g k1=%-6g k2=%-8g m0=%-6g g=%-6g %-10s %.10g ± %.1e  actual %.1e"
                   "  ratio %-8.3g%s %8.1f ms (fine %.0f ms)%s\n",
                   K->name, K->D, K->k1, K->k2, K->m0, K->g, qn, A.v[q].value, est, act, r,
                   dec ? (r > 1 ? " ACTUAL > ESTIMATE" : "") : " (finer run not decisive)", ms,
                   ms_fine, A.w.n ? " [warned]" : "");
            nrow++;
        }
        fflush(stdout);
    }
    fclose(f);
    qsort(ratio, (size_t)nr, sizeof *ratio, cmp_d);
    int le1 = 0;
    for (int i = 0; i < nr; i++)
        le1 += ratio[i] <= 1.0;
    if (nr > 0)
        printf("honesty: actual/estimated error over %d decisive rows (of %d): median %.3g, max "
               "%.3g, fraction <= 1: %.3f (%d rows with actual > estimate)\n",
               nr, nrow, bench_median(ratio, nr), ratio[nr - 1], (double)le1 / nr, dishonest);
    if (dishonest) printf("rows with actual error above the estimate:\n%s", bad);
    return 0;
}
