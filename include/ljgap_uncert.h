/* ljgap_uncert.h -- the measurement's uncertainty of a PSD, carried to what is computed from it.
 *
 * A measured PSD is known to its errors: each knot of a table to its P_err (1 σ), neighbouring
 * knots correlated (a windowed map's, and the table's solve, make them anticorrelated), the
 * tail's exponent to its exponent_err; a power law's D and level to theirs. Whatever the core
 * computes from the PSD (the adhesion summary, a traction curve, a PDF's mean traction) inherits
 * that uncertainty. Two ways to carry it, both with the caller's solver in the loop (the core
 * makes the PSDs and combines the answers; the caller solves each PSD as it solves the nominal
 * one):
 *
 *   - sampling (a table): K PSDs whose knot vector ln P is drawn from N(ln P, Σ), Σ the knots'
 *     relative variances ln(1 + (P_err/P)²) with the neighbours' correlations (tridiagonal,
 *     Cholesky), the tail exponent independently N(q, q_err²); a quantity's input error is the
 *     standard deviation of its K values about their mean (K − 1 degrees of freedom: the
 *     estimate's own relative error is about 1/√(2(K − 1)));
 *   - linear propagation (a power law, few parameters): for each parameter p with error σ_p the
 *     PSDs at p ± h σ_p (h = 1, smaller near a bound of the model), and
 *     σ_f² = Σ_p ((f(p + hσ_p) − f(p − hσ_p))/(2h))², parameters independent.
 *
 * The draws come from a fixed seed, so an answer is reproducible and cacheable. Knows nothing
 * of JSON; docs/theory.md §9 states the method and its test.
 */
#ifndef LJGAP_UNCERT_H
#define LJGAP_UNCERT_H

#include "ljgap.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LJGAP_UNCERT_KMAX 64 /* at most this many perturbed PSDs */

/* What the sampling of a table did besides drawing. */
typedef struct {
    double corr_scale; /* the neighbours' correlations were multiplied by this (1: as given;
                        * less when they did not form a positive definite matrix) */
    int tail_clipped;  /* draws of the tail exponent clipped to keep the variance finite */
} ljgap_uncert_info;

/* K perturbed copies of the table psd (n knots, possibly a tail) into out[0..K-1] (each to be
 * freed with ljgap_psd_free): ln P of the knots drawn from N(ln P, Σ), Σ_ii = ln(1 + r_i²),
 * r_i = P_err[i]/P[i], Σ_i,i+1 = corr[i] √(Σ_ii Σ_i+1,i+1) (corr NULL: independent; n − 1
 * entries, |corr| <= 1), the tail exponent q + q_err z, at most (q − 2)/2 (half-way to −2: a
 * draw beyond would carry infinite variance; info->tail_clipped counts them). seed fixes the
 * draws. LJGAP_EINVAL unless psd is a table with finite P_err >= 0, 2 <= K <= KMAX;
 * LJGAP_ENOMEM. out is untouched on failure. */
int ljgap_uncert_table_draws(const ljgap_psd *psd, const double *P_err, const double *corr,
                             double q_err, size_t K, unsigned long seed, ljgap_psd *out,
                             ljgap_uncert_info *info);

/* The standard deviation of the values x[k] with ok[k] != 0 (ok NULL: all) about their mean,
 * K − 1 degrees of freedom; NAN when fewer than 3 values count. */
double ljgap_uncert_sd_sample(const double *x, const int *ok, size_t K);

/* Linear propagation: npar parameters, x[2p] and x[2p + 1] the quantity at p + h[p] σ_p and
 * p − h[p] σ_p: √Σ ((x[2p] − x[2p + 1])/(2 h[p]))². NAN when a value is not finite. */
double ljgap_uncert_sd_linear(const double *x, const double *h, size_t npar);

/* The step h in units of err, at most 1, such that value ± h err stays inside (lo, hi) with a
 * margin of 1 % of the room left; 0 when err is 0 or value lies outside. */
double ljgap_uncert_step(double value, double err, double lo, double hi);

/* The relative standard error of a standard deviation estimated from K samples,
 * 1/√(2(K − 1)) (a normal population). */
double ljgap_uncert_sd_relerr(size_t K);

/* The part of psd's variance beyond kc (a table's last measured knot), over m0; 0 when none. */
double ljgap_uncert_beyond(const ljgap_psd *psd, double kc);

#ifdef __cplusplus
}
#endif
#endif
