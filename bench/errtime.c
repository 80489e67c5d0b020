/* errtime.c -- error against run time of the three methods (figures, never assertions).
 *
 *   errtime OUT.csv     writes OUT.csv (method,setting,error,elapsed_ms; one row per setting)
 *                       and prints the reference, its Monte Carlo cross-check and the
 *                       equal-error speed ratios.
 *
 * Two quantities:
 *  - dgamma: Δγeff/Δγ of the paper's Fig. 4 case (D = 2.5, k1 = 1, k2 = ∞, C = 1/(4π): the
 *    README's "Reproducing the paper's figures"), absolute error;
 *  - pdf: the gap PDF of the Fig. 2 case (same spectrum cut at k2 = 5, g_ave = 0.98), L1 error
 *    Σ w_i |phi_i - phi_ref(g_i)| at the method's own points (l1_error).
 * Ladders (each row is one setting; elapsed_ms is the median of bench_repeats runs):
 *  - pde: one solve at resolution level L (no extrapolation, no error estimate), L = 0..7;
 *  - pde_auto: the public solver (Richardson extrapolation, lower-end search, error estimate)
 *    at a ladder of tol, what a user of the API pays;
 *  - paper: one level of the paper's iteration at Vmax (grid h = min(0.005, √Vmax/10)), no
 *    refinement, Vmax halving from 1/25 (dgamma) or 1/10 (pdf); the ladder stops at
 *    Vmax = 1/3200 (dgamma, ~17 s a run) and 1/5120 (pdf, ~13 s): each halving costs 2.8-3x;
 *  - montecarlo: the public Monte Carlo (paths at step control c and 2c, bias-corrected) at a
 *    ladder of samples, seeds 1, 2, 3; error is the root mean square over the seeds (one run
 *    is a random draw), the time the median. The PDF is a histogram of bin width
 *    0.5 N^(-1/3) (Scott's rule for a spread ~0.15).
 * Reference: the public PDE at tol 1e-10 (work cap raised), with its own error estimate,
 * cross-checked against Monte Carlo (printed). Equal-error ratios: the paper's last rung
 * against the PDE's lines, interpolated (or, flagged, extrapolated) log-log (time_at_error).
 */
#include "bench.h"
#include "core.h" /* ljgap__now */
#include "ljgap.h"
#include "paper.h"
#include "pde.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_interp.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NREP_MC 3      /* Monte Carlo seeds per setting */
#define PDE_G_LO 0.3   /* grid of the single-level solves (dgamma) */
#define PDE_G_HI 60.0  /* (the public solver's upper end for this case) */
#define PDF_GAVE 0.98  /* Fig. 2 / Fig. 3 mean gap */
#define PDF_K2 5.0     /* Fig. 2 cut-off */
#define PDF_G_LO 0.5   /* grid of the single-level PDF solves */
#define PDF_G_HI 8.0   /* (the PDF vanishes beyond ~4) */
#define MC_BIN_C 0.5   /* histogram bin width c N^(-1/3) */
#define MC_HIST_LO 0.5 /* histogram range */
#define MC_HIST_HI 4.5
#define MAX_ROWS 80

typedef enum { Q_DGAMMA = 0, Q_PDF = 1 } quantity;

/* One setting of one method: what to run and what it gave. */
typedef struct {
    const char *method; /* pde, pde_auto, paper, montecarlo */
    quantity q;         /* what is measured */
    double x;           /* level, tol, Vmax or samples */
    double err[7];      /* error of each repeat */
    double est[7];      /* the method's own error estimate (0: none) */
    double value[7];    /* dgamma, or the PDF's sigma */
    double vest[7];     /* the estimate of value */
    ljgap_summary sum;  /* last dgamma result */
    ljgap_pdf pdf;      /* last PDF result (released after scoring) */
} job;

/* The row written to the CSV and used for the ratios. */
typedef struct {
    char method[16];
    char setting[48];
    double error, ms, est; /* error, median time, mean own estimate of the error */
    double value, vest;    /* mean value (dgamma or the PDF's sigma) and its mean estimate */
    int reps;
} row;

static const ljgap_psd *psd_fig4, *psd_fig2;
static double ref_dgamma, ref_dgamma_err;
static ljgap_pdf ref_pdf; /* reference density at its nodes */
static row rows[MAX_ROWS];
static int nrows;

