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

#include <fftw3.h>
#include <float.h>
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
    o->cancel = NULL;
}

void ljgap_topo_result_free(ljgap_topo_result *res)
{
    if (!res) return;
    free(res->k);
    free(res->P);
    free(res->P_err);
    free(res->modes);
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

/* ---- detrending and window ---- */

/* Removes the mean (periodic) or the least-squares plane, in place; a is [ny][nx]. On the
 * centred coordinates the normal equations are diagonal: b = Σ h (i - ī) / Σ (i - ī)². The
 * sums run in long double, so that a map that is a plane (or constant) leaves only the rounding
 * of its own heights. */
static void detrend(double *a, size_t nx, size_t ny, int plane)
{
    size_t N = nx * ny;
    long double s = 0, sx = 0, sy = 0, xc = 0.5L * (long double)(nx - 1);
    long double yc = 0.5L * (long double)(ny - 1), bx = 0, by = 0;
    for (size_t j = 0; j < ny; j++)
        for (size_t i = 0; i < nx; i++) {
            long double h = a[j * nx + i];
            s += h;
            sx += h * ((long double)i - xc);
            sy += h * ((long double)j - yc);
        }
    long double mean = s / (long double)N;
    if (plane) {
        /* Σ over the map of (i - ī)² = ny · nx (nx² - 1)/12 */
        long double vx = (long double)ny * nx * ((long double)nx * nx - 1) / 12;
        long double vy = (long double)nx * ny * ((long double)ny * ny - 1) / 12;
        if (vx > 0) bx = sx / vx;
        if (vy > 0) by = sy / vy;
    }
    for (size_t j = 0; j < ny; j++)
        for (size_t i = 0; i < nx; i++)
            a[j * nx + i] = (double)(a[j * nx + i] - (mean + bx * ((long double)i - xc) +
                                                      by * ((long double)j - yc)));
}

/* The periodic Hann window of length n at i, w = (1 - cos(2πi/n))/2 (1 when n == 1). */
static double hann(size_t i, size_t n)
{
    return n > 1 ? 0.5 * (1 - cos(2 * M_PI * (double)i / (double)n)) : 1.0;
}

/* Multiplies a by w(i)w(j) / rms(w ⊗ w). */
static void window(double *a, size_t nx, size_t ny)
{
    double *wx = malloc(nx * sizeof *wx), *wy = malloc(ny * sizeof *wy), sx = 0, sy = 0;
    if (!wx || !wy) { /* small; fall back to computing in place */
        free(wx);
        free(wy);
        wx = wy = NULL;
    }
    for (size_t i = 0; i < nx; i++) {
        double w = hann(i, nx);
        sx += w * w;
        if (wx) wx[i] = w;
    }
    for (size_t j = 0; j < ny; j++) {
        double w = hann(j, ny);
        sy += w * w;
        if (wy) wy[j] = w;
    }
    double norm = 1 / sqrt(sx / (double)nx * sy / (double)ny);
    for (size_t j = 0; j < ny; j++) {
        double w = (wy ? wy[j] : hann(j, ny)) * norm;
        for (size_t i = 0; i < nx; i++)
            a[j * nx + i] *= w * (wx ? wx[i] : hann(i, nx));
    }
    free(wx);
    free(wy);
}

/* ---- bins ---- */

#define TOPO_NO_BIN UINT16_MAX

/* Sums per logarithmic bin while the modes are visited. */
typedef struct {
    size_t nb;   /* bins allocated (< TOPO_NO_BIN) */
    double kf;   /* fundamental: the bins' origin */
    double knyq; /* last |q| binned */
    double B;    /* bins per decade */
    double *cnt; /* modes (full plane or full line) */
    double *sl;  /* Σ ln(|q|/kf), Σ ln², Σ ln³: 3 a bin */
    double *sP;  /* Σ periodogram */
    double *cor; /* windowed: Σ over the bin's modes of the in-bin correlation sum (see
                  * bin_correlations); NULL unwindowed (each mode correlates with itself only) */
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
    return b->cnt && b->sl && b->sP && (b->cor || !windowed) && b->nb < TOPO_NO_BIN ? LJGAP_OK
                                                                                    : LJGAP_ENOMEM;
}

static void binner_free(binner *b)
{
    free(b->cnt);
    free(b->sl);
    free(b->sP);
    free(b->cor);
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
            double sum = 0, mult = (i == 0 || 2 * i == nx) ? 1 : 2;
            if (j >= 2 && j + 2 < ny && i >= 2 && i + 2 < nxc) { /* inside: no wrapping */
                const uint16_t *r = bi + (j - 2) * nxc + (i - 2);
                for (int c = 0; c < 5; c++, r += nxc)
                    for (int a = 0; a < 5; a++)
                        sum += r[a] == me ? w[c][a] : 0;
            } else {
                for (long c = -2; c <= 2; c++)
                    for (long a = -2; a <= 2; a++) {
                        long ii = (long)i + a, jj = (long)j + c;
                        if (ii < 0 || ii > (long)nx / 2) { /* the conjugate: -q */
                            ii = ii < 0 ? -ii : (long)nx - ii;
                            jj = -jj;
                        }
                        jj = ((jj % (long)ny) + (long)ny) % (long)ny;
                        if (bi[(size_t)jj * nxc + (size_t)ii] == me) sum += w[c + 2][a + 2];
                    }
            }
            b->cor[me] += mult * sum;
        }
}

