/* topo.c -- the isotropic PSD of a measured height map (issue 15, include/ljgap_topo.h).
 *
 * Convention: wavenumbers are angular and ∫∫ P d²k = 2π ∫ k P dk = h_rms², the paper's (22)
 * with its k the angular wavenumber of a sinusoid h sin(kx) (theory.md §1); a profile's
 * two-sided 1-D PSD PP has ∫ PP dk = 2 ∫_0^∞ PP dk = h_rms², the paper's PP of (22).
 *
 * Periodogram. An nx × ny map with spacings dx, dy (sides Lx = nx dx, Ly = ny dy) has the
 * wavevectors q = (2π i/Lx, 2π j/Ly); with H(q) = Σ h e^{-iq·x} over the grid (FFTW's
 * unnormalised forward transform) the periodogram is
 *     P(q) = dx dy |H(q)|² / ((2π)² nx ny),
 * so that Σ_q P(q) Δqx Δqy = mean(h²) (Parseval, Δq = 2π/L): the lattice form of ∫∫ P d²k =
 * h_rms². A profile of n points, spacing d: PP(k) = d |H(k)|² / (2π n), Σ PP Δk = mean(h²).
 * core/sim.c builds surfaces the other way round (amplitude √(P(|q|)) Δq per wavevector), so a
 * surface it makes comes back with exactly its P at every wavevector.
 *
 * Detrending and window. Periodic: the mean is removed, nothing else. Non-periodic: the
 * least-squares plane a + b(x - x̄) + c(y - ȳ) (a line for a profile) is removed, then the map is
 * multiplied by w(i)w(j), w(i) = (1 - cos(2πi/n))/2 (the periodic Hann window), divided by the
 * rms of the window over the map (√(3/8) a direction), so that the windowed map keeps the
 * detrended map's variance on average ("variance correction"). The window takes the map's ends
 * smoothly to zero: otherwise the jump between opposite edges of a non-periodic map leaks a
 * k^-2 (k^-3 in 2-D) spectrum over everything steeper.
 *
 * Bins. Edges k_f 10^((b - 1/2)/B), b = 0, 1, ..., B bins a decade, k_f the grid's lowest
 * nonzero |q| (which sits mid-bin). Every mode with 0 < |q| <= k_nyq = min(π/dx, π/dy) goes to
 * the bin of its |q|; the bin's k is the mean |q| of its modes, its P their mean periodogram.
 * The corners of the grid beyond k_nyq (an incomplete annulus) stay out of the bins but count
 * in h_rms, the slope and m0_spectrum.
 *
 * Errors. For a Gaussian random surface each independent mode's periodogram is exponentially
 * distributed (χ² with 2 degrees of freedom): its standard deviation equals its mean. q and -q
 * are one mode (h is real), so a bin of N modes q has N/2 independent ones and P_err = P/√(N/2).
 * The Hann window correlates neighbouring DFT values: its spectrum is (-1/4, 1/2, -1/4), so
 * values m apart along a direction have correlation ρ = 1, -2/3, 1/6 (m = 0, 1, 2) and their
 * periodograms ρ², and a bin's mean has variance σ²/N² Σ_{i,j in the bin} ρ²_ij (ρ²_ij the product
 * over the two directions). That sum is taken exactly, over the 5 × 5 neighbourhood of every
 * mode in the bin: a wide bin tends to (35/18)² times the unwindowed variance (Welch's factor
 * 1 + 2(ρ1² + ρ2²) = 35/18 a direction), a thin or sparse one to 1. The moments m0 = Σ P Δq² and
 * m2 = Σ |q|² P Δq² are sums of independent exponential terms X, so Var(m0) = Σ_independent
 * X²/2 (E X² = 2 (E X)²: an unbiased estimate), times (35/18)^d windowed (d = 2 a map, 1 a
 * profile), likewise m2; the errors of h_rms = √m0 and the slope √m2 follow by linearisation.
 * h_rms itself is the rms of the detrended heights, exact for the map: its error says how well
 * it estimates the surface's. tests/unit/test_topo.c checks every error against the spread
 * over many Gaussian surfaces, periodic and windowed.
 *
 * Fit. ln P = ln C + (2D - 8) ln k by least squares over the bins in [fit_kmin, fit_kmax] with
 * weights (P/P_err)², on ln k centred at its weighted mean; standard errors from the
 * covariance, scaled by √χ²_red when the bins scatter more than their errors say (the law
 * does not describe them). Three bins at least.
 *
 * Profiles. An isotropic surface's straight profile has the 2-D PSD integrated across:
 *     PP(kx) = ∫ P(√(kx² + ky²)) dky   (an Abel transform), inverted by
 *     P(k) = -(1/π) ∫_k^∞ PP'(s) ds / √(s² - k²).
 * For PP = A k^-α (α > 0) this gives exactly P(k) = F(α) PP(k)/k with
 *     F(α) = Γ((α+1)/2) / (√π Γ(α/2))   (∫(1+t²)^-s dt = √π Γ(s-1/2)/Γ(s), s = (α+1)/2),
 * e.g. F(2) = 1/2 for D = 2.5 (P ∝ k^-3, PP ∝ k^-2); D = (7 - α)/2. We fit α to the profile's bins
 * (the fit band as for maps) and convert every bin with F(α): exact for a power-law spectrum,
 * approximate where the spectrum bends (about a bin's width around a roll-off) and near k_nyq,
 * where the profile lacks the ky the grid did not sample. The converted bins' errors add the
 * effect of α's error on F in quadrature. The slope of an isotropic surface: <|∇h|²> =
 * 2 <h'²> for any straight profile, so rms_slope = √(2 m2) of the profile.
 *
 * FFTW's planner is not thread-safe and core/sim.c plans under a lock of its own, so a lock
 * inside FFTW (fftw_make_planner_thread_safe, libfftw3_threads) serialises every planner call
 * of every module; it is installed before main, while the process has one thread.
 */
#include "ljgap_topo.h"
#include "topo_parts.h"

