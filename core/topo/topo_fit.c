/* topo_fit.c -- the power-law fit of a measured PSD's bins (topo.c; docs/topography.md).
 *
 * Weighted least squares of ln P on ln k, each bin weighted by its Gamma statistics, with the
 * correlations of a windowed map's neighbouring bins (sandwich errors); the band detected past a
 * roll-off (a knee below it, fit_knee), a cutoff or a white-noise floor (fit_floor), or given.
 * topo.c calls ljgap__topo_fit_band on the binned spectrum of a map or a converted profile.
 */
#include "ljgap_topo.h"
#include "topo_parts.h"

#include <float.h>
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_sf_gamma.h>
#include <gsl/gsl_sf_psi.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Weighted least squares of ln P on ln k over the bins with k in [kmin, kmax]. A bin's mean of
 * N independent exponential periodograms is Gamma-distributed: E[ln P̄] = ln P + ψ(N) - ln N
 * and Var[ln P̄] = ψ'(N) (ψ the digamma function). So each bin enters as ln P̄ - ψ(N) + ln N with
 * weight 1/(ψ'(N) + var_extra) (var_extra: a variance common to every bin, the profile
 * conversion's): without that shift the few-mode bins at low k sit low by up to γ = 0.58 in
 * ln P and tilt the slope. f filled and 0, or -1 when fewer than 3 usable bins. */
static int fit_uses(double k, double P, double modes, double kmin, double kmax)
{
    return !(k < kmin * (1 - 1e-9) || k > kmax * (1 + 1e-9) || !(P > 0) || !(modes > 0));
}

static int fit_power(const double *k, const double *P, const double *modes, const double *rho,
                     double var_extra, size_t n, double kmin, double kmax, ljgap_topo_fit *f)
{
    double S = 0, Sx = 0, Sy = 0, Sxx = 0, Sxy = 0, chi2 = 0, klo = INFINITY, khi = 0;
    size_t m = 0;
    for (int pass = 0; pass < 3; pass++) {
        double xm = pass ? Sx / S : 0, ym = pass ? Sy / S : 0, slope = pass == 2 ? Sxy / Sxx : 0;
        for (size_t i = 0; i < n; i++) {
            if (k[i] < kmin * (1 - 1e-9) || k[i] > kmax * (1 + 1e-9) || !(P[i] > 0) ||
                !(modes[i] > 0))
                continue;
            double w = 1 / (gsl_sf_psi_1(modes[i]) + var_extra);
            double x = log(k[i]), y = log(P[i]) - gsl_sf_psi(modes[i]) + log(modes[i]);
            if (pass == 0) {
                S += w, Sx += w * x, Sy += w * y;
                klo = fmin(klo, k[i]), khi = fmax(khi, k[i]);
                m++;
            } else if (pass == 1) {
                Sxx += w * (x - xm) * (x - xm);
                Sxy += w * (x - xm) * (y - ym);
            } else {
                double r = y - ym - slope * (x - xm);
                chi2 += w * r * r;
            }
        }
        if (pass == 0 && (m < 3 || !(S > 0))) return -1;
        if (pass == 1 && !(Sxx > 0)) return -1;
    }
    double xm = Sx / S, ym = Sy / S, slope = Sxy / Sxx;
    double chi2_red = chi2 / (double)(m - 2), scale = chi2_red > 1 ? chi2_red : 1;
    double var_s = scale / Sxx, var_y = scale / S;
    if (rho) { /* a windowed map's neighbouring bins share modes: the estimates' sandwich
                * variance, Var = Σ_ij c_i c_j Cov_ij with Cov_ij = ρ_ij σ_i σ_j */
        double ts = 0, ty = 0;
        for (size_t i = 0; i < n; i++)
            for (size_t l = 1; l <= TOPO_LAGS && i + l < n; l++) {
                size_t j = i + l;
                double r = rho[TOPO_LAGS * i + l - 1];
                if (!(r > 0) || !fit_uses(k[i], P[i], modes[i], kmin, kmax) ||
                    !fit_uses(k[j], P[j], modes[j], kmin, kmax))
                    continue;
                double w0 = 1 / (gsl_sf_psi_1(modes[i]) + var_extra);
                double w1 = 1 / (gsl_sf_psi_1(modes[j]) + var_extra), sw = sqrt(w0 * w1);
                ts += 2 * r * sw * (log(k[i]) - xm) * (log(k[j]) - xm);
                ty += 2 * r * sw;
            }
        var_s *= fmax(1 + ts / Sxx, 1);
        var_y *= fmax(1 + ty / S, 1);
    }
    double lnC = ym - slope * xm, var_lnC = var_y + xm * xm * var_s;
    f->D.value = 0.5 * (slope + 8);
    f->D.err = 0.5 * sqrt(var_s);
    f->C.value = exp(lnC);
    f->C.err = f->C.value * sqrt(var_lnC);
    f->corr = var_lnC > 0 ? -xm * var_s / sqrt(var_lnC * var_s) : 0;
    f->kmin = klo;
    f->kmax = khi;
    f->bins = m;
    f->chi2_red = chi2_red;
    f->noise_floor = 0;
    f->noise_floor_err = 0;
    f->rolloff = 0;
    return 0;
}

/* The curvature of ln P in ln k over the bins [0, n): the weighted least-squares quadratic
 * y = a + b x + c x² (x centred, weights as in fit_power); *c and its standard error *sc.
 * -1 when fewer than 4 bins or a singular system. */
static int fit_curvature(const double *k, const double *P, const double *modes, double var_extra,
                         size_t n, double *c, double *sc)
{
    double S[5] = {0}, T[3] = {0}, xm = 0, W = 0;
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (P[i] > 0 && modes[i] > 0) {
            double w = 1 / (gsl_sf_psi_1(modes[i]) + var_extra);
            W += w, xm += w * log(k[i]), m++;
        }
    if (m < 4 || !(W > 0)) return -1;
    xm /= W;
    for (size_t i = 0; i < n; i++) {
        if (!(P[i] > 0) || !(modes[i] > 0)) continue;
        double w = 1 / (gsl_sf_psi_1(modes[i]) + var_extra), x = log(k[i]) - xm;
        double y = log(P[i]) - gsl_sf_psi(modes[i]) + log(modes[i]), xp = 1;
        for (int p = 0; p < 5; p++, xp *= x) {
            S[p] += w * xp;
            if (p < 3) T[p] += w * xp * y;
        }
    }
    /* normal equations [[S0 S1 S2] [S1 S2 S3] [S2 S3 S4]] (a b c) = T, by Cramer's rule */
    double A[3][3] = {{S[0], S[1], S[2]}, {S[1], S[2], S[3]}, {S[2], S[3], S[4]}};
    double det = A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
                 A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
                 A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
    if (!(fabs(det) > 0) || !isfinite(det)) return -1;
    double numc = A[0][0] * (A[1][1] * T[2] - T[1] * A[2][1]) -
                  A[0][1] * (A[1][0] * T[2] - T[1] * A[2][0]) +
                  T[0] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
    double cof = A[0][0] * A[1][1] - A[0][1] * A[1][0]; /* (A⁻¹)_cc = cof / det */
    *c = numc / det;
    *sc = cof / det > 0 ? sqrt(cof / det) : INFINITY;
    return 0;
}

#define TOPO_BAND_MIN 0.7   /* decades: the narrowest band the detection takes */
#define TOPO_BAND_EDGE 0.35 /* decades: the ends whose slope must agree with the band's */
#define TOPO_BAND_SLOPE                                                                            \
    -1.0 /* and it falls faster than k^-1 (D < 3.5): flat parts (roll-off,                         \
          * white-noise floor) are no candidates */
#define TOPO_BAND_STEEP                                                                            \
    -6.0 /* when no window passes, the fallback takes none steeper than k^-6 (D < 1: a cutoff) */

/* Is the window [a, b] a power law? Its fit into f (-1: no fit); *z the largest of its tests'
 * normalised statistics (χ²'s excess in its standard deviations, the curvature's and the ends'
 * slope differences in their standard errors), *ok whether all lie within Z and the window
 * falls faster than k^-1. */
static int window_fit(const double *k, const double *P, const double *modes, const double *rho,
                      double var_extra, size_t a, size_t b, double Z, ljgap_topo_fit *f, int *ok,
                      double *z)
{
    double c, sc;
    *ok = 0;
    *z = INFINITY;
    if (fit_power(k + a, P + a, modes + a, rho ? rho + TOPO_LAGS * a : NULL, var_extra, b - a + 1,
                  0, INFINITY, f))
        return -1;
    double dof = (double)f->bins - 2;
    double zmax = (f->chi2_red - 1) / sqrt(2 / dof);
    if (fit_curvature(k + a, P + a, modes + a, var_extra, b - a + 1, &c, &sc) == 0)
        zmax = fmax(zmax, fabs(c) / sc);
    /* the slope at either end (its last TOPO_BAND_EDGE decades) agrees with the band's: a
     * floor or a roll-off bends the ends first, where a global test has little power */
    for (int end = 0; end < 2; end++) {
        size_t x = end ? b : a, y = x;
        while (end ? (y > a && log10(k[b] / k[y - 1]) <= TOPO_BAND_EDGE)
                   : (y < b && log10(k[y + 1] / k[a]) <= TOPO_BAND_EDGE))
            y += end ? (size_t)-1 : 1;
        size_t u = end ? y : x, v = end ? x : y;
        ljgap_topo_fit g;
        if (v < u + 2 || v - u + 1 >= f->bins) continue;
        if (fit_power(k + u, P + u, modes + u, rho ? rho + TOPO_LAGS * u : NULL, var_extra,
                      v - u + 1, 0, INFINITY, &g))
            continue;
        zmax = fmax(zmax, fabs(g.D.value - f->D.value) / hypot(g.D.err, f->D.err));
    }
    if (!(zmax == zmax)) zmax = INFINITY;
    *z = zmax;
    *ok = zmax <= Z && 2 * f->D.value - 8 < TOPO_BAND_SLOPE;
    return 0;
}

#define TOPO_FLOOR_ALPHA                                                                           \
    1e-3 /* the floor's F-test level: it runs on every map, and a false floor shortens the band    \
          * (at 5 % it found one in 2 to 5 % of clean 256² maps; at 0.1 % in none of 300) */

/* The power law with a white floor, P = C k^s + N, over the bins [0, n) for a given N: the
 * weighted fit of ln(P - N) (fit_power on P - N with the modes m (1 - N/P)², the relative
 * variance of P - N being the bin's times (P/(P - N))²). -1 when a bin lies at or below N. */
static int fit_minus(const double *k, const double *P, const double *modes, const double *rho,
                     double var_extra, size_t n, double N, double *Pw, double *mw,
                     ljgap_topo_fit *f)
{
    for (size_t i = 0; i < n; i++) {
        double r = 1 - N / P[i];
        if (!(r > 0)) return -1;
        Pw[i] = P[i] - N, mw[i] = modes[i] * r * r;
    }
    return fit_power(k, Pw, mw, rho, var_extra, n, 0, INFINITY, f);
}

/* The floor's error from its χ² profile on the grid (N[i], chi[i], increasing N): the interval
 * where χ² ≤ χ²_min + s (s = max(χ²_red, 1): the errors scaled for misfit as the fit's), its
 * ends interpolated linearly between grid points; half its width. An end beyond the grid: the
 * other half-width (a floor's upper end unbounded on the grid: its distance to the grid's end). */
static double floor_err(const double *N, const double *chi, int n, double chimin, double s)
{
    int b = 0;
    for (int i = 0; i < n; i++)
        if (chi[i] < chi[b]) b = i;
    double lim = chimin + s, lo = NAN, hi = NAN;
    for (int i = b; i > 0; i--)
        if (isfinite(chi[i - 1]) && chi[i - 1] > lim) {
            lo = N[i - 1] + (N[i] - N[i - 1]) * (chi[i - 1] - lim) / (chi[i - 1] - chi[i]);
            break;
        }
    for (int i = b; i + 1 < n; i++)
        if (!isfinite(chi[i + 1]) || chi[i + 1] > lim) {
            hi = isfinite(chi[i + 1])
                     ? N[i] + (N[i + 1] - N[i]) * (lim - chi[i]) / (chi[i + 1] - chi[i])
                     : N[i + 1];
            break;
        }
    double e = isfinite(lo) && isfinite(hi) ? (hi - lo) / 2
               : isfinite(lo)               ? N[b] - lo
               : isfinite(hi)               ? hi - N[b]
                                            : N[b];
    return fmax(e, 0);
}

/* A white-noise floor above the band starting at bin a: N profiled on a grid (0 and Pmin
 * 10^(-3 + j/20), j < 60, Pmin the least P over [a, hi]), the law fitted to ln(P - N) over
 * [a, hi] at each. The floor is kept when it lowers χ² significantly (F(1, n - 3) at
 * TOPO_FLOOR_ALPHA) and
 * the law + floor is itself acceptable over [a, hi] (χ²_red within 1 + Z √(2/dof)); the band
 * then ends where N reaches TOPO_FLOOR_END of the law and the fit is the law's with N
 * subtracted. 1 and f set when a floor is found, 0 otherwise, -1 out of memory. */
static int fit_floor(const double *k, const double *P, const double *modes, const double *rho,
                     double var_extra, size_t a, size_t hi, double Z, ljgap_topo_fit *f)
{
    size_t n = hi - a + 1;
    if (n < 6) return 0;
    double *Pw = malloc(2 * n * sizeof *Pw), Pmin = INFINITY, chi0 = INFINITY, chib = INFINITY,
           Nb = 0, Ng[61], cg[61];
    if (!Pw) return -1;
    double *mw = Pw + n;
    ljgap_topo_fit g;
    for (size_t i = a; i <= hi; i++)
        Pmin = fmin(Pmin, P[i]);
    for (int j = -1; j < 60; j++) {
        double N = j < 0 ? 0 : Pmin * pow(10, -3 + j / 20.0);
        Ng[j + 1] = N, cg[j + 1] = INFINITY;
        if (fit_minus(k + a, P + a, modes + a, rho ? rho + TOPO_LAGS * a : NULL, var_extra, n, N,
                      Pw, mw, &g))
            continue;
        double chi = g.chi2_red * ((double)g.bins - 2);
        cg[j + 1] = chi;
        if (j < 0) chi0 = chi;
        if (chi < chib) chib = chi, Nb = N;
    }
    int found = 0;
    double dof = (double)n - 3;
    if (Nb > 0 && isfinite(chi0) && chib / dof <= 1 + Z * sqrt(2 / dof) &&
        (chi0 - chib) / fmax(chib / dof, 1) > gsl_cdf_fdist_Pinv(1 - TOPO_FLOOR_ALPHA, 1, dof)) {
        /* the band's end: the last bin at which N <= TOPO_FLOOR_END × (P - N) */
        size_t b = a;
        for (size_t i = a; i <= hi; i++)
            if (Nb <= TOPO_FLOOR_END * (P[i] - Nb)) b = i;
        if (b >= a + 2 && !fit_minus(k + a, P + a, modes + a, rho ? rho + TOPO_LAGS * a : NULL,
                                     var_extra, b - a + 1, Nb, Pw, mw, &g)) {
            *f = g;
            f->noise_floor = Nb;
            f->noise_floor_err = floor_err(Ng, cg, 61, chib, fmax(chib / dof, 1));
            found = 1;
        }
    }
    free(Pw);
    return found;
}

#define TOPO_KNEE_ALPHA                                                                            \
    1e-3 /* the roll-off's F-test level, the floor's (TOPO_FLOOR_ALPHA): it runs on every map,     \
          * and a false knee drops the lowest bins */
#define TOPO_KNEE_CLEAR                                                                            \
    1.3                    /* the band starts at the first bin whose modes all lie above           \
                            * TOPO_KNEE_CLEAR k_r */
#define TOPO_KNEE_STEPS 40 /* the knee's grid: 40 points a decade */

/* A roll-off below the band [a, b] (bins [lo, b] with lo <= a): the law flat below a knee,
 * P = C max(k, k_r)^s (SurfaceTopography's roll-off), k_r profiled on a grid of
 * TOPO_KNEE_STEPS a decade from k[lo] up to the lower of √(k[lo] k[b]) and the point that
 * leaves TOPO_BAND_MIN decades above TOPO_KNEE_CLEAR k_r, the law fitted to ln P on
 * ln max(k, k_r) over [lo, b] at each. The knee is kept when it lowers χ² significantly
 * (F(1, n - 3) at TOPO_KNEE_ALPHA, the χ² scaled by max(χ²_red, 1) as the floor's); *kr then
 * holds it and *first the first bin of [a, b] whose lower edge edge[i] lies at or above
 * TOPO_KNEE_CLEAR k_r, or, when that leaves less than TOPO_BAND_MIN decades, at or above k_r
 * (a bin straddling the knee sits above the continued law and, being the band's lowest,
 * levers its slope: a roll-off always flattens the low end).
 * 1 when a knee moves the band's start, 0 otherwise (*kr set whenever a knee is kept), -1 out
 * of memory. */
static int fit_knee(const double *k, const double *P, const double *modes, const double *rho,
                    const double *edge, double var_extra, size_t lo, size_t a, size_t b, double *kr,
                    size_t *first)
{
    size_t n = b - lo + 1;
    *kr = 0;
    *first = a;
    if (n < 6 || !edge) return 0;
    double *kk = malloc(n * sizeof *kk), chi0 = INFINITY, chib = INFINITY, kb = 0, db = 0;
    if (!kk) return -1;
    double top = fmin(sqrt(k[lo] * k[b]), k[b] / pow(10, TOPO_BAND_MIN) / TOPO_KNEE_CLEAR);
    ljgap_topo_fit g;
    for (int j = -1;; j++) {
        double K = j < 0 ? 0 : k[lo] * pow(10, (double)(j + 1) / TOPO_KNEE_STEPS);
        if (j >= 0 && K > top) break;
        for (size_t i = 0; i < n; i++)
            kk[i] = fmax(k[lo + i], K);
        if (fit_power(kk, P + lo, modes + lo, rho ? rho + TOPO_LAGS * lo : NULL, var_extra, n, 0,
                      INFINITY, &g))
            continue;
        double chi = g.chi2_red * ((double)g.bins - 2);
        if (j < 0) {
            chi0 = chi;
            continue;
        }
        if (chi < chib) chib = chi, kb = K, db = (double)g.bins - 3;
    }
    free(kk);
    if (!(kb > 0) || !isfinite(chi0) || !(db > 0) ||
        !((chi0 - chib) / fmax(chib / db, 1) > gsl_cdf_fdist_Pinv(1 - TOPO_KNEE_ALPHA, 1, db)))
        return 0;
    *kr = kb;
    /* the first bin clear of the knee; when that leaves less than TOPO_BAND_MIN decades, the
     * first whose modes all lie above k_r */
    for (int pass = 0; pass < 2; pass++) {
        size_t i = a;
        while (i <= b && edge[i] < (pass ? 1 : TOPO_KNEE_CLEAR) * kb * (1 - 1e-9))
            i++;
        if (i == a) return 0;
        if (i + 2 > b || log10(k[b] / k[i]) < TOPO_BAND_MIN) continue;
        *first = i;
        return 1;
    }
    return 0;
}

/* The power-law band among the bins [lo, hi] (fix_lo, fix_hi: that end is given and stays):
 * of the M windows of contiguous bins at least TOPO_BAND_MIN decades wide, those that are a
 * power law with each test at Z_M = Φ⁻¹(1 - 0.05/(8 M)) (window_fit; 4 tests a window, two
 * of them two-sided: the family of all at 5 %, Bonferroni); of those the one whose D has the
 * least error (scaled by its misfit), then, unless the upper end is given, with a white floor
 * when one is found (fit_floor). None passes: of the windows that fall faster than k^-1 and
 * slower than k^-6 (TOPO_BAND_STEEP: no cutoff), the one whose largest normalised statistic is
 * least, not sound; none of those: the fit over [lo, hi], not sound. f filled and 0, or -1
 * when [lo, hi] holds fewer than 3 bins. */
int ljgap__topo_fit_band(const double *k, const double *P, const double *modes, const double *rho,
                         const double *edge, double var_extra, size_t lo, size_t hi, int fix_lo,
                         int fix_hi, ljgap_topo_fit *f)
{
    ljgap_topo_fit t, best = {0}, any = {0};
    double z, zany = INFINITY, ZM = INFINITY;
    int ok, found = 0, found_any = 0;
    size_t M = 0;
    if (hi < lo + 2) return -1;
    for (int pass = 0; pass < 2; pass++) {
        /* pass 0 counts the windows, M; pass 1 tests each at Z_M = Φ⁻¹(1 - 0.05/(8 M)) */
        ZM = pass ? gsl_cdf_ugaussian_Qinv(0.05 / (8.0 * (double)M)) : 0;
        for (size_t a = lo; a + 2 <= hi && (!fix_lo || a == lo); a++)
            for (size_t b = hi; b >= a + 2 && (!fix_hi || b == hi); b--) {
                double w = log10(k[b] / k[a]);
                if (w < TOPO_BAND_MIN && !(a == lo && b == hi)) break; /* narrower from here */
                if (!pass) {
                    M++;
                    continue;
                }
                if (window_fit(k, P, modes, rho, var_extra, a, b, ZM, &t, &ok, &z)) continue;
                if (ok && (!found || t.D.err < best.D.err)) best = t, found = 1;
                double s = 2 * t.D.value - 8;
                if (s < TOPO_BAND_SLOPE && s > TOPO_BAND_STEEP && z < zany)
                    any = t, zany = z, found_any = 1;
            }
    }
    if (found || found_any) {
        *f = found ? best : any;
        f->sound = found && f->D.value > 2 && f->D.value < 3;
        ljgap_topo_fit g;
        size_t a = lo, e = lo, a2;
        double kr = 0;
        while (a < hi && k[a] < f->kmin * (1 - 1e-9))
            a++;
        while (e < hi && k[e + 1] <= f->kmax * (1 + 1e-9))
            e++;
        /* a roll-off below the band: its knee's bins tilt the band's low end (fit_knee) */
        if (!fix_lo && found) {
            int kn = fit_knee(k, P, modes, rho, edge, var_extra, lo, a, e, &kr, &a2);
            if (kn < 0) return -1;
            if (kn == 1 && fit_power(k + a2, P + a2, modes + a2, rho ? rho + TOPO_LAGS * a2 : NULL,
                                     var_extra, e - a2 + 1, 0, INFINITY, &g) == 0) {
                g.sound = g.D.value > 2 && g.D.value < 3;
                *f = g, a = a2;
            }
        }
        /* a white floor above the band tilts its upper bins before any test sees it */
        if (!fix_hi && found && fit_floor(k, P, modes, rho, var_extra, a, hi, ZM, &g) == 1) {
            g.sound = g.D.value > 2 && g.D.value < 3;
            *f = g;
        }
        f->rolloff = kr;
    } else {
        if (fit_power(k + lo, P + lo, modes + lo, rho ? rho + TOPO_LAGS * lo : NULL, var_extra,
                      hi - lo + 1, 0, INFINITY, f))
            return -1;
        f->sound = 0;
    }
    f->given = fix_lo || fix_hi;
    return 0;
}