/* The same along a profile (bins in bi[0..nc)). */
static void bin_correlations_line(binner *b, const uint16_t *bi, size_t n)
{
    size_t nc = n / 2 + 1;
    for (size_t i = 1; i < nc; i++) {
        uint16_t me = bi[i];
        if (me == TOPO_NO_BIN) continue;
        double sum = 0, mult = 2 * i == n ? 1 : 2;
        for (long a = -2; a <= 2; a++) {
            long ii = (long)i + a;
            if (ii < 0) ii = -ii;
            if (ii > (long)n / 2) ii = (long)n - ii;
            if (ii > 0 && bi[ii] == me) sum += hann_rho2[labs(a)];
        }
        b->cor[me] += mult * sum;
    }
}

/* The binned spectrum before its curvature correction. */
typedef struct {
    size_t n;              /* non-empty bins */
    double *k, *P, *P_err; /* geometric mean |q|, mean periodogram, its standard error */
    double *modes;         /* independent modes (window-corrected) */
    double *kap;           /* 2 a bin: the variance and third cumulant of ln |q| over the modes */
} bins;

static void bins_free(bins *o)
{
    free(o->k);
    free(o->P);
    free(o->P_err);
    free(o->modes);
    free(o->kap);
    memset(o, 0, sizeof *o);
}

/* The non-empty bins into o. A bin of cnt modes has cnt/2 independent ones unwindowed,
 * (cnt/2) · cnt/cor windowed (eff); E[P̄²] = P²(1 + 1/eff), so P̄/√(eff + 1) estimates the
 * standard error P/√eff without bias. */
static int binner_out(const binner *b, bins *o)
{
    size_t m = 0;
    for (size_t i = 0; i < b->nb; i++)
        m += b->cnt[i] > 0;
    memset(o, 0, sizeof *o);
    o->k = malloc((m ? m : 1) * sizeof *o->k);
    o->P = malloc((m ? m : 1) * sizeof *o->P);
    o->P_err = malloc((m ? m : 1) * sizeof *o->P_err);
    o->modes = malloc((m ? m : 1) * sizeof *o->modes);
    o->kap = malloc((m ? m : 1) * 2 * sizeof *o->kap);
    if (!o->k || !o->P || !o->P_err || !o->modes || !o->kap) return LJGAP_ENOMEM;
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
        o->n++;
    }
    return LJGAP_OK;
}

/* The curvature of a power law k^s inside a bin: the mean of k^s over the bin's modes is
 * k_g^s <e^{s x}>, x = ln(k/k_g) (k_g the geometric mean), ln <e^{s x}> = s²κ2/2 + s³κ3/6 + ...
 * (the cumulants of ln k). The bin's mean P, divided by that, is the law at k_g: P_true[b] =
 * P_raw[b] / exp(s²κ2/2 + s³κ3/6), with s the fitted slope (10 bins a decade, slope -3.4: 3 %). */