#include <fftw3.h>
#include <float.h>
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_sf_bessel.h>
#include <gsl/gsl_sf_gamma.h>
#include <gsl/gsl_sf_psi.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define TOPO_HANN_VIF (35.0 / 18.0) /* Welch's variance factor of Hann-windowed sums */
#define TOPO_ALPHA_MIN 0.1          /* flattest profile spectrum converted (F -> 0 as α -> 0) */
#define TOPO_POINTS_MAX ((size_t)1 << 28) /* hard bound; the server's cap is far lower */
#define TOPO_FIT_WINDOWED 4.0             /* automatic fit band of a windowed map: from 4 k_f */

__attribute__((constructor)) static void topo_fftw_thread_safe(void)
{
    fftw_make_planner_thread_safe();
}

void ljgap_topo_opts_default(ljgap_topo_opts *o)
{
    memset(o, 0, sizeof *o);
    o->bins_per_decade = 10;
    o->fit_kmin = 0;
    o->fit_kmax = 0;
    o->detrend = LJGAP_DETREND_AUTO;
    o->tip_radius = 0;
    o->resolution = 0;
    o->cancel = NULL;
}

void ljgap_topo_result_free(ljgap_topo_result *res)
{
    if (!res) return;
    free(res->k);
    free(res->P);
    free(res->P_err);
    free(res->modes);
    free(res->lo);
    free(res->hi);
    free(res->var);
    free(res->slope);
    free(res->rho);
    free(res->PP);
    free(res->PP_err);
    memset(res, 0, sizeof *res);
}

double ljgap_topo_abel_factor(double alpha)
{
    if (!(alpha > 0)) return NAN;
    return exp(gsl_sf_lngamma(0.5 * (alpha + 1)) - gsl_sf_lngamma(0.5 * alpha)) / sqrt(M_PI);
}

/* d ln F / d alpha */
static double abel_dlog(double alpha)
{
    return 0.5 * (gsl_sf_psi(0.5 * (alpha + 1)) - gsl_sf_psi(0.5 * alpha));
}

/* ---- bins ---- */

#define TOPO_NO_BIN UINT16_MAX

/* Sums per logarithmic bin while the modes are visited. */
typedef struct {
    size_t nb;    /* bins allocated (< TOPO_NO_BIN) */
    double kf;    /* fundamental: the bins' origin */
    double knyq;  /* last |q| binned */
    double B;     /* bins per decade */
    double *cnt;  /* modes (full plane or full line) */
    double *sl;   /* Σ ln(|q|/kf), Σ ln², Σ ln³: 3 a bin */
    double *sP;   /* Σ periodogram */
    double *cor;  /* windowed: Σ over the bin's modes of the in-bin correlation sum (see
                   * bin_correlations); NULL unwindowed (each mode correlates with itself only) */
    double *xcor; /* windowed: the same over the next bin's modes (the bins' covariance) */
    double cell;  /* the lattice's cell: Δqx Δqy (a map) or Δk (a profile) */
    int line;     /* 1: a profile (cells along a line) */
} binner;

static int binner_alloc(binner *b, double kf, double knyq, double B, int windowed)
{
    b->kf = kf;
    b->knyq = knyq;
    b->B = B;
    b->nb = (size_t)floor(B * log10(knyq / kf) + 0.5) + 2;
    b->cnt = calloc(b->nb, sizeof(double));
    b->sl = calloc(3 * b->nb, sizeof(double));
    b->sP = calloc(b->nb, sizeof(double));
    b->cor = windowed ? calloc(b->nb, sizeof(double)) : NULL;
    b->xcor = windowed ? calloc(TOPO_LAGS * b->nb, sizeof(double)) : NULL;
    return b->cnt && b->sl && b->sP && ((b->cor && b->xcor) || !windowed) && b->nb < TOPO_NO_BIN
               ? LJGAP_OK
               : LJGAP_ENOMEM;
}

static void binner_free(binner *b)
{
    free(b->cnt);
    free(b->sl);
    free(b->sP);
    free(b->cor);
    free(b->xcor);
}

/* The bin of |q| (TOPO_NO_BIN beyond k_nyq); x = ln(q/kf). */
static uint16_t bin_of(const binner *b, double q, double x)
{
    if (!(q > 0) || q > b->knyq * (1 + 1e-12)) return TOPO_NO_BIN;
    double f = floor(b->B * x / M_LN10 + 0.5);
    size_t i = f < 0 ? 0 : (size_t)f;
    return (uint16_t)(i < b->nb ? i : b->nb - 1);
}

/* One mode of |q| = q, x = ln(q/kf), periodogram P, counted mult times, into bin i. */
static void binner_add(binner *b, uint16_t i, double x, double P, double mult)
{
    if (i == TOPO_NO_BIN) return;
    b->cnt[i] += mult;
    b->sl[3 * i] += mult * x;
    b->sl[3 * i + 1] += mult * x * x;
    b->sl[3 * i + 2] += mult * x * x * x;
    b->sP[i] += mult * P;
}

/* ρ² of two Hann-windowed DFT values m apart, m = 0, 1, 2 (0 beyond): the window's spectrum is
 * (-1/4, 1/2, -1/4), so the coefficients' correlations are 1, -2/3, 1/6. */
static const double hann_rho2[3] = {1.0, 4.0 / 9.0, 1.0 / 36.0};

/* Windowed map: for every binned half-spectrum entry (bins in bi, [ny][nxc]), the sum of ρ² over
 * the modes of the 5 × 5 stencil around it that fall in the same bin (itself included), weighted
 * like the entry, into b->cor. A bin's mean then has the variance of cnt²/cor/2 independent
 * modes: Var(mean) = σ²/M² Σ_{i,j in bin} ρ²_ij. Neighbours across kx = 0 or the grid's edge
 * are the conjugates of entries of the half spectrum (the same |q|, the same bin). */