static void die(const char *what, int st)
{
    fprintf(stderr, "errtime: %s: %s\n", what, ljgap_strerror(st));
    exit(1);
}

/* ---- the L1 distance of a density from the reference ---- */

/* The reference density between its nodes: a cubic spline (interpolation error ~h^4, far
 * below the errors measured; a linear one would add h^2 phi''/8 ~ 1e-5 at the peak). 0
 * outside its support. */
static gsl_interp *ref_spline;
static gsl_interp_accel *ref_acc;

static double ref_at(double g)
{
    const ljgap_pdf *r = &ref_pdf;
    if (g < r->g[0] || g > r->g[r->n - 1]) return 0.0;
    return gsl_interp_eval(ref_spline, r->g, r->phi, g, ref_acc);
}

/* Σ w_i |phi_i - phi_ref(g_i)| over the method's own points g_i, w_i their trapezoid weights
 * (a histogram's bin width): the discrete L1 error in the sense of the methods' own
 * estimates, which compare densities at points too. Between points the answer is whatever
 * the caller interpolates; that is not charged to the method. */
static double l1_error(const ljgap_pdf *p)
{
    double s = 0.0;
    for (size_t i = 0; i < p->n; i++) {
        double gl = i > 0 ? p->g[i - 1] : p->g[i], gr = i + 1 < p->n ? p->g[i + 1] : p->g[i];
        s += 0.5 * (gr - gl) * fabs(p->phi[i] - ref_at(p->g[i]));
    }
    return s;
}

/* ---- the runs ---- */

static int run_job(void *ctx, int i)
{
    job *J = ctx;
    ljgap_opts o;
    ljgap_opts_default(&o);
    ljgap_warnings w = {0};
    int pde = strcmp(J->method, "pde") == 0, paper = strcmp(J->method, "paper") == 0;
    int mc = strcmp(J->method, "montecarlo") == 0;
    o.max_seconds = 300; /* the paper's finest levels take ~30 s on a loaded machine */
    if (mc) {
        o.method = LJGAP_METHOD_MC;
        o.samples = (long)J->x;
        o.seed = (unsigned long)i + 1;
        o.max_work = 40000000000L;
    } else if (!pde && !paper) {
        o.tol = J->x;
    }
    if (J->q == Q_DGAMMA) {
        if (pde)
            return ljgap__pde_summary_at_level(psd_fig4, PDE_G_LO, PDE_G_HI, (int)J->x, &J->sum);
        if (paper) return ljgap__paper_summary_at(psd_fig4, &o, J->x, &J->sum);
        return ljgap_traction(psd_fig4, &o, NULL, 0, NULL, &J->sum, &w);
    }
    double k2 = PDF_K2;
    if (pde)
        return ljgap__pde_pdf_at_level(psd_fig2, PDF_GAVE, k2, PDF_G_LO, PDF_G_HI, (int)J->x,
                                      &J->pdf);
    if (paper) return ljgap__paper_pdf_at(psd_fig2, &o, J->x, PDF_GAVE, k2, NULL, &J->pdf);
    if (mc) {
        double bin = MC_BIN_C * pow(J->x, -1.0 / 3.0);
        double grid[3] = {MC_HIST_LO, MC_HIST_HI, floor((MC_HIST_HI - MC_HIST_LO) / bin) + 1};
        return ljgap_pdf_compute(psd_fig2, &o, PDF_GAVE, &k2, 1, grid, &J->pdf, &w);
    }
    return ljgap_pdf_compute(psd_fig2, &o, PDF_GAVE, &k2, 1, NULL, &J->pdf, &w);
}

static int score_job(void *ctx, int i)
{
    job *J = ctx;
    if (J->q == Q_DGAMMA) {
        J->value[i] = J->sum.dgamma_eff.value;
        J->vest[i] = J->est[i] = J->sum.dgamma_eff.err;
        J->err[i] = fabs(J->sum.dgamma_eff.value - ref_dgamma);
    } else {
        J->value[i] = J->pdf.sigma.value;
        J->vest[i] = J->pdf.sigma.err;
        J->est[i] = J->pdf.phi_err;
        J->err[i] = l1_error(&J->pdf);
        ljgap_pdf_release(&J->pdf, 1);
    }
    return isfinite(J->err[i]) ? LJGAP_OK : LJGAP_EFAIL;
}

