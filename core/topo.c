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

/* ---- detrending and window ---- */

/* Removes what mode says, in place; a is [ny][nx] (a profile: ny = 1). On the centred
 * coordinates x = i - ī, y = j - ȳ the polynomials 1, x, y, x² - <x²>, xy, y² - <y²> are
 * orthogonal over the full grid, so each least-squares coefficient is Σ h φ / Σ φ² on its own
 * (mean: the first; plane: three; curvature: all six; a profile has y = 0 and keeps those of
 * x). lines: each row's own mean and slope along x (AFM scan lines with their offsets and
 * tilts). The sums run in long double, so that a map that is a plane (or constant) leaves only
 * the rounding of its own heights. */
static void detrend(double *a, size_t nx, size_t ny, ljgap_topo_detrend mode)
{
    const long double xc = 0.5L * (long double)(nx - 1), yc = 0.5L * (long double)(ny - 1);
    const long double mx2 = ((long double)nx * nx - 1) / 12, my2 = ((long double)ny * ny - 1) / 12;
    if (mode == LJGAP_DETREND_LINES) {
        for (size_t j = 0; j < ny; j++) {
            double *r = a + j * nx;
            long double s = 0, sx = 0;
            for (size_t i = 0; i < nx; i++)
                s += r[i], sx += r[i] * ((long double)i - xc);
            long double m = s / (long double)nx, bx = mx2 > 0 ? sx / (mx2 * (long double)nx) : 0;
            for (size_t i = 0; i < nx; i++)
                r[i] = (double)(r[i] - (m + bx * ((long double)i - xc)));
        }
        return;
    }
    if (mode != LJGAP_DETREND_CURVATURE) { /* mean or plane: the three sums alone (fast) */
        long double sm = 0, sx = 0, sy = 0, bx = 0, by = 0;
        for (size_t j = 0; j < ny; j++) {
            long double y = (long double)j - yc, r = 0, rx = 0;
            for (size_t i = 0; i < nx; i++) {
                long double h = a[j * nx + i];
                r += h, rx += h * ((long double)i - xc);
            }
            sm += r, sx += rx, sy += r * y;
        }
        long double N = (long double)nx * (long double)ny, mean = sm / N;
        if (mode == LJGAP_DETREND_PLANE) {
            if (mx2 > 0) bx = sx / (mx2 * N);
            if (my2 > 0) by = sy / (my2 * N);
        }
        for (size_t j = 0; j < ny; j++) {
            double off = (double)(mean + by * ((long double)j - yc));
            for (size_t i = 0; i < nx; i++)
                a[j * nx + i] = (double)(a[j * nx + i] - (off + bx * ((long double)i - xc)));
        }
        return;
    }
    const int np = 6;
    long double num[6] = {0}, den[6] = {0}, c[6] = {0}, phi[6];
    for (int pass = 0; pass < 2; pass++)
        for (size_t j = 0; j < ny; j++) {
            long double y = (long double)j - yc;
            for (size_t i = 0; i < nx; i++) {
                long double x = (long double)i - xc, h = a[j * nx + i], fit = 0;
                phi[0] = 1, phi[1] = x, phi[2] = y;
                phi[3] = x * x - mx2, phi[4] = x * y, phi[5] = y * y - my2;
                for (int p = 0; p < np; p++) {
                    if (pass == 0)
                        num[p] += h * phi[p], den[p] += phi[p] * phi[p];
                    else
                        fit += c[p] * phi[p];
                }
                if (pass == 1) a[j * nx + i] = (double)(h - fit);
            }
            if (pass == 0 && j + 1 == ny)
                for (int p = 0; p < np; p++)
                    c[p] = den[p] > 0 ? num[p] / den[p] : 0;
        }
}