static void bin_correlations_map(binner *b, const uint16_t *bi, size_t nx, size_t ny)
{
    const size_t nxc = nx / 2 + 1;
    double w[5][5];
    for (int c = 0; c < 5; c++)
        for (int a = 0; a < 5; a++)
            w[c][a] = hann_rho2[abs(c - 2)] * hann_rho2[abs(a - 2)];
    for (size_t j = 0; j < ny; j++)
        for (size_t i = 0; i < nxc; i++) {
            uint16_t me = bi[j * nxc + i];
            if (me == TOPO_NO_BIN) continue;
            /* acc[0]: the same bin, acc[l]: l bins on (TOPO_NO_BIN and lower bins wrap to a
             * large unsigned lag and land in acc[TOPO_LAGS + 1], discarded) */
            double acc[TOPO_LAGS + 2] = {0}, *xs = acc + 1;
            double mult = (i == 0 || 2 * i == nx) ? 1 : 2;
            if (j >= 2 && j + 2 < ny && i >= 2 && i + 2 < nxc) { /* inside: no wrapping */
                const uint16_t *r = bi + (j - 2) * nxc + (i - 2);
                double s0 = 0, s1 = 0; /* lags 0 and 1 (TOPO_LAGS): branch-free */
                const uint16_t me1 = (uint16_t)(me + 1);
                for (int c = 0; c < 5; c++, r += nxc)
                    for (int a = 0; a < 5; a++) {
                        s0 += r[a] == me ? w[c][a] : 0;
                        s1 += r[a] == me1 ? w[c][a] : 0;
                    }
                acc[0] = s0, acc[1] = s1;
            } else {
                for (long c = -2; c <= 2; c++)
                    for (long a = -2; a <= 2; a++) {
                        long ii = (long)i + a, jj = (long)j + c;
                        if (ii < 0 || ii > (long)nx / 2) { /* the conjugate: -q */
                            ii = ii < 0 ? -ii : (long)nx - ii;
                            jj = -jj;
                        }
                        jj = ((jj % (long)ny) + (long)ny) % (long)ny;
                        unsigned l = (uint16_t)(bi[(size_t)jj * nxc + (size_t)ii] - me);
                        acc[l <= TOPO_LAGS ? l : TOPO_LAGS + 1] += w[c + 2][a + 2];
                    }
            }
            b->cor[me] += mult * acc[0];
            for (int l = 0; l < TOPO_LAGS; l++)
                b->xcor[TOPO_LAGS * me + l] += mult * xs[l];
        }
}

/* The same along a profile (bins in bi[0..nc)). */
static void bin_correlations_line(binner *b, const uint16_t *bi, size_t n)
{
    size_t nc = n / 2 + 1;
    for (size_t i = 1; i < nc; i++) {
        uint16_t me = bi[i];
        if (me == TOPO_NO_BIN) continue;
        double sum = 0, xs[TOPO_LAGS] = {0}, mult = 2 * i == n ? 1 : 2;
        for (long a = -2; a <= 2; a++) {
            long ii = (long)i + a;
            if (ii < 0) ii = -ii;
            if (ii > (long)n / 2) ii = (long)n - ii;
            if (ii > 0 && bi[ii] == me) sum += hann_rho2[labs(a)];
            if (ii > 0 && bi[ii] > me && bi[ii] <= me + TOPO_LAGS && bi[ii] != TOPO_NO_BIN)
                xs[bi[ii] - me - 1] += hann_rho2[labs(a)];
        }
        b->cor[me] += mult * sum;
        for (int l = 0; l < TOPO_LAGS; l++)
            b->xcor[TOPO_LAGS * me + l] += mult * xs[l];
    }
}

/* The binned spectrum before its curvature correction. */
typedef struct {
    size_t n;              /* non-empty bins */
    double *k, *P, *P_err; /* geometric mean |q|, mean periodogram, its standard error */
    double *modes;         /* independent modes (window-corrected) */
    double *kap;           /* 2 a bin: the variance and third cumulant of ln |q| over the modes */
    double *lo, *hi;       /* the band the bin's modes cover (see binner_out) */
    double *var;           /* Σ P × cell over the bin's modes */
    double *rho;           /* the correlation of the bin's mean with the next bin's (window) */
} bins;

static void bins_free(bins *o)
{
    free(o->k);
    free(o->P);
    free(o->P_err);
    free(o->modes);
    free(o->kap);
    free(o->lo);
    free(o->hi);
    free(o->var);
    free(o->rho);
    memset(o, 0, sizeof *o);
}

/* The edge of the disc (a map: π e² = cells × cell) or interval (a profile: 2e = cells × Δk)
 * of c lattice cells around k = 0. */
static double cells_edge(const binner *b, double c)
{
    return b->line ? 0.5 * c * b->cell : sqrt(c * b->cell / M_PI);
}

/* The non-empty bins into o. A bin of cnt modes has cnt/2 independent ones unwindowed,
 * (cnt/2) · cnt/cor windowed (eff); E[P̄²] = P²(1 + 1/eff), so P̄/√(eff + 1) estimates the
 * standard error P/√eff without bias. The band a bin stands for: every mode stands for its
 * cell of the lattice, so the modes up to and including bin b (and the zero mode) cover the
 * disc of the same area; lo and hi are that disc's radius before and after the bin (the
 * fundamental modes of a periodic map, at |q| = k_f, cover k_f/√π to √(5/π) k_f). */