/* Runs one setting (Monte Carlo: NREP_MC seeds) and appends its row. */
static row *measure(const char *method, quantity q, double x, const char *setting)
{
    job J;
    memset(&J, 0, sizeof J);
    J.method = method;
    J.q = q;
    J.x = x;
    double ms = 0;
    int reps = 0, st;
    if (strcmp(method, "montecarlo") == 0) {
        double t[NREP_MC];
        reps = NREP_MC;
        st = LJGAP_OK;
        for (int i = 0; i < NREP_MC && !st; i++) {
            double t0 = ljgap__now();
            st = run_job(&J, i);
            t[i] = 1e3 * (ljgap__now() - t0);
            if (!st) st = score_job(&J, i);
        }
        ms = bench_median(t, NREP_MC);
    } else {
        st = bench_median_ms(run_job, score_job, &J, &ms, &reps);
    }
    if (st) die(setting, st);
    if (nrows == MAX_ROWS) die("too many rows", LJGAP_EFAIL);
    row *r = &rows[nrows++];
    snprintf(r->method, sizeof r->method, "%s", method);
    snprintf(r->setting, sizeof r->setting, "%s", setting);
    double e2 = 0, es = 0, v = 0, ve = 0;
    for (int i = 0; i < reps; i++) {
        e2 += J.err[i] * J.err[i], es += J.est[i];
        v += J.value[i], ve += J.vest[i];
    }
    r->value = v / reps;
    r->vest = ve / reps;
    /* deterministic methods give the same error every repeat; Monte Carlo: RMS over seeds */
    r->error = sqrt(e2 / reps);
    r->est = es / reps;
    r->ms = ms;
    r->reps = reps;
    printf("  %-10s %-24s error %.3e  est %.2e  %10.2f ms  (median of %d)\n", method, setting,
           r->error, r->est, ms, reps);
    fflush(stdout);
    return r;
}

/* One ladder: the setting x[i] (1/x[i] when inv) named by fmt; returns the last row. */
static const row *ladder(const char *method, quantity q, const char *fmt, const double *x, int n,
                         int inv)
{
    const row *r = NULL;
    char s[48];
    for (int i = 0; i < n; i++) {
        snprintf(s, sizeof s, fmt, x[i]);
        r = measure(method, q, inv ? 1.0 / x[i] : x[i], s);
    }
    return r;
}

/* ---- equal-error ratios ---- */

/* Time at error e on the method's line through its rows (log-log, piecewise linear between
 * the rows that bracket e; outside, the power law of the two nearest rows). *extrap is set
 * when e is outside the line's range. Rows of one method must be in ladder order. */
static double time_at_error(const char *method, const char *prefix, double e, int *extrap)
{
    int idx[MAX_ROWS], n = 0;
    for (int i = 0; i < nrows; i++)
        if (strcmp(rows[i].method, method) == 0 &&
            strncmp(rows[i].setting, prefix, strlen(prefix)) == 0)
            idx[n++] = i;
    if (n < 2) return NAN;
    /* sort by error, descending */
    for (int a = 1; a < n; a++)
        for (int b = a; b > 0 && rows[idx[b]].error > rows[idx[b - 1]].error; b--) {
            int t = idx[b];
            idx[b] = idx[b - 1];
            idx[b - 1] = t;
        }
    int j = 0;
    while (j + 2 < n && rows[idx[j + 1]].error > e)
        j++;
    const row *A = &rows[idx[j]], *B = &rows[idx[j + 1]];
    *extrap = e > rows[idx[0]].error || e < rows[idx[n - 1]].error;
    double s = log(B->ms / A->ms) / log(B->error / A->error);
    return A->ms * exp(s * log(e / A->error));
}

static const row *find_row(const char *method, const char *setting)
{
    for (int i = 0; i < nrows; i++)
        if (strcmp(rows[i].method, method) == 0 && strcmp(rows[i].setting, setting) == 0)
            return &rows[i];
    return NULL;
}

