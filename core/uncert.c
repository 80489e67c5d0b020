/* uncert.c -- perturbed PSDs from a measurement's errors, and the spread of what they give
 * (ljgap_uncert.h; docs/theory.md §9).
 *
 * A table's knots are drawn in ln P: a knot's error is relative (a periodogram bin's is P/√N),
 * the draws stay positive, and the variance ln(1 + r²) matches a log-normal's to the given
 * relative variance r². The covariance is tridiagonal (each knot correlated with the next:
 * /v1/psd's P_corr), so its Cholesky factor is lower bidiagonal and a draw costs O(n):
 *   L_00 = s_0,  L_i,i-1 = c_i-1 / L_i-1,i-1,  L_ii = √(s_i² − L_i,i-1²),  c_i = ρ_i s_i s_i+1.
 * Correlations given knot by knot need not form a positive definite matrix together (|ρ| = 1
 * everywhere does not); when a pivot fails they are all scaled by 0.9 until it holds, and the
 * scale is reported. The draws use GSL's MT19937 from a fixed seed: the same request gives the
 * same answer (the cache keeps it).
 */
#include "ljgap_uncert.h"

#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The bidiagonal Cholesky factor of the tridiagonal covariance (diag s², off-diagonal
 * scale ρ_i s_i s_i+1): d (n) and l (n, l[0] unused). 0, or -1 when not positive definite. */
static int chol_tridiag(const double *s, const double *rho, double scale, size_t n, double *d,
                        double *l)
{
    d[0] = s[0];
    l[0] = 0;
    for (size_t i = 1; i < n; i++) {
        double c = rho ? scale * rho[i - 1] * s[i - 1] * s[i] : 0, r;
        l[i] = c == 0 ? 0 : c / d[i - 1];
        r = s[i] * s[i] - l[i] * l[i];
        if (c != 0 && !(r > 1e-12 * s[i] * s[i])) return -1;
        d[i] = sqrt(r > 0 ? r : 0);
    }
    return 0;
}

int ljgap_uncert_table_draws(const ljgap_psd *psd, const double *P_err, const double *corr,
                             double q_err, size_t K, unsigned long seed, ljgap_psd *out,
                             ljgap_uncert_info *info)
{
    size_t n = psd ? psd->n : 0, made = 0;
    double *s, *d, *l, *P, scale = 1;
    gsl_rng *rng;
    int st = LJGAP_OK;
    ljgap_uncert_info inf = {1, 0};
    if (!psd || psd->kind != LJGAP_PSD_TABLE || n < 2 || !P_err || K < 2 || K > LJGAP_UNCERT_KMAX ||
        !(q_err >= 0) || !isfinite(q_err))
        return LJGAP_EINVAL;
    for (size_t i = 0; i < n; i++)
        if (!(P_err[i] >= 0) || !isfinite(P_err[i])) return LJGAP_EINVAL;
    for (size_t i = 0; corr && i + 1 < n; i++)
        if (!(fabs(corr[i]) <= 1)) return LJGAP_EINVAL;
    s = malloc(4 * n * sizeof *s);
    rng = gsl_rng_alloc(gsl_rng_mt19937);
    if (!s || !rng) {
        free(s);
        if (rng) gsl_rng_free(rng);
        return LJGAP_ENOMEM;
    }
    d = s + n, l = d + n, P = l + n;
    for (size_t i = 0; i < n; i++) {
        double r = P_err[i] / psd->P[i];
        s[i] = sqrt(log1p(r * r));
    }
    while (chol_tridiag(s, corr, scale, n, d, l) != 0)
        scale *= 0.9; /* terminates: at scale ~0 the matrix is diagonal */
    inf.corr_scale = scale;
    gsl_rng_set(rng, seed);
    for (made = 0; made < K; made++) {
        double zprev = 0, q = psd->tail_q;
        for (size_t i = 0; i < n; i++) {
            double z = gsl_ran_gaussian(rng, 1.0);
            P[i] = psd->P[i] * exp(l[i] * zprev + d[i] * z);
            /* the next knot's term l[i+1] multiplies the previous *normalised* row: with
             * y = L z, y_i = l_i z_i-1 + d_i z_i */
            zprev = z;
        }
        if (psd->has_tail) {
            double z = gsl_ran_gaussian(rng, 1.0), qmax = (psd->tail_q - 2) / 2;
            q = psd->tail_q + q_err * z;
            if (q > qmax) q = qmax, inf.tail_clipped++;
        }
        st = ljgap_psd_table(&out[made], psd->k, P, n, psd->has_tail, q);
        if (st) break;
    }
    if (st)
        for (size_t k = 0; k < made; k++)
            ljgap_psd_free(&out[k]);
    gsl_rng_free(rng);
    free(s);
    if (!st && info) *info = inf;
    return st;
}

double ljgap_uncert_sd_sample(const double *x, const int *ok, size_t K)
{
    double m = 0, v = 0;
    size_t c = 0;
    for (size_t k = 0; k < K; k++)
        if ((!ok || ok[k]) && isfinite(x[k])) m += x[k], c++;
    if (c < 3) return NAN;
    m /= (double)c;
    for (size_t k = 0; k < K; k++)
        if ((!ok || ok[k]) && isfinite(x[k])) v += (x[k] - m) * (x[k] - m);
    return sqrt(v / (double)(c - 1));
}

double ljgap_uncert_sd_linear(const double *x, const double *h, size_t npar)
{
    double v = 0;
    for (size_t p = 0; p < npar; p++) {
        double g = (x[2 * p] - x[2 * p + 1]) / (2 * h[p]);
        if (!isfinite(g)) return NAN;
        v += g * g;
    }
    return sqrt(v);
}

double ljgap_uncert_step(double value, double err, double lo, double hi)
{
    double room;
    if (!(err > 0) || !(value > lo && value < hi)) return 0;
    room = 0.99 * fmin(value - lo, hi - value);
    return err <= room ? 1 : room / err;
}

double ljgap_uncert_sd_relerr(size_t K)
{
    return K > 1 ? 1 / sqrt(2.0 * (double)(K - 1)) : INFINITY;
}

double ljgap_uncert_beyond(const ljgap_psd *psd, double kc)
{
    if (!psd || !(psd->m0 > 0) || !(kc < psd->k2)) return 0;
    return (psd->m0 - ljgap_psd_cumvar(psd, kc)) / psd->m0;
}