static int binner_out(const binner *b, bins *o)
{
    size_t m = 0;
    for (size_t i = 0; i < b->nb; i++)
        m += b->cnt[i] > 0;
    memset(o, 0, sizeof *o);
    size_t mm = m ? m : 1;
    o->k = malloc(mm * sizeof *o->k);
    o->P = malloc(mm * sizeof *o->P);
    o->P_err = malloc(mm * sizeof *o->P_err);
    o->modes = malloc(mm * sizeof *o->modes);
    o->kap = malloc(mm * 2 * sizeof *o->kap);
    o->lo = malloc(mm * sizeof *o->lo);
    o->hi = malloc(mm * sizeof *o->hi);
    o->var = malloc(mm * sizeof *o->var);
    o->rho = calloc(TOPO_LAGS * mm, sizeof *o->rho);
    if (!o->k || !o->P || !o->P_err || !o->modes || !o->kap || !o->lo || !o->hi || !o->var ||
        !o->rho)
        return LJGAP_ENOMEM;
    double cells = 1; /* the zero mode */
    for (size_t i = 0; i < b->nb; i++) {
        double c = b->cnt[i];
        if (!(c > 0)) continue;
        double eff = 0.5 * c, k1 = b->sl[3 * i] / c, m2 = b->sl[3 * i + 1] / c;
        double m3 = b->sl[3 * i + 2] / c;
        if (b->cor && b->cor[i] > 0) eff *= c / b->cor[i];
        o->k[o->n] = b->kf * exp(k1);
        o->P[o->n] = b->sP[i] / c;
        o->P_err[o->n] = o->P[o->n] / sqrt(eff + 1);
        o->modes[o->n] = eff;
        o->kap[2 * o->n] = fmax(m2 - k1 * k1, 0);
        o->kap[2 * o->n + 1] = m3 - 3 * k1 * m2 + 2 * k1 * k1 * k1;
        o->lo[o->n] = cells_edge(b, cells);
        cells += c;
        o->hi[o->n] = cells_edge(b, cells);
        o->var[o->n] = b->sP[i] * b->cell;
        /* Cov(P̄_b, P̄_b+1) = P_b P_b+1 Σ_{i∈b, j∈b+1} ρ²_ij / (cnt_b cnt_b+1) / 2 × 2 */
        for (size_t l = 1; b->xcor && l <= TOPO_LAGS && i + l < b->nb; l++) {
            if (!(b->cnt[i + l] > 0 && b->cor[i] > 0 && b->cor[i + l] > 0)) break;
            o->rho[TOPO_LAGS * o->n + l - 1] =
                fmin(b->xcor[TOPO_LAGS * i + l - 1] / sqrt(b->cor[i] * b->cor[i + l]), 0.99);
        }
        /* the bin's k inside its band (the lattice's first rings are coarse) */
        o->lo[o->n] = fmin(o->lo[o->n], o->k[o->n]);
        o->hi[o->n] = fmax(o->hi[o->n], o->k[o->n]);
        if (o->n > 0) o->lo[o->n] = fmax(o->lo[o->n], o->hi[o->n - 1]);
        o->n++;
    }
    return LJGAP_OK;
}

#define TOPO_SLOPE_REACH 2 /* the local slope: from windows of 2 × 2 + 1 bins */

/* The weighted least-squares slope of ln P over the bins [a, b] (weights and digamma shift as
 * in fit_power) and its χ² per degree of freedom (0 with two bins); -1 with fewer than 2. */
static int slope_of(const double *k, const double *P, const double *modes, size_t a, size_t b,
                    double *slope, double *chi2)
{
    double S = 0, Sx = 0, Sy = 0, Sxx = 0, Sxy = 0, Syy = 0;
    size_t m = 0;
    for (size_t j = a; j <= b; j++) {
        if (!(P[j] > 0) || !(modes[j] > 0)) continue;
        double w = 1 / gsl_sf_psi_1(modes[j]), x = log(k[j]);
        double y = log(P[j]) - gsl_sf_psi(modes[j]) + log(modes[j]);
        S += w, Sx += w * x, Sy += w * y, Sxx += w * x * x, Sxy += w * x * y, Syy += w * y * y;
        m++;
    }
    double vx = Sxx - Sx * Sx / S, cxy = Sxy - Sx * Sy / S, vy = Syy - Sy * Sy / S;
    if (m < 2 || !(vx > 1e-12 * Sxx)) return -1;
    *slope = cxy / vx;
    *chi2 = m > 2 ? fmax(vy - cxy * cxy / vx, 0) / (double)(m - 2) : 0;
    return isfinite(*slope) ? 0 : -1;
}

/* The local slope of ln P at every bin (into s): of the windows of TOPO_SLOPE_REACH + 1 bins
 * that hold bin i (i at their left end, centre or right end), the slope of the one that is
 * most straight (least χ² per degree of freedom), so that a bin next to a cutoff or a corner
 * takes its slope from its own side; within [TOPO_SLOPE_MIN, TOPO_SLOPE_MAX]. From the raw
 * bins only: nothing fitted feeds back into it (a slope fitted across a roll-off once ran the
 * correction away, issue 25). */
static void local_slopes(const double *k, const double *P, const double *modes, size_t n, double *s)
{
    const size_t w = 2 * TOPO_SLOPE_REACH;
    for (size_t i = 0; i < n; i++) {
        double best = INFINITY, v = 0, sl, c2;
        for (int side = 0; side < 3; side++) {
            size_t a = side == 0   ? i
                       : side == 1 ? (i >= w / 2 ? i - w / 2 : 0)
                                   : (i >= w ? i - w : 0);
            size_t b = a + w < n ? a + w : n - 1;
            if (b <= a || slope_of(k, P, modes, a, b, &sl, &c2)) continue;
            if (c2 < best) best = c2, v = sl;
        }
        s[i] = fmin(fmax(v, TOPO_SLOPE_MIN), TOPO_SLOPE_MAX);
    }
}

/* The curvature of the spectrum inside a bin: the mean of k^s over the bin's modes is
 * k_g^s <e^{s x}>, x = ln(k/k_g) (k_g the geometric mean), ln <e^{s x}> = s²κ2/2 + s³κ3/6 + ...
 * (the cumulants of ln k). The bin's mean P, divided by that, is the spectrum at k_g: P[b] =
 * P_raw[b] / exp(s²κ2/2 + s³κ3/6), s the bin's local slope (10 bins a decade, slope -3.4: 3 %). */
static void bins_correct(const bins *o, const double *s, double *P, double *P_err)
{
    for (size_t i = 0; i < o->n; i++) {
        double si = s[i];
        double c = exp(-(si * si * o->kap[2 * i] / 2 + si * si * si * o->kap[2 * i + 1] / 6));
        P[i] = o->P[i] * c;
        P_err[i] = o->P_err[i] * c;
    }
}