/* The paper's finest row against the PDE lines at equal error, both ways round. */
static void ratios(const char *what, const char *prefix, const char *paper_last,
                   const char *auto_default)
{
    const row *P = find_row("paper", paper_last), *A = find_row("pde_auto", auto_default);
    if (!P || !A) die("ratio rows missing", LJGAP_EFAIL);
    int x1 = 0, x2 = 0;
    double tl = time_at_error("pde", prefix, P->error, &x1);
    double tp = time_at_error("paper", prefix, A->error, &x2);
    printf("%s: paper at %s: error %.2e in %.0f ms\n", what, paper_last, P->error, P->ms);
    printf("  pde single level at that error (log-log %s of the level line): %.2f ms -> "
           "ratio %.0f\n",
           x1 ? "extrapolation" : "interpolation", tl, P->ms / tl);
    printf("  pde_auto %s: error %.2e in %.2f ms (more accurate) -> ratio %.0f\n", auto_default,
           A->error, A->ms, P->ms / A->ms);
    printf("  paper at the pde_auto error %.2e (log-log %s of the paper's last two rows): "
           "%.3g ms -> ratio %.3g\n",
           A->error, x2 ? "extrapolation" : "interpolation", tp, tp / A->ms);
}

/* ---- the reference and its cross-check ---- */

static void reference(void)
{
    ljgap_opts o;
    ljgap_opts_default(&o);
    o.tol = 1e-10;
    o.max_work = 4000000000L;
    o.max_seconds = 120;
    ljgap_warnings w = {0};
    ljgap_summary s;
    double t = ljgap__now();
    int st = ljgap_traction(psd_fig4, &o, NULL, 0, NULL, &s, &w);
    if (st) die("reference dgamma", st);
    ref_dgamma = s.dgamma_eff.value;
    ref_dgamma_err = s.dgamma_eff.err;
    printf("reference dgamma_eff (pde, tol 1e-10): %.12f ± %.1e (%.1f s)%s%s\n", ref_dgamma,
           ref_dgamma_err, ljgap__now() - t, w.n ? "; warning: " : "", w.n ? w.msg[0] : "");

    /* cross-check: the traction at three gaps by Monte Carlo against the reference solver */
    double g[3] = {s.g_eq.value, s.g_at_max.value, 4.0};
    ljgap_est pde[3], mc[3];
    w.n = 0;
    if ((st = ljgap_traction(psd_fig4, &o, g, 3, pde, NULL, &w))) die("reference traction", st);
    ljgap_opts m;
    ljgap_opts_default(&m);
    m.method = LJGAP_METHOD_MC;
    m.samples = 40000;
    m.seed = 11;
    m.max_seconds = 120;
    m.max_work = 40000000000L;
    if ((st = ljgap_traction(psd_fig4, &m, g, 3, mc, NULL, &w))) die("cross-check traction", st);
    printf("cross-check, traction by Monte Carlo (40000 paths, bias-corrected):\n");
    for (int i = 0; i < 3; i++)
        printf("  sigma_bar(%.4f): pde %.9f ± %.1e, montecarlo %.6f ± %.1e: difference %.1e = "
               "%.2f x the Monte Carlo estimate\n",
               g[i], pde[i].value, pde[i].err, mc[i].value, mc[i].err,
               fabs(mc[i].value - pde[i].value), fabs(mc[i].value - pde[i].value) / mc[i].err);

    double k2 = PDF_K2;
    w.n = 0;
    t = ljgap__now();
    if ((st = ljgap_pdf_compute(psd_fig2, &o, PDF_GAVE, &k2, 1, NULL, &ref_pdf, &w)))
        die("reference pdf", st);
    ref_spline = gsl_interp_alloc(gsl_interp_cspline, ref_pdf.n);
    ref_acc = gsl_interp_accel_alloc();
    if (!ref_spline || !ref_acc) die("reference spline", LJGAP_ENOMEM);
    if (gsl_interp_init(ref_spline, ref_pdf.g, ref_pdf.phi, ref_pdf.n))
        die("reference spline", LJGAP_EFAIL);
    printf("reference pdf (pde, tol 1e-10): %zu nodes on [%.3f, %.3f], L1 error estimate %.1e, "
           "sigma %.10f ± %.1e (%.1f s)%s%s\n",
           ref_pdf.n, ref_pdf.g[0], ref_pdf.g[ref_pdf.n - 1], ref_pdf.phi_err, ref_pdf.sigma.value,
           ref_pdf.sigma.err, ljgap__now() - t, w.n ? "; warning: " : "", w.n ? w.msg[0] : "");
}