static void bins_correct(const bins *o, double s, double *P, double *P_err)
{
    for (size_t i = 0; i < o->n; i++) {
        double c = exp(-(s * s * o->kap[2 * i] / 2 + s * s * s * o->kap[2 * i + 1] / 6));
        P[i] = o->P[i] * c;
        P_err[i] = o->P_err[i] * c;
    }
}

/* ---- the fit ---- */

/* Weighted least squares of ln P on ln k over the bins with k in [kmin, kmax]. A bin's mean of
 * N independent exponential periodograms is Gamma-distributed: E[ln P̄] = ln P + ψ(N) - ln N
 * and Var[ln P̄] = ψ'(N) (ψ the digamma function). So each bin enters as ln P̄ - ψ(N) + ln N with
 * weight 1/(ψ'(N) + var_extra) (var_extra: a variance common to every bin, the profile
 * conversion's): without that shift the few-mode bins at low k sit low by up to γ = 0.58 in
 * ln P and tilt the slope. f filled and 0, or -1 when fewer than 3 usable bins. */
static int fit_power(const double *k, const double *P, const double *modes, double var_extra,
                     size_t n, double kmin, double kmax, ljgap_topo_fit *f)
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
    return 0;
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
    for (size_t i = 0; i < nx * ny; i++)
        if (!isfinite(h[i])) {
            ljgap_warn(w, "topography: height %zu (row %zu, column %zu) is not finite", i, i / nx,
                       i % nx);
            return LJGAP_EINVAL;
        }
    return LJGAP_OK;
}

/* The fit of the bins o with their curvature correction: fit the raw bins, correct them with
 * the fitted slope, fit again (twice: the correction moves the slope by about 1e-3). P and
 * P_err (o->n each) receive the corrected bins, or the raw ones when there is no fit (-1). */
static int fit_corrected(const bins *o, double *P, double *P_err, double kmin, double kmax,
                         ljgap_topo_fit *f)
{
    memcpy(P, o->P, o->n * sizeof *P);
    memcpy(P_err, o->P_err, o->n * sizeof *P_err);
    if (fit_power(o->k, P, o->modes, 0, o->n, kmin, kmax, f)) return -1;
    for (int it = 0; it < 2; it++) {
        bins_correct(o, 2 * f->D.value - 8, P, P_err);
        if (fit_power(o->k, P, o->modes, 0, o->n, kmin, kmax, f)) return -1;
    }
    return 0;
}

/* Profile: the 1-D bins (corrected, in r->PP) and their exponent alpha, then the isotropic PSD
 * F(alpha) PP/k in r->P. */