/* ---- the two transforms ---- */

/* Moments and their variances, summed over the modes. */
typedef struct {
    double m0, m2; /* Σ P Δ, Σ q² P Δ (Δ: Δq² or Δk) */
    double v0, v2; /* Σ over independent modes of the squared terms */
} moments;

static void moments_add(moments *m, double q2, double PD, double mult)
{
    /* mult full modes = mult/2 independent ones, each carrying X = 2 PD, exponential: Var X =
     * (E X)² = E[X²]/2, so X²/2 estimates each one's variance without bias */
    m->m0 += mult * PD;
    m->m2 += mult * q2 * PD;
    m->v0 += 0.25 * mult * (2 * PD) * (2 * PD);
    m->v2 += 0.25 * mult * (2 * q2 * PD) * (2 * q2 * PD);
}

/* The 2-D periodogram of a (ny rows of nx) into the binner and the moments. */
static int map_spectrum(double *a, size_t nx, size_t ny, double dx, double dy, binner *b,
                        moments *mo)
{
    size_t nxc = nx / 2 + 1;
    fftw_complex *c = fftw_alloc_complex(nxc * ny);
    uint16_t *bi = b->cor ? malloc(nxc * ny * sizeof *bi) : NULL;
    fftw_plan p = NULL;
    int st = LJGAP_ENOMEM;
    if (!c || (b->cor && !bi)) goto end;
    if (!(p = fftw_plan_dft_r2c_2d((int)ny, (int)nx, a, c, FFTW_ESTIMATE))) goto end;
    fftw_execute(p);
    double dqx = 2 * M_PI / ((double)nx * dx), dqy = 2 * M_PI / ((double)ny * dy);
    double norm = dx * dy / (4 * M_PI * M_PI * (double)nx * (double)ny), dA = dqx * dqy;
    double kf2 = b->kf * b->kf;
    for (size_t j = 0; j < ny; j++) {
        double qy = dqy * (j <= ny / 2 ? (double)j : (double)j - (double)ny);
        for (size_t i = 0; i < nxc; i++) {
            const double *z = c[j * nxc + i];
            double qx = dqx * (double)i, q2 = qx * qx + qy * qy;
            double P = norm * (z[0] * z[0] + z[1] * z[1]), q = sqrt(q2), x = 0.5 * log(q2 / kf2);
            double mult = (i == 0 || 2 * i == nx) ? 1 : 2; /* i and -i (the other half) */
            uint16_t k = i == 0 && j == 0 ? TOPO_NO_BIN : bin_of(b, q, x);
            if (bi) bi[j * nxc + i] = k;
            if (i == 0 && j == 0) continue;
            moments_add(mo, q2, P * dA, mult);
            binner_add(b, k, x, P, mult);
        }
    }
    if (bi) bin_correlations_map(b, bi, nx, ny);
    st = LJGAP_OK;
end:
    if (p) fftw_destroy_plan(p);
    fftw_free(c);
    free(bi);
    return st;
}

/* The 1-D periodogram of a profile a[0..n) into the binner and the moments. */
static int profile_spectrum(double *a, size_t n, double d, binner *b, moments *mo)
{
    size_t nc = n / 2 + 1;
    fftw_complex *c = fftw_alloc_complex(nc);
    uint16_t *bi = b->cor ? malloc(nc * sizeof *bi) : NULL;
    fftw_plan p = NULL;
    int st = LJGAP_ENOMEM;
    if (!c || (b->cor && !bi)) goto end;
    if (!(p = fftw_plan_dft_r2c_1d((int)n, a, c, FFTW_ESTIMATE))) goto end;
    fftw_execute(p);
    double dk = 2 * M_PI / ((double)n * d), norm = d / (2 * M_PI * (double)n);
    if (bi) bi[0] = TOPO_NO_BIN;
    for (size_t i = 1; i < nc; i++) {
        const double *z = c[i];
        double PP = norm * (z[0] * z[0] + z[1] * z[1]), k = dk * (double)i, x = log(k / b->kf);
        double mult = 2 * i == n ? 1 : 2;
        uint16_t bk = bin_of(b, k, x);
        if (bi) bi[i] = bk;
        moments_add(mo, k * k, PP * dk, mult);
        binner_add(b, bk, x, PP, mult);
    }
    if (bi) bin_correlations_line(b, bi, n);
    st = LJGAP_OK;
end:
    if (p) fftw_destroy_plan(p);
    fftw_free(c);
    free(bi);
    return st;
}

/* ---- the whole computation ---- */

static int check_input(const double *h, const ljgap_topo_grid *g, const ljgap_topo_opts *o,
                       ljgap_warnings *w)
{
    size_t nx = g->nx, ny = g->ny;
    int profile = nx == 1 || ny == 1;
    if (!h || (profile && (nx > 1 ? nx : ny) < LJGAP_TOPO_MIN_SIDE) ||
        (!profile && (nx < LJGAP_TOPO_MIN_SIDE || ny < LJGAP_TOPO_MIN_SIDE))) {
        ljgap_warn(w, "topography: at least %d points a side are needed (got %zu × %zu)",
                   LJGAP_TOPO_MIN_SIDE, nx, ny);
        return LJGAP_EINVAL;
    }
    if (nx > INT32_MAX || ny > INT32_MAX || nx * ny / nx != ny || nx * ny > TOPO_POINTS_MAX) {
        ljgap_warn(w, "topography: %zu × %zu points are more than %zu", nx, ny, TOPO_POINTS_MAX);
        return LJGAP_EINVAL;
    }
    if (!(g->dx > 0) || !isfinite(g->dx) || !(g->dy > 0) || !isfinite(g->dy)) {
        ljgap_warn(w, "topography: the spacings dx, dy must be positive and finite");
        return LJGAP_EINVAL;
    }
    if (!(o->bins_per_decade >= 2 && o->bins_per_decade <= 100) || !(o->fit_kmin >= 0) ||
        !(o->fit_kmax >= 0) || !isfinite(o->fit_kmin) || !isfinite(o->fit_kmax)) {
        ljgap_warn(w, "topography: bins_per_decade in [2, 100] and fit limits >= 0 are needed");
        return LJGAP_EINVAL;
    }
    if (!(o->tip_radius >= 0) || !isfinite(o->tip_radius) || !(o->resolution >= 0) ||
        !isfinite(o->resolution) || o->detrend < LJGAP_DETREND_AUTO ||
        o->detrend > LJGAP_DETREND_CURVATURE ||
        (o->fit_kmin > 0 && o->fit_kmax > 0 && !(o->fit_kmax > o->fit_kmin))) {
        ljgap_warn(w, "topography: tip_radius and resolution >= 0, a known detrend and fit_kmax > "
                      "fit_kmin are needed");
        return LJGAP_EINVAL;
    }
    for (size_t i = 0; i < nx * ny; i++)
        if (!isfinite(h[i])) {
            ljgap_warn(w, "topography: height %zu (row %zu, column %zu) is not finite", i, i / nx,
                       i % nx);
            return LJGAP_EINVAL;
        }
    return LJGAP_OK;
}

