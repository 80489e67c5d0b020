/* ljgap.h -- public interface of the numerical core.
 *
 * The core computes, for a rough surface given by its power spectral density (PSD), the
 * statistics of the local gap when the surfaces interact through the integrated
 * Lennard-Jones law: the Persson-type theory of the gap PDF with the Lennard-Jones law
 * (equation numbers (N) are the paper's; docs/theory.md restates the model and its numerics).
 * Everything here is dimensionless (docs/theory.md §1): gaps in units of epsilon, wavenumbers
 * in units of 1/chi, tractions in units of sigma0, energies in units of the flat-surface work
 * of separation.
 *
 * The core knows nothing of HTTP or JSON. Every function returns an int status
 * (LJGAP_OK or an LJGAP_E* code) and writes results through out-pointers; every computed
 * quantity comes with an estimated absolute error (ljgap_est). Callers own memory.
 *
 * As a library (make install; pkg-config --cflags --libs ljgap): call ljgap_init() once at
 * start-up, then for example
 *   ljgap_psd psd; ljgap_opts o; ljgap_summary s; ljgap_warnings w = {0};
 *   ljgap_psd_power(&psd, 2.5, 1, INFINITY, LJGAP_LEVEL_M0, 0.5);
 *   ljgap_opts_default(&o);
 *   if (ljgap_traction(&psd, &o, NULL, 0, NULL, &s, &w) == LJGAP_OK)
 *       printf("%g ± %g\n", s.dgamma_eff.value, s.dgamma_eff.err);
 */
#ifndef LJGAP_H
#define LJGAP_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define LJGAP_VERSION "0.1.0"

/* ---- status codes (one table, see ljgap_strerror) ---- */
enum {
    LJGAP_OK = 0,
    LJGAP_EINVAL = 1,  /* input outside the model's domain */
    LJGAP_ENOMEM = 2,  /* allocation failed */
    LJGAP_ECAP = 3,    /* request needs more work than the caps allow */
    LJGAP_EFAIL = 4,   /* numerical failure (no finite answer could be formed) */
    LJGAP_ECANCEL = 5, /* cancelled by the caller */
};
const char *ljgap_strerror(int status);

/* Once at start-up, before any thread calls the core: turns off GSL's error handler, whose
 * default aborts the process on conditions the core detects and reports as a status itself. */
void ljgap_init(void);

/* ---- warnings attached to a result ---- */
#define LJGAP_MAX_WARN 8
#define LJGAP_WARN_LEN 240
typedef struct {
    int n;                                    /* number of messages in msg */
    char msg[LJGAP_MAX_WARN][LJGAP_WARN_LEN]; /* human-readable, one sentence each */
} ljgap_warnings;
/* Append a printf-style message; extra messages beyond LJGAP_MAX_WARN are dropped.
 * w may be NULL. Identical messages are not repeated. */
