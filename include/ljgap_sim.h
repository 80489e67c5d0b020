/* ljgap_sim.h -- the discrete numerical model of the paper's Section 5 (theory.md §5), and the
 * hybrid of its Section 6.
 *
 * A periodic square of side L (units of chi), n x n points, random surfaces with the
 * requested isotropic PSD, Lennard-Jones tractions at every point, the elastic half-space
 * answer in Fourier space, solved to a stated residual at each prescribed mean gap. The mean
 * gap is swept with continuation from the largest value inward and then back out; where the
 * two branches differ the sweep has a jump (hysteresis) and the result says so.
 *
 * Hybrid (opts.k_split): the grid carries the roughness of [k1, k_split] only, and the band
 * (k_split, k2] (k2 may be infinite) acts through its statistical law: at every grid point the
 * interface law is the mean traction σ̄(g) of that band at the local gap g (the theory, PDE
 * method, computed once per run and tabulated), in place of the Lennard-Jones law. The grid
 * must then resolve k_split, not k2. k_split = k1 is the theory alone (a flat grid), k_split
 * >= k2 the plain model.
 *
 * Realizations are independent and run on up to opts.threads threads; the result does not
 * depend on the number of threads.
 *
 * Dimensionless as in ljgap.h. Depends on FFTW3 and GSL; knows nothing of HTTP or JSON.
 */
#ifndef LJGAP_SIM_H
#define LJGAP_SIM_H
#include "ljgap.h"
#ifdef __cplusplus
extern "C" {
#endif

#define LJGAP_SIM_N_MAX 512 /* grid points per side */
#define LJGAP_SIM_REALIZATIONS_MAX 16
#define LJGAP_SIM_GAPS_MAX 200   /* mean gaps in one job */
#define LJGAP_SIM_THREADS_MAX 64 /* threads of one run */

typedef struct {
    int n;                      /* grid points per side: even, 8 <= n <= LJGAP_SIM_N_MAX (64) */
    double L;                   /* side of the periodic square in units of chi; 0 = 2*pi/k1;
                                 * otherwise 2*pi/k1 <= L <= 1e4 * 2*pi/k1 */
    int realizations;           /* 1 <= realizations <= LJGAP_SIM_REALIZATIONS_MAX (4) */
    unsigned long seed;         /* seed of realization 0; realization r uses seed + r (1) */
    double tol;                 /* residual target: rms of the force balance over the grid,
                                 * relative to sigma0, or to the rms traction where that exceeds
                                 * sigma0 (deep compression), 1e-14 <= tol <= 1e-2 (1e-8) */
    long max_iter;              /* iterations of the solver at one mean gap (200000) */
    double max_seconds;         /* wall-time cap of the whole run (600 s) */
    const volatile int *cancel; /* optional: stop with LJGAP_ECANCEL when *cancel != 0 */
    /* optional: called now and then with the fraction done (0..1); must be cheap */
    void (*progress)(void *ctx, double fraction);
    void *progress_ctx;
    int match_m0;   /* 1: scale each realization to carry the PSD's m0 exactly; 0: the
                     * lattice sum m0_grid, which overestimates m0 when L spans only a
                     * few wavelengths of k1 (1.75 m0 for Fig. 6 at L = 2π) (1) */
    double k_split; /* hybrid: 0 = none (the plain model); else k1 <= k_split <= LJGAP_K_MAX:
                     * the grid carries [k1, k_split] (and must resolve k_split), the band
                     * (k_split, k2] acts through its statistical law (0) */
    double law_tol; /* hybrid: tolerance of the fine band's law (ljgap_traction's tol),
                     * 1e-10 <= law_tol <= 1e-2 (1e-6) */
    int threads;    /* realizations computed at once, 1 <= threads <=
                     * LJGAP_SIM_THREADS_MAX (1); the result does not depend on it */
} ljgap_sim_opts;

void ljgap_sim_opts_default(ljgap_sim_opts *o);

typedef struct {
    size_t n_gap;       /* number of mean gaps, in the order asked */
    double *g_ave;      /* owned: the mean gaps */
    double *sigma;      /* owned: mean traction / sigma0 on the inward sweep, averaged
                         * over realizations */
    double *sigma_std;  /* owned: standard deviation over realizations (0 for one) */
    double *sigma_err;  /* owned: estimated error of sigma: standard error of the mean
                         * plus the effect of the residual left by the solver (plus, for
                         * the hybrid, the mean error of the fine band's law over the grid) */
    double *sigma_each; /* owned: sigma of each realization, realization r at
                         * sigma_each[r * n_gap .. r * n_gap + n_gap - 1] (inward sweep) */
    double *sigma_out;  /* owned: the same on the outward sweep (equal to sigma where
                         * there is no hysteresis) */
    double *residual;   /* owned: largest final residual over realizations, per gap */
    int *jump;          /* owned: 1 where some realization jumped between branches
                         * between this gap and the previous (larger) one on the way in
                         * (its solver met negative curvature). Never when 2*pi/L > k0:
                         * the energy is then convex, the solution unique, and the
                         * outward sweep is skipped (sigma_out = sigma) */
    int realizations;
    double *m0_realized; /* owned: height variance of each realization (on the grid: for the
                          * hybrid, of the band [k1, k_split]) */
    double m0_target;    /* variance of the PSD (the continuum m0) */
    double m0_grid;      /* the lattice sum Σ_q P(|q|)(2π/L)² over the grid's wavevectors
                          * (before any match_m0 scaling) */
    double g_min;        /* smallest local gap met at a solution */
    /* hybrid only (all zero when opts.k_split = 0) */
    double k_split;     /* opts.k_split */
    double m0_fine;     /* variance of the band (k_split, k2] (0 when k_split >= k2) */
    ljgap_summary fine; /* that band's modified law: g_eq, sigma_max, g_at_max, dgamma_eff
                         * with their errors, and m0 (the Lennard-Jones law's own values,
                         * exact, when the band is empty) */
    double law_err;     /* largest estimated error of the tabulated law at the local gaps met */
    double L;           /* side actually used */
    int n;              /* grid actually used */
} ljgap_sim_result;

/* Runs the model for g_ave[0..n_gap-1] (each in [LJGAP_G_MIN, LJGAP_G_MAX], any order).
 * The band on the grid must be resolved: k2 <= pi n / L (finite), or for the hybrid
 * k_split <= pi n / L (otherwise LJGAP_EINVAL with a warning that says which n would do). Returns
 * LJGAP_OK, LJGAP_EINVAL, LJGAP_ENOMEM, LJGAP_ECAP (time cap; res holds nothing), LJGAP_ECANCEL or
 * LJGAP_EFAIL. res is released with ljgap_sim_result_free. */
int ljgap_sim_run(const ljgap_psd *psd, const ljgap_sim_opts *o, const double *g_ave, size_t n_gap,
                  ljgap_sim_result *res, ljgap_warnings *w);
void ljgap_sim_result_free(ljgap_sim_result *res);

#ifdef __cplusplus
}
#endif
#endif