/* 2π ∫ k P dk over [x1, x2] of the power law P = Pa (k/ka)^s. */
double ljgap__topo_seg_var(double ka, double Pa, double s, double x1, double x2)
{
    if (!(x2 > x1)) return 0;
    double e = s + 2, a = log(x1 / ka), b = log(x2 / ka), t = e * (b - a);
    double f = fabs(t) < 1e-12 ? b - a : expm1(t) / e;
    return 2 * M_PI * Pa * ka * ka * exp(e * a) * f;
}

/* The 2-D equivalent of a profile's bins: r->P = F(alpha) PP/k (alpha fitted to the PP bins
 * of the band [lo, hi], detected unless fixed), errors with alpha's, the bins' variances
 * 2π ∫ k P dk over their bands with the local slope. */
static int profile_convert(ljgap_topo_result *r, size_t lo, size_t hi, int fix_lo, int fix_hi,
                           ljgap_warnings *w)
{
    ljgap_topo_fit f1;
    if (ljgap__topo_fit_band(r->k, r->PP, r->modes, r->rho, r->lo, 0, lo, hi, fix_lo, fix_hi,
                             &f1) != 0) {
        ljgap_warn(w,
                   "topography: the profile has fewer than 3 bins in the band [%g, %g] to "
                   "fit the exponent that converts it to the isotropic PSD",
                   r->k[lo < r->n ? lo : 0], r->k[hi < r->n ? hi : r->n - 1]);
        return LJGAP_EINVAL;
    }
    /* PP ∝ k^(2 D1 - 8) in the fit's terms: alpha = 8 - 2 D1 */
    r->alpha.value = 8 - 2 * f1.D.value;
    r->alpha.err = 2 * f1.D.err;
    if (!(r->alpha.value > TOPO_ALPHA_MIN) || !isfinite(r->alpha.value)) {
        ljgap_warn(w,
                   "topography: the profile's spectrum goes as k^%.3g; the conversion to an "
                   "isotropic PSD needs a decay faster than k^-%g (a 2-D PSD steeper than k^-1)",
                   -r->alpha.value, TOPO_ALPHA_MIN);
        return LJGAP_EINVAL;
    }
    double F = ljgap_topo_abel_factor(r->alpha.value);
    double eF = fabs(abel_dlog(r->alpha.value)) * r->alpha.err;
    for (size_t i = 0; i < r->n; i++) {
        double rel = r->PP_err[i] / r->PP[i];
        r->P[i] = F * r->PP[i] / r->k[i];
        r->P_err[i] = r->P[i] * sqrt(rel * rel + eF * eF);
        r->slope[i] -= 1; /* of P = F PP / k */
        r->var[i] = ljgap__topo_seg_var(r->k[i], r->P[i], r->slope[i], r->lo[i], r->hi[i]);
    }
    return LJGAP_OK;
}

#define TOPO_TIP_CURV                                                                              \
    0.1                   /* the tip's limit: where the rms curvature at scale λ reaches this     \
                           * fraction of the tip's 1/R (calibrated, docs/topography.md) */
#define TOPO_TIP_STEPS 40 /* wavenumbers a decade searched for the tip's limit */

/* The tip's limit (docs/topography.md, after Sanner et al. 2022): the curvature of the surface
 * at scale λ, the second difference κ_λ = (h(x + λ) - 2h(x) + h(x - λ))/λ² along a direction,
 * has for an isotropic surface the variance
 *     σκ²(λ) = (16/λ⁴) ∫∫ P sin⁴(qx λ/2) d²q = (16/λ⁴) Σ_b var_b g(k_b λ/2),
 *     g(a) = <sin⁴(a cos θ)>_θ = 3/8 - J0(2a)/2 + J0(4a)/8.
 * A tip of radius R follows the surface where the curvature of its valleys stays below 1/R;
 * the data at wavenumber k = π/λ (the second difference's peak) are unreliable from the lowest
 * k at which σκ(π/k) > TOPO_TIP_CURV/R on. INFINITY when that does not happen up to k_nyq. */
static double tip_limit(const ljgap_topo_result *r, double R)
{
    if (!(R > 0) || r->n == 0) return INFINITY;
    double steps = TOPO_TIP_STEPS * log10(r->k_nyq / r->k_fund), lim = TOPO_TIP_CURV / R;
    for (double t = 0; t <= steps + 1e-9; t++) {
        double k = r->k_fund * pow(10, t / TOPO_TIP_STEPS), lam = M_PI / k, s2 = 0;
        for (size_t b = 0; b < r->n; b++) {
            double a = 0.5 * r->k[b] * lam;
            s2 += r->var[b] *
                  (0.375 - 0.5 * gsl_sf_bessel_J0(2 * a) + 0.125 * gsl_sf_bessel_J0(4 * a));
        }
        if (sqrt(16 * s2) / (lam * lam) > lim) return k;
    }
    return INFINITY;
}