void ljgap_warn(ljgap_warnings *w, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* A value with its estimated absolute error. */
typedef struct {
    double value; /* the result */
    double err;   /* estimated absolute error, >= 0 */
} ljgap_est;

/* ---- lj.c: the Lennard-Jones law and the gap transfer function ---- */
double ljgap_sigma(double g);       /* sigma/sigma0 of (8),(9): (3√3/2)(g^-3 - g^-9) */
double ljgap_sigma_work(double g);  /* ∫_g^∞ sigma/sigma0 dg' */
double ljgap_f(double g, double k); /* f(g,k) of (14) */
double ljgap_k0(void);              /* (324/3125)^(1/3) of (19) */
double ljgap_gstar(void);           /* (15/2)^(1/6) */
double ljgap_g_sigma_max(void);     /* 3^(1/6), where sigma/sigma0 = 1 */
double ljgap_flat_work(void);       /* 9√3/16 = ∫_1^∞ sigma/sigma0 dg */
/* E[sigma(g+X)] and E[sigma_work(g+X)], X ~ N(0,V), by the asymptotic series in V/g^2.
 * Valid (relative error < 1e-12) for V/g^2 <= 0.01, g > 0; returns NAN outside. */
double ljgap_sigma_smoothed(double g, double V);
double ljgap_sigma_work_smoothed(double g, double V);
double ljgap_dsigma_smoothed(double g, double V); /* E[sigma'(g+X)], the same range */

/* ---- psd.c: power spectral densities (dimensionless, theory.md §1) ---- */
typedef enum { LJGAP_PSD_POWER = 0, LJGAP_PSD_TABLE = 1 } ljgap_psd_kind;

typedef struct {
    ljgap_psd_kind kind; /* power law (6) or table */
    double k1;           /* lowest wavenumber with P > 0 */
    double k2;           /* highest (INFINITY when the PSD has an infinite tail) */
    double m0;           /* total variance 2π∫ k P dk of (22) */
    /* power law: P = C k^(2D-8) on [k1,k2] */
    double C, D;
    /* table: P[i] at k[i], log-log interpolation, zero outside unless has_tail */
    size_t n;     /* number of table points */
    double *k;    /* owned, increasing */
    double *P;    /* owned, > 0 */
    double *cum;  /* owned: cum[i] = variance 2π∫_{k[0]}^{k[i]} s P ds */
    double *q;    /* owned: log-log slope of segment i (n-1 entries) */
    int has_tail; /* table continues as P[n-1] (k/k[n-1])^tail_q beyond k[n-1] */
    double tail_q;
} ljgap_psd;

/* Which field sets the level of a power law. */
typedef enum { LJGAP_LEVEL_C = 0, LJGAP_LEVEL_M0 = 1, LJGAP_LEVEL_HRMS = 2 } ljgap_level;

/* Power law (6) on [k1,k2] (k2 = INFINITY allowed for D < 3), level from C, m0 or h_rms.
 * Returns LJGAP_EINVAL (psd untouched) when 2<D<3, 0<k1<k2, level>0 do not hold. */
int ljgap_psd_power(ljgap_psd *psd, double D, double k1, double k2, ljgap_level lk, double level);
/* Table of n >= 2 points (copied), optional tail exponent q < -2 (has_tail != 0). */
int ljgap_psd_table(ljgap_psd *psd, const double *k, const double *P, size_t n, int has_tail,
                    double tail_q);
void ljgap_psd_free(ljgap_psd *psd); /* frees table storage; NULL and power laws are fine */
/* Copy of psd truncated at kc (k1 < kc; kc >= k2 gives a plain copy). */
int ljgap_psd_truncate(ljgap_psd *out, const ljgap_psd *psd, double kc);
/* Copy of psd restricted to k >= kc (k1 < kc < k2): the band above kc, with the same P there. */
int ljgap_psd_above(ljgap_psd *out, const ljgap_psd *psd, double kc);
double ljgap_psd_eval(const ljgap_psd *psd, double k);            /* P(k) */
double ljgap_psd_var(const ljgap_psd *psd, double ka, double kb); /* 2π∫_ka^kb s P ds */
double ljgap_psd_cumvar(const ljgap_psd *psd, double k);          /* ljgap_psd_var(k1, k) */
/* Inverse of the cumulative variance: the k with cumvar(k) = tau, 0 <= tau < m0. */
double ljgap_psd_k_of_cumvar(const ljgap_psd *psd, double tau);
/* Packet variance V(g0,ka,kb) of (17): 2π∫ s P(s) f(g0,s)^2 ds, by Gauss-Legendre on
 * log-spaced panels (relative accuracy ~1e-12 for smooth P). */
double ljgap_packet_var(const ljgap_psd *psd, double g0, double ka, double kb);

/* ---- the range the solvers accept (LJGAP_EINVAL with a warning outside) ---- */
#define LJGAP_M0_MAX 1e4 /* height variance m0 (h_rms up to 100 epsilon) */
#define LJGAP_K_MAX 1e15 /* finite wavenumbers k1, k2 */
#define LJGAP_G_MIN 1e-3 /* mean gaps g_ave */
#define LJGAP_G_MAX 1e6

/* ---- methods ---- */
typedef enum { LJGAP_METHOD_PDE = 0, LJGAP_METHOD_PAPER = 1, LJGAP_METHOD_MC = 2 } ljgap_method;

typedef struct {
    ljgap_method method;
    double tol;                 /* |err| <= tol*max(1,|value|) is the target (1e-6) */
    double vmax;                /* paper: band variance bound Vmax (1/400) */
    int fixed_vmax;             /* paper: answer at vmax itself, not refined to tol (0); its
                                 * error is then 3|v(vmax) - v(vmax/2)| */
    long samples;               /* montecarlo: number of paths (1e5) */
    unsigned long seed;         /* montecarlo: seed (1) */
    double max_seconds;         /* wall-time cap of one computation (20 s) */
    long max_work;              /* cap on grid points x steps summed over levels (4e8) */
    const volatile int *cancel; /* optional: computation stops with LJGAP_ECANCEL when
                                 * *cancel becomes nonzero */
} ljgap_opts;
void ljgap_opts_default(ljgap_opts *o);

/* The adhesion summary of a traction curve (theory.md §1 "outputs"). */
typedef struct {
    ljgap_est g_eq;       /* mean gap where mean traction = 0, left of the maximum */
    ljgap_est sigma_max;  /* maximum mean traction / sigma0 (pull-off traction) */
    ljgap_est g_at_max;   /* mean gap at the maximum */
    ljgap_est dgamma_eff; /* ∫_{g_eq}^∞ mean traction dg / (9√3/16) */
    double m0;            /* variance of the PSD (22) */
    double k0;            /* instability wavenumber (19) */
} ljgap_summary;

/* Mean traction sigma_bar(g_ave)/sigma0 at n mean gaps (n may be 0), and the summary.
 * sigma (n entries) receives values and error estimates. */
int ljgap_traction(const ljgap_psd *psd, const ljgap_opts *o, const double *g_ave, size_t n,
                   ljgap_est *sigma, ljgap_summary *sum, ljgap_warnings *w);

/* One gap PDF snapshot. */
typedef struct {
    double k2;       /* upper cut-off of this snapshot (INFINITY for the whole PSD) */
    size_t n;        /* number of points */
    double *g;       /* owned: gaps */
    double *phi;     /* owned: probability density at g */
    double mass;     /* ∫ phi dg (discrete) */
    double mean;     /* ∫ g phi dg (discrete) */
    ljgap_est sigma; /* ∫ phi sigma dg, with error */
    double phi_err;  /* estimated L1 error of phi */
} ljgap_pdf;

/* PDFs of the gap at mean gap g_ave for the PSD truncated at each k2[i] (INFINITY = whole
 * PSD). grid (NULL or {min,max,n}) asks for output on a uniform grid. out has nk2 entries,
 * released with ljgap_pdf_release. */
int ljgap_pdf_compute(const ljgap_psd *psd, const ljgap_opts *o, double g_ave, const double *k2,
                      size_t nk2, const double *grid, ljgap_pdf *out, ljgap_warnings *w);
void ljgap_pdf_release(ljgap_pdf *p, size_t n);

#ifdef __cplusplus
}
#endif
#endif