/* Monte Carlo against the references, from the largest ladder setting: the mean over the
 * seeds of the value (dgamma or the PDF's sigma) against the reference, in units of the
 * Monte Carlo estimate of the mean (est/√seeds), and the error against the own estimate. */
static void mc_check(const char *what, const row *r, double ref, double ref_err)
{
    double se = r->vest / sqrt(r->reps), d = fabs(r->value - ref);
    printf("cross-check, %s by Monte Carlo at %s, mean of %d seeds: %.6f ± %.1e against the "
           "reference %.9f ± %.1e: difference %.1e = %.2f x the Monte Carlo estimate%s\n",
           what, r->setting, r->reps, r->value, se, ref, ref_err, d, d / se,
           d > 3 * se ? " (OUTSIDE 3x: Monte Carlo bias, see below)" : "");
    printf("  error %.2e (RMS over seeds) against the own estimate %.2e: ratio %.2f\n", r->error,
           r->est, r->error / r->est);
}

int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    if (argc != 2) {
        fprintf(stderr, "usage: errtime OUT.csv\n");
        return 2;
    }
    ljgap_psd p4, p2;
    ljgap_psd_power(&p4, 2.5, 1.0, INFINITY, LJGAP_LEVEL_C, 1.0 / (4.0 * M_PI));
    ljgap_psd_power(&p2, 2.5, 1.0, PDF_K2, LJGAP_LEVEL_C, 1.0 / (4.0 * M_PI));
    psd_fig4 = &p4;
    psd_fig2 = &p2;
    reference();
    /* the ladders: settings as printed (Vmax as 1/x) */
    static const double lev7[] = {0, 1, 2, 3, 4, 5, 6, 7};
    static const double dtol[] = {1e-6, 1e-7, 1e-8, 1e-9}, ptol[] = {1e-4, 1e-5, 1e-6};
    static const double dvm[] = {25, 50, 100, 200, 400, 800, 1600, 3200};
    static const double pvm[] = {10, 20, 40, 80, 160, 320, 640, 1280, 2560, 5120};
    static const double dN[] = {250, 500, 1000, 2000, 4000};
    static const double pN[] = {1000, 4000, 16000, 64000, 256000};
#define LADDER(m, q, fmt, x, inv) ladder(m, q, fmt, x, (int)(sizeof x / sizeof x[0]), inv)
    printf("dgamma_eff of Fig. 4 (absolute error):\n");
    LADDER("pde", Q_DGAMMA, "dgamma:level=%.0f", lev7, 0);
    LADDER("pde_auto", Q_DGAMMA, "dgamma:tol=%.0e", dtol, 0);
    LADDER("paper", Q_DGAMMA, "dgamma:vmax=1/%.0f", dvm, 1);
    const row *mcd = LADDER("montecarlo", Q_DGAMMA, "dgamma:samples=%.0f", dN, 0);
    printf("pdf of Fig. 2 at g_ave = 0.98, k2 = 5 (L1 error):\n");
    LADDER("pde", Q_PDF, "pdf:level=%.0f", lev7, 0);
    LADDER("pde_auto", Q_PDF, "pdf:tol=%.0e", ptol, 0);
    LADDER("paper", Q_PDF, "pdf:vmax=1/%.0f", pvm, 1);
    const row *mcp = LADDER("montecarlo", Q_PDF, "pdf:samples=%.0f", pN, 0);

    mc_check("dgamma_eff", mcd, ref_dgamma, ref_dgamma_err);
    mc_check("pdf sigma (L1 below)", mcp, ref_pdf.sigma.value, ref_pdf.sigma.err);
    ratios("dgamma_eff", "dgamma:", "dgamma:vmax=1/3200", "dgamma:tol=1e-06");
    ratios("pdf", "pdf:", "pdf:vmax=1/5120", "pdf:tol=1e-06");

    FILE *f = fopen(argv[1], "w");
    if (!f) {
        perror(argv[1]);
        return 1;
    }
    fprintf(f, "method,setting,error,elapsed_ms\n");
    for (int i = 0; i < nrows; i++)
        fprintf(f, "%s,%s,%.4e,%.3f\n", rows[i].method, rows[i].setting, rows[i].error, rows[i].ms);
    fclose(f);
    gsl_interp_free(ref_spline);
    gsl_interp_accel_free(ref_acc);
    ljgap_pdf_release(&ref_pdf, 1);
    return 0;
}