/* The reliable band and its bins (r->rel_*). */
static void reliable_band(ljgap_topo_result *r, const ljgap_topo_opts *o)
{
    double kres = o->resolution > 0 ? M_PI / o->resolution : INFINITY;
    r->k_tip = tip_limit(r, o->tip_radius);
    r->rel_kmax = r->k_nyq, r->rel_by = LJGAP_RELIABLE_NYQUIST;
    if (r->k_tip < r->rel_kmax) r->rel_kmax = r->k_tip, r->rel_by = LJGAP_RELIABLE_TIP;
    if (kres < r->rel_kmax) r->rel_kmax = kres, r->rel_by = LJGAP_RELIABLE_RESOLUTION;
    double kmin = r->k_fund * (r->periodic ? 1 : TOPO_FIT_WINDOWED);
    size_t a = 0, b = r->n;
    while (a < r->n && r->k[a] < kmin * (1 - 1e-9))
        a++;
    while (b > 0 && r->k[b - 1] > r->rel_kmax * (1 + 1e-9))
        b--;
    r->rel_first = a;
    r->rel_last = b > 0 ? b - 1 : 0;
    r->rel_kmin = a < r->n ? r->lo[a] : kmin;
}

/* The fit: its band detected inside the reliable bins, or given (either end). */
static int fit_spectrum(ljgap_topo_result *r, const ljgap_topo_opts *o, double var_extra,
                        const double *P, int profile_pp, ljgap_warnings *w)
{
    size_t lo = r->rel_first, hi = r->rel_last;
    int fix_lo = o->fit_kmin > 0, fix_hi = o->fit_kmax > 0;
    if (fix_lo) {
        for (lo = 0; lo < r->n && r->k[lo] < o->fit_kmin * (1 - 1e-9); lo++)
            ;
    }
    if (fix_hi) {
        for (hi = r->n; hi > 0 && r->k[hi - 1] > o->fit_kmax * (1 + 1e-9); hi--)
            ;
        hi = hi > 0 ? hi - 1 : 0;
    }
    if (r->n == 0 || lo >= r->n || hi < lo + 2) return -1;
    if (profile_pp) return profile_convert(r, lo, hi, fix_lo, fix_hi, w) ? -2 : 0;
    return ljgap__topo_fit_band(r->k, P, r->modes, r->rho, r->lo, var_extra, lo, hi, fix_lo, fix_hi,
                                &r->fit);
}