static int profile_convert(const bins *o, ljgap_topo_result *r, double kmin, double kmax,
                           ljgap_warnings *w)
{
    ljgap_topo_fit f1;
    if (fit_corrected(o, r->PP, r->PP_err, kmin, kmax, &f1) != 0) {
        ljgap_warn(w,
                   "topography: the profile has fewer than 3 bins in the band [%g, %g] to "
                   "fit the exponent that converts it to the isotropic PSD",
                   kmin, kmax);
        return LJGAP_EINVAL;
    }
    /* PP ∝ k^(2 D1 - 8) in the fit's terms: alpha = 8 - 2 D1 */
    r->alpha.value = 8 - 2 * f1.D.value;
    r->alpha.err = 2 * f1.D.err;
    if (!(r->alpha.value > TOPO_ALPHA_MIN) || !isfinite(r->alpha.value)) {
        ljgap_warn(w,
                   "topography: the profile's spectrum falls as k^-%.3g; the conversion to an "
                   "isotropic PSD needs a decay faster than k^-%g (a 2-D PSD steeper than k^-1)",
                   r->alpha.value, TOPO_ALPHA_MIN);
        return LJGAP_EINVAL;
    }
    double F = ljgap_topo_abel_factor(r->alpha.value);
    double eF = fabs(abel_dlog(r->alpha.value)) * r->alpha.err;
    for (size_t i = 0; i < r->n; i++) {
        double rel = r->PP_err[i] / r->PP[i];
        r->P[i] = F * r->PP[i] / r->k[i];
        r->P_err[i] = r->P[i] * sqrt(rel * rel + eF * eF);
    }
    return LJGAP_OK;
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
        detrend(a, n, 1, !g->periodic);
    else
        detrend(a, nx, ny, !g->periodic);
    double ss = 0;
    for (size_t i = 0; i < N; i++)
        ss += a[i] * a[i];
    res->h_rms.value = sqrt(ss / (double)N);
    if (!(res->h_rms.value > 64 * DBL_EPSILON * scale) || !isfinite(res->h_rms.value)) {
        ljgap_warn(w, "topography: nothing is left after removing the mean and the plane: the "
                      "heights lie on a plane (to round-off)");
        st = LJGAP_EINVAL;
        goto end;
    }
    if (!g->periodic) {
        if (profile)
            window(a, n, 1);
        else
            window(a, nx, ny);
    }
    if ((st = binner_alloc(&b, res->k_fund, res->k_nyq, o->bins_per_decade, !g->periodic)))
        goto end;
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
    res->k = o1.k, res->modes = o1.modes; /* the result owns them now */
    o1.k = o1.modes = NULL;
    res->P = malloc((res->n ? res->n : 1) * sizeof *res->P);
    res->P_err = malloc((res->n ? res->n : 1) * sizeof *res->P_err);
    if (profile) {
        res->PP = malloc((res->n ? res->n : 1) * sizeof *res->PP);
        res->PP_err = malloc((res->n ? res->n : 1) * sizeof *res->PP_err);
    }
    if (!res->P || !res->P_err || (profile && (!res->PP || !res->PP_err))) {
        st = LJGAP_ENOMEM;
        goto end;
    }
    o1.k = res->k, o1.modes = res->modes; /* read below, freed with res */
    double kmin =
        o->fit_kmin > 0 ? o->fit_kmin : res->k_fund * (g->periodic ? 1 : TOPO_FIT_WINDOWED);
    double kmax = o->fit_kmax > 0 ? o->fit_kmax : res->k_nyq;
    if (profile) {
        if ((st = profile_convert(&o1, res, kmin, kmax, w))) goto end;
        double eF = fabs(abel_dlog(res->alpha.value)) * res->alpha.err;
        res->has_fit =
            fit_power(res->k, res->P, res->modes, eF * eF, res->n, kmin, kmax, &res->fit) == 0;
    } else {
        res->has_fit = fit_corrected(&o1, res->P, res->P_err, kmin, kmax, &res->fit) == 0;
    }
    if (!res->has_fit)
        ljgap_warn(w,
                   "topography: fewer than 3 bins lie in the fit band [%g, %g]: no power-law fit",
                   kmin, kmax);
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
        finite =
            isfinite(res->k[i]) && isfinite(res->P[i]) && isfinite(res->P_err[i]) && res->P[i] > 0;
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

int ljgap_topo_table(const ljgap_topo_result *r, double k_from, double **k, double **P, size_t *n)
{
    size_t first = 0, m;
    *k = *P = NULL;
    *n = 0;
    while (first < r->n && r->k[first] <= k_from)
        first++;
    int lead = first > 0 && first < r->n; /* k_from inside the band: interpolate there */
    m = r->n - first + (size_t)lead;
    if (m < 2) return LJGAP_EINVAL;
    *k = malloc(m * sizeof **k);
    *P = malloc(m * sizeof **P);
    if (!*k || !*P) {
        free(*k);
        free(*P);
        *k = *P = NULL;
        return LJGAP_ENOMEM;
    }
    if (lead) {
        size_t i = first - 1;
        double t = log(k_from / r->k[i]) / log(r->k[i + 1] / r->k[i]);
        (*k)[0] = k_from;
        (*P)[0] = exp(log(r->P[i]) + t * log(r->P[i + 1] / r->P[i]));
        if (r->k[i] == k_from) (*P)[0] = r->P[i];
    }
    memcpy(*k + lead, r->k + first, (r->n - first) * sizeof **k);
    memcpy(*P + lead, r->P + first, (r->n - first) * sizeof **P);
    *n = m;
    return LJGAP_OK;
}