const char *ljgap_topo_detrend_name(ljgap_topo_detrend d)
{
    switch (d) {
    case LJGAP_DETREND_MEAN:
        return "mean";
    case LJGAP_DETREND_PLANE:
        return "plane";
    case LJGAP_DETREND_LINES:
        return "lines";
    case LJGAP_DETREND_CURVATURE:
        return "curvature";
    default:
        return "auto";
    }
}

int ljgap_topo_detrend_parse(const char *name)
{
    for (int d = LJGAP_DETREND_MEAN; d <= LJGAP_DETREND_CURVATURE; d++)
        if (name && strcmp(name, ljgap_topo_detrend_name((ljgap_topo_detrend)d)) == 0) return d;
    return -1;
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
/* a windowed map's bins correlate with the next TOPO_LAGS bins (the window's ±2 modes reach
 * further over narrow low bins, but 3 lags changed the errors of D by 0.1 % and looked to slow
 * the core on a 2048² map by up to a third, measured at load 7: noisy) */
#define TOPO_LAGS 1

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

#define TOPO_SLOPE_MIN -10.0 /* bounds of the local slope the curvature correction uses */
#define TOPO_SLOPE_MAX 2.0
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

/* ---- the fit ---- */

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

#define TOPO_FLOOR_END 0.2 /* with a floor, the band ends where it reaches 20 % of the law */
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
static int fit_band(const double *k, const double *P, const double *modes, const double *rho,
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
static double seg_var(double ka, double Pa, double s, double x1, double x2)
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
    if (fit_band(r->k, r->PP, r->modes, r->rho, r->lo, 0, lo, hi, fix_lo, fix_hi, &f1) != 0) {
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
        r->slope[i] -= 1; /* of P = F PP / k */
        r->var[i] = seg_var(r->k[i], r->P[i], r->slope[i], r->lo[i], r->hi[i]);
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
    return fit_band(r->k, P, r->modes, r->rho, r->lo, var_extra, lo, hi, fix_lo, fix_hi, &r->fit);
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
        detrend(a, n, 1, res->detrend);
    else
        detrend(a, nx, ny, res->detrend);
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
            window(a, n, 1);
        else
            window(a, nx, ny);
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

/* ---- the psd object's table ---- */

void ljgap_topo_tab_free(ljgap_topo_tab *t)
{
    if (!t) return;
    free(t->k);
    free(t->P);
    free(t->P_err);
    free(t->corr);
    memset(t, 0, sizeof *t);
}

/* 2π ∫ k P dk over [x1, x2] of the table's log-log interpolation (knots K, log values V). */
static double tab_int(const double *K, const double *V, size_t m, double x1, double x2)
{
    double sum = 0;
    for (size_t j = 0; j + 1 < m; j++) {
        double a = fmax(x1, K[j]), b = fmin(x2, K[j + 1]);
        if (!(b > a)) continue;
        double s = (V[j + 1] - V[j]) / log(K[j + 1] / K[j]);
        sum += seg_var(K[j], exp(V[j]), s, a, b);
    }
    return sum;
}

/* The knots' errors: the values solve g_b(V) = ln ∫_b (the table) − ln S_b = 0, so a change
 * δ ln S of the bins' sums moves the free values by δV = J⁻¹ δ ln S, J_bc = ∂ ln ∫_b / ∂V_c
 * (numerical, the edge knots tied to their neighbours as in the solve). The bins' relative
 * errors are independent: cov V = J⁻¹ diag(P_err/P)² J⁻ᵀ. rel[j] receives the knot's relative
 * error √cov_jj, corr[j] the correlation of knots j and j + 1 (0 for the last). The solve is a
 * deconvolution of the interpolation's overlap between neighbouring bins, which amplifies
 * alternating noise: the bins' own relative errors understate the knots' (issue 29). 0, or -1
 * out of memory. */
static int tab_errors(const ljgap_topo_result *r, size_t first, const double *K, const double *V0,
                      size_t mm, size_t idx0, size_t nb, int lead, int trail, double s_end,
                      const double *blo, const double *bhi, double *rel, double *corr)
{
    int st = -1;
    double *V = malloc(mm * sizeof *V), *g0 = malloc(nb * sizeof *g0);
    gsl_matrix *J = gsl_matrix_alloc(nb, nb), *X = gsl_matrix_calloc(nb, nb);
    gsl_permutation *perm = gsl_permutation_alloc(nb);
    if (!V || !g0 || !J || !X || !perm) goto out;
    memcpy(V, V0, mm * sizeof *V);
    for (size_t b = 0; b < nb; b++)
        g0[b] = log(tab_int(K, V, mm, blo[b], bhi[b]));
    const double h = 1e-6;
    for (size_t c = 0; c < nb; c++) {
        V[idx0 + c] += h;
        if (lead) V[0] = V[1];
        if (trail) V[mm - 1] = V[mm - 2] + s_end * log(K[mm - 1] / K[mm - 2]);
        for (size_t b = 0; b < nb; b++)
            gsl_matrix_set(J, b, c, (log(tab_int(K, V, mm, blo[b], bhi[b])) - g0[b]) / h);
        memcpy(V, V0, mm * sizeof *V);
    }
    /* X = J⁻¹ diag(rel_b): column b solves J x = rel_b e_b */
    int sgn;
    if (gsl_linalg_LU_decomp(J, perm, &sgn)) goto out;
    for (size_t b = 0; b < nb; b++) {
        gsl_vector_view col = gsl_matrix_column(X, b);
        gsl_vector_set(&col.vector, b, r->P_err[first + b] / r->P[first + b]);
        if (gsl_linalg_LU_svx(J, perm, &col.vector)) goto out;
    }
    /* the knot j's row of X (the edge knots: their neighbour's) */
    for (size_t j = 0; j < mm; j++) {
        size_t a = j < idx0 ? 0 : j - idx0 >= nb ? nb - 1 : j - idx0;
        size_t a2 = j + 1 < idx0 ? 0 : j + 1 - idx0 >= nb ? nb - 1 : j + 1 - idx0;
        double vaa = 0, vbb = 0, vab = 0;
        for (size_t b = 0; b < nb; b++) {
            double x = gsl_matrix_get(X, a, b), y = gsl_matrix_get(X, a2, b);
            vaa += x * x, vbb += y * y, vab += x * y;
        }
        rel[j] = sqrt(vaa);
        corr[j] = j + 1 < mm && vaa > 0 && vbb > 0 ? vab / sqrt(vaa * vbb) : 0;
        if (!(rel[j] > 0) || !isfinite(rel[j])) /* a singular solve: the bin's own */
            rel[j] = r->P_err[first + a] / r->P[first + a], corr[j] = 0;
    }
    st = 0;
out:
    free(V);
    free(g0);
    gsl_matrix_free(J);
    gsl_matrix_free(X);
    gsl_permutation_free(perm);
    return st;
}

#define TOPO_TAB_ITER                                                                              \
    500 /* iterations of the table's values (each divides the misfit by 2 or more) */

int ljgap_topo_table(const ljgap_topo_result *r, double k_from, double tail_q, ljgap_topo_tab *t)
{
    memset(t, 0, sizeof *t);
    if (!r || r->n == 0 || r->rel_last < r->rel_first || r->rel_last >= r->n) return LJGAP_EINVAL;
    size_t first = r->rel_first, last = r->rel_last;
    while (first <= last && r->hi[first] <= k_from * (1 + 1e-12))
        first++;
    if (first > last) return LJGAP_EINVAL;
    const size_t nb = last - first + 1;
    double lo0 = fmax(r->lo[first], k_from), hiN = fmin(r->hi[last], r->rel_kmax);
    if (!(hiN > lo0)) return LJGAP_EINVAL;
    /* knots: [lo0,] c_first ... c_last [, hiN]; c_b the bin's k inside its band */
    size_t m = nb + 2, lead, idx0;
    double *K = malloc(m * sizeof *K), *V = malloc(m * sizeof *V), *S = malloc(nb * sizeof *S);
    double *blo = calloc(nb, sizeof *blo), *bhi = calloc(nb, sizeof *bhi);
    double *dv = malloc(nb * sizeof *dv);
    int st = LJGAP_ENOMEM;
    if (!K || !V || !S || !blo || !bhi || !dv) goto end;
    for (size_t b = 0; b < nb; b++) {
        size_t i = first + b;
        blo[b] = b == 0 ? lo0 : r->lo[i];
        bhi[b] = b + 1 == nb ? hiN : r->hi[i];
        S[b] = r->var[i];
        if (b == 0 && lo0 > r->lo[i]) /* the share of the bin above k_from, by its local slope */
            S[b] *= seg_var(r->k[i], 1, r->slope[i], lo0, r->hi[i]) /
                    seg_var(r->k[i], 1, r->slope[i], r->lo[i], r->hi[i]);
    }
    double c0 = fmin(fmax(r->k[first], blo[0]), bhi[0]);
    lead = lo0 < c0 * (1 - 1e-12);
    idx0 = lead;
    if (lead) K[0] = lo0;
    for (size_t b = 0; b < nb; b++) {
        double c = fmin(fmax(r->k[first + b], blo[b]), bhi[b]);
        if (idx0 + b > 0 && !(c > K[idx0 + b - 1])) c = K[idx0 + b - 1] * (1 + 1e-9);
        K[idx0 + b] = c;
        V[idx0 + b] = log(r->P[first + b]);
    }
    size_t mm = idx0 + nb;
    int trail = hiN > K[mm - 1] * (1 + 1e-12);
    double s_end = isfinite(tail_q) ? tail_q : fmin(fmax(r->slope[last], TOPO_SLOPE_MIN), 0);
    if (trail) K[mm++] = hiN;
    if (mm < 2) {
        st = LJGAP_EINVAL;
        goto end;
    }
    for (int it = 0; it < TOPO_TAB_ITER; it++) {
        double worst = 0;
        if (lead) V[0] = V[1];
        if (trail) V[mm - 1] = V[mm - 2] + s_end * log(K[mm - 1] / K[mm - 2]);
        for (size_t b = 0; b < nb; b++) { /* Jacobi: every bin from the same values */
            double I = tab_int(K, V, mm, blo[b], bhi[b]);
            dv[b] = S[b] > 0 && I > 0 ? log(S[b] / I) : 0;
            worst = fmax(worst, fabs(dv[b]));
        }
        for (size_t b = 0; b < nb; b++)
            V[idx0 + b] += dv[b];
        if (worst < 1e-12) break;
    }
    if (lead) V[0] = V[1];
    if (trail) V[mm - 1] = V[mm - 2] + s_end * log(K[mm - 1] / K[mm - 2]);
    t->k = malloc(mm * sizeof *t->k);
    t->P = malloc(mm * sizeof *t->P);
    t->P_err = malloc(mm * sizeof *t->P_err);
    t->corr = calloc(mm, sizeof *t->corr);
    if (!t->k || !t->P || !t->P_err || !t->corr) goto end;
    for (size_t j = 0; j < mm; j++) {
        t->k[j] = K[j];
        t->P[j] = exp(V[j]);
    }
    if (tab_errors(r, first, K, V, mm, idx0, nb, lead, trail, s_end, blo, bhi, t->P_err, t->corr))
        goto end;
    for (size_t j = 0; j < mm; j++)
        t->P_err[j] *= t->P[j];
    t->n = mm;
    t->m0 = tab_int(K, V, mm, K[0], K[mm - 1]);
    t->m0_modes = 0;
    for (size_t b = 0; b < nb; b++)
        t->m0_modes += S[b];
    st = LJGAP_OK;
end:
    free(K);
    free(V);
    free(S);
    free(blo);
    free(bhi);
    free(dv);
    if (st) ljgap_topo_tab_free(t);
    return st;
}