int ljgap_topo_compute(const double *h, const ljgap_topo_grid *g, const ljgap_topo_opts *o,
                       ljgap_topo_result *res, ljgap_warnings *w)
{
    ljgap_topo_opts od;
    binner b = {0};
    bins o1 = {0};
    moments mo = {0};
    double *a = NULL;
    int st;
    if (!res) return LJGAP_EINVAL;
    memset(res, 0, sizeof *res);
    if (!o) ljgap_topo_opts_default(&od), o = &od;
    if (!g || (st = check_input(h, g, o, w))) return LJGAP_EINVAL;
    const size_t nx = g->nx, ny = g->ny, N = nx * ny;
    const int profile = nx == 1 || ny == 1;
    /* a profile runs along its long side: n points, spacing d */
    const size_t n = nx > 1 ? nx : ny;
    const double d = nx > 1 ? g->dx : g->dy;
    res->profile = profile;
    res->periodic = g->periodic != 0;
    res->detrend = o->detrend != LJGAP_DETREND_AUTO ? o->detrend
                   : g->periodic                    ? LJGAP_DETREND_MEAN
                                                    : LJGAP_DETREND_PLANE;
    if (profile && res->detrend == LJGAP_DETREND_LINES) res->detrend = LJGAP_DETREND_PLANE;
    if (profile) {
        res->k_fund = 2 * M_PI / ((double)n * d);
        res->k_nyq = M_PI / d;
    } else {
        res->k_fund = fmin(2 * M_PI / ((double)nx * g->dx), 2 * M_PI / ((double)ny * g->dy));
        res->k_nyq = fmin(M_PI / g->dx, M_PI / g->dy);
    }
    if (!(a = fftw_alloc_real(N))) {
        st = LJGAP_ENOMEM;
        goto end;
    }
    memcpy(a, h, N * sizeof *a);
    double scale = 0;
    size_t same = 1;
    for (size_t i = 0; i < N; i++) {
        scale = fmax(scale, fabs(a[i]));
        same += i > 0 && a[i] == a[0];
    }
    if (same == N) {
        ljgap_warn(w, "topography: all %zu heights are equal (%g): a flat map has no spectrum", N,
                   a[0]);
        st = LJGAP_EINVAL;
        goto end;
    }
    if (profile)
        ljgap__topo_detrend(a, n, 1, res->detrend);
    else
        ljgap__topo_detrend(a, nx, ny, res->detrend);
    double ss = 0;
    for (size_t i = 0; i < N; i++)
        ss += a[i] * a[i];
    res->h_rms.value = sqrt(ss / (double)N);
    if (!(res->h_rms.value > 64 * DBL_EPSILON * scale) || !isfinite(res->h_rms.value)) {
        ljgap_warn(w,
                   "topography: nothing is left after removing the %s: the heights lie on %s "
                   "(to round-off)",
                   ljgap_topo_detrend_name(res->detrend),
                   res->detrend == LJGAP_DETREND_MEAN ? "a constant" : "that");
        st = LJGAP_EINVAL;
        goto end;
    }
    if (!g->periodic) {
        if (profile)
            ljgap__topo_window(a, n, 1);
        else
            ljgap__topo_window(a, nx, ny);
    }
    if ((st = binner_alloc(&b, res->k_fund, res->k_nyq, o->bins_per_decade, !g->periodic)))
        goto end;
    b.line = profile;
    b.cell = profile ? 2 * M_PI / ((double)n * d)
                     : 4 * M_PI * M_PI / ((double)nx * g->dx * (double)ny * g->dy);
    st = profile ? profile_spectrum(a, n, d, &b, &mo)
                 : map_spectrum(a, nx, ny, g->dx, g->dy, &b, &mo);
    if (st) goto end;
    if (o->cancel && *o->cancel) {
        st = LJGAP_ECANCEL;
        goto end;
    }
    const double vif = g->periodic ? 1 : pow(TOPO_HANN_VIF, profile ? 1 : 2);
    if ((st = binner_out(&b, &o1))) goto end;
    res->n = o1.n;
    /* the result owns them now */
    res->k = o1.k, res->modes = o1.modes, res->lo = o1.lo, res->hi = o1.hi, res->var = o1.var;
    res->rho = o1.rho;
    o1.k = o1.modes = o1.lo = o1.hi = o1.var = o1.rho = NULL;
    size_t nn = res->n ? res->n : 1;
    res->P = malloc(nn * sizeof *res->P);
    res->P_err = malloc(nn * sizeof *res->P_err);
    res->slope = malloc(nn * sizeof *res->slope);
    if (profile) {
        res->PP = malloc(nn * sizeof *res->PP);
        res->PP_err = malloc(nn * sizeof *res->PP_err);
    }
    if (!res->P || !res->P_err || !res->slope || (profile && (!res->PP || !res->PP_err))) {
        st = LJGAP_ENOMEM;
        goto end;
    }
    o1.k = res->k, o1.modes = res->modes; /* read below, freed with res */
    local_slopes(res->k, o1.P, res->modes, res->n, res->slope);
    bins_correct(&o1, res->slope, profile ? res->PP : res->P, profile ? res->PP_err : res->P_err);
    int ft;
    if (profile) {
        /* the band for alpha: the reliable band of the PP bins (the tip's limit needs the
         * converted variances: a first conversion over the whole band, then the real one) */
        ljgap_topo_opts o0 = *o;
        o0.tip_radius = 0;
        reliable_band(res, &o0);
        if ((ft = fit_spectrum(res, &o0, 0, res->PP, 1, w)) == -2) {
            st = LJGAP_EINVAL;
            goto end;
        }
        if (o->tip_radius > 0 || o->resolution > 0) {
            reliable_band(res, o);
            local_slopes(res->k, o1.P, res->modes, res->n, res->slope);
            if ((ft = fit_spectrum(res, o, 0, res->PP, 1, w)) == -2) {
                st = LJGAP_EINVAL;
                goto end;
            }
        }
        double eF = fabs(abel_dlog(res->alpha.value)) * res->alpha.err;
        ft = ft == 0 ? fit_spectrum(res, o, eF * eF, res->P, 0, w) : ft;
    } else {
        reliable_band(res, o);
        ft = fit_spectrum(res, o, 0, res->P, 0, w);
    }
    res->has_fit = ft == 0;
    if (!res->has_fit)
        ljgap_warn(w, "topography: fewer than 3 bins lie in the fit band: no power-law fit");
    else if (!res->fit.sound)
        ljgap_warn(w,
                   "topography: %s (D = %.3g, χ²_red = %.3g over k = %g to %g): no power-law "
                   "tail is attached",
                   res->fit.D.value > 2 && res->fit.D.value < 3
                       ? "the spectrum is no power law in any band of the reliable data"
                       : "the fitted fractal dimension lies outside (2, 3)",
                   res->fit.D.value, res->fit.chi2_red, res->fit.kmin, res->fit.kmax);
    if (res->has_fit && res->fit.noise_floor > 0) {
        /* the floor ends the reliable band: above the fit band the bins are mostly noise */
        size_t e = res->rel_first;
        while (e + 1 <= res->rel_last && res->k[e + 1] <= res->fit.kmax * (1 + 1e-9))
            e++;
        if (res->hi[e] < res->rel_kmax)
            res->rel_kmax = res->hi[e], res->rel_last = e, res->rel_by = LJGAP_RELIABLE_NOISE;
    }
    if (res->has_fit && res->fit.noise_floor > 0)
        ljgap_warn(w,
                   "topography: a white-noise floor (P = %.3g) lies above the power law: the "
                   "fit band ends at k = %g, where it reaches %g %% of the law, and the law is "
                   "fitted with the floor subtracted",
                   res->fit.noise_floor, res->fit.kmax, 100 * TOPO_FLOOR_END);
    /* moments: a profile's m2 is <h'²>; an isotropic surface has <|∇h|²> = 2 <h'²> */
    double f2 = profile ? 2 : 1, v = vif;
    res->m0_spectrum = mo.m0;
    res->h_rms.err = sqrt(v * mo.v0) / (2 * res->h_rms.value);
    res->rms_slope.value = sqrt(f2 * mo.m2);
    res->rms_slope.err =
        res->rms_slope.value > 0 ? f2 * sqrt(v * mo.v2) / (2 * res->rms_slope.value) : 0;
    int finite = isfinite(res->h_rms.err) && isfinite(res->rms_slope.value) &&
                 isfinite(res->rms_slope.err) && isfinite(res->m0_spectrum);
    for (size_t i = 0; finite && i < res->n; i++)
        finite = isfinite(res->k[i]) && isfinite(res->P[i]) && isfinite(res->P_err[i]) &&
                 res->P[i] > 0 && isfinite(res->var[i]);
    if (res->has_fit)
        finite = finite && isfinite(res->fit.D.value) && isfinite(res->fit.D.err) &&
                 isfinite(res->fit.C.value) && isfinite(res->fit.C.err) &&
                 isfinite(res->fit.chi2_red) && isfinite(res->fit.corr);
    if (!finite) {
        ljgap_warn(w, "topography: the spectrum is not finite (heights or spacings too extreme "
                      "for double precision)");
        st = LJGAP_EFAIL;
    }
end:
    o1.k = o1.modes = NULL; /* res's */
    bins_free(&o1);
    binner_free(&b);
    fftw_free(a);
    if (st) ljgap_topo_result_free(res);
    return st;
}
