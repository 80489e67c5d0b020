/* ljgap_topo.h -- from a measured height map to the isotropic PSD of the project (issue 15).
 *
 * Convention (the paper's (22), theory.md §1): wavenumbers k are ANGULAR (2π/λ) and the
 * isotropic 2-D PSD P(k) is normalised so that
 *     ∫∫ P(|k|) d²k = 2π ∫ k P(k) dk = h_rms²
 * (Persson's C(q)). A profile's 1-D PSD PP(k) is two-sided, 2 ∫_0^∞ PP dk = h_rms² (the
 * paper's PP of (22)). Lengths are in any one unit (the server uses metres): k comes out in
 * 1/unit, P in unit⁴, PP in unit³.
 *
 * ljgap_topo_compute takes an nx × ny map (row j, column i at h[j*nx + i]; a row runs along x
 * with spacing dx), removes its mean (periodic) or its least-squares plane and applies a 2-D
 * Hann window with its variance correction (non-periodic), takes the FFT (FFTW3), averages the
 * periodogram over logarithmic bins of |k|, and fits a power law P = C k^(2D-8) to the bins.
 * A map with one row (or one column) is a profile: its 1-D PSD is turned into the isotropic one
 * by the power-law form of the inverse Abel transform (core/topo/topo.c explains and the tests check
 * it on the rows of a synthetic isotropic surface). Every number has an error estimate.
 *
 * Knows nothing of JSON, HTTP or materials; returns a status like every core call.
 */
#ifndef LJGAP_TOPO_H
#define LJGAP_TOPO_H

#include "ljgap.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LJGAP_TOPO_MIN_SIDE 16 /* points a side (a profile: along its one side) */

/* The sampled map. */
typedef struct {
    size_t nx;    /* points along x: the length of a row */
    size_t ny;    /* rows (points along y); nx or ny equal to 1 makes a profile */
    double dx;    /* spacing along x, > 0 */
    double dy;    /* spacing along y, > 0 (not used by a profile along x) */
    int periodic; /* 1: one period of a periodic surface: mean removed, no plane, no window */
} ljgap_topo_grid;

/* What is removed from the map before its transform. */
typedef enum {
    LJGAP_DETREND_AUTO = 0, /* mean for a periodic map, plane for a non-periodic one */
    LJGAP_DETREND_MEAN,     /* the mean only */
    LJGAP_DETREND_PLANE,    /* the least-squares plane (a line for a profile) */
    LJGAP_DETREND_LINES,    /* each row's (scan line's) own least-squares line */
    LJGAP_DETREND_CURVATURE /* the least-squares quadratic surface (parabola for a profile) */
} ljgap_topo_detrend;

/* What limits the reliable band from above. */
typedef enum {
    LJGAP_RELIABLE_NYQUIST = 0,
    LJGAP_RELIABLE_TIP,
    LJGAP_RELIABLE_RESOLUTION,
    LJGAP_RELIABLE_NOISE /* a white-noise floor: the band ends with the fit's (the floor at 20 %
                          * of the law) */
} ljgap_topo_by;

typedef struct {
    double bins_per_decade;     /* logarithmic bins of |k| per decade (10), in [2, 100] */
    double fit_kmin;            /* lowest bin k fitted; 0: detected (the power-law band) */
    double fit_kmax;            /* highest bin k fitted; 0: detected */
    ljgap_topo_detrend detrend; /* LJGAP_DETREND_AUTO by default */
    double tip_radius;          /* radius of the probe's tip (length unit); 0: not known */
    double resolution;          /* lateral resolution of the instrument; 0: not known */
    const volatile int *cancel; /* optional: LJGAP_ECANCEL when *cancel becomes nonzero */
} ljgap_topo_opts;

void ljgap_topo_opts_default(ljgap_topo_opts *o);

/* The power-law fit P = C k^(2D-8) (weighted least squares of ln P on ln k). */
typedef struct {
    ljgap_est D; /* fractal dimension (H = 3 - D); the exponent of P is 2D - 8 */
    ljgap_est C; /* prefactor, unit^(2D-4); strongly correlated with D unless k ~ 1 */
    double corr; /* correlation coefficient of the estimates of ln C and D */
    double kmin; /* the band fitted: first and last bin k used */
    double kmax;
    size_t bins;        /* bins used (>= 3) */
    double chi2_red;    /* χ² per degree of freedom against the bins' errors; the errors of D
                         * and C are scaled up by √chi2_red when it exceeds 1 (misfit) */
    int given;          /* 1: the band (or one of its ends) was given in the options */
    int sound;          /* 1: the bins in the band are a power law (χ²_red and curvature within
                         * their statistical bounds) and 2 < D < 3; 0: a warning says why not */
    double noise_floor; /* a white floor N (unit⁴) found above the band, P = C k^(2D-8) + N
                         * fitted with it (core/topo/topo.c: fit_floor); 0: none */
    double noise_floor_err; /* its standard error (the χ² profile's Δχ² = max(χ²_red, 1)) */
    double rolloff; /* the knee k_r (unit⁻¹) of a roll-off found below the band, P = C max(k,
                     * k_r)^(2D-8) (core/topo/topo.c: fit_knee; the band starts clear of it); 0: none */
} ljgap_topo_fit;

typedef struct {
    size_t n;      /* non-empty bins, increasing k */
    double *k;     /* owned: mean |k| of the bin's modes */
    double *P;     /* owned: isotropic 2-D PSD (mean periodogram of the bin) */
    double *P_err; /* owned: standard error of P (see core/topo/topo.c: modes and window) */
    double *modes; /* owned: independent modes behind each bin (window-corrected) */
    double *lo;    /* owned: lower edge of the band the bin's modes cover (the lattice's count
                    * of cells: π lo² = cells below the bin, a profile 2 lo = cells × Δk) */
    double *hi;    /* owned: its upper edge (the next bin's lo) */
    double *var;   /* owned: the variance the bin's modes carry, Σ P Δq² (a profile: its 2-D
                    * equivalent 2π ∫ k P dk of the converted bin over [lo, hi]) */
    double *slope; /* owned: the local slope d ln P / d ln k the bin's curvature correction used */
    double *rho;   /* owned: the correlation of the bin's P with the next bin's (a windowed map's
                    * neighbouring modes are correlated; 0 unwindowed); the fit's errors use it */
    /* profiles only (NULL for a map): the 1-D PSD PP the bins were converted from */
    double *PP;      /* owned: mean two-sided 1-D periodogram of the bin */
    double *PP_err;  /* owned: its standard error */
    ljgap_est alpha; /* profile: PP ∝ k^-alpha, fitted (the exponent of the conversion) */
    int profile;     /* 1: computed from one profile */
    int periodic;    /* as given */
    double k_fund;   /* lowest nonzero |k| of the grid: 2π/(n d) of the longer side */
    double k_nyq;    /* highest |k| binned: min(π/dx, π/dy) (π/d along a profile) */
    ljgap_est h_rms; /* rms of the (detrended) heights: exact for the map; the error is its
                      * standard error as an estimate of the surface's h_rms */
    ljgap_est rms_slope; /* √(∫∫ k² P d²k) = rms |∇h| over the measured band (a profile: √2 ×
                          * its rms slope, isotropy assumed), with its standard error */
    double m0_spectrum; /* ∫∫ P d²k summed over every mode of the grid (= h_rms² for a
                         * periodic map, to round-off; windowed: close to it) */
    int has_fit;        /* 0 when fewer than 3 bins lie in the fit band */
    ljgap_topo_fit fit;
    ljgap_topo_detrend detrend; /* what was removed (never AUTO) */
    double rel_kmin;            /* the reliable band: from the lower edge of its first bin */
    double rel_kmax;            /* to min(k_nyq, the tip's limit, π/resolution) */
    ljgap_topo_by rel_by;       /* which of the three is rel_kmax */
    double k_tip;               /* the tip's limit (INFINITY without a tip radius) */
    size_t rel_first, rel_last; /* the bins inside the reliable band: [rel_first, rel_last] */
} ljgap_topo_result;

/* The psd object's table (ljgap_topo_table). */
typedef struct {
    size_t n;
    double *k, *P, *P_err; /* owned, n each; P_err propagated through the solve (below) */
    double *corr;          /* owned, n: correlation of the errors of knots j and j + 1 (the
                            * solve makes neighbours anticorrelated); corr[n - 1] = 0 */
    double m0;             /* 2π ∫ k P dk of the table's log-log interpolation (no tail) */
    double m0_modes;       /* the variance of the modes the table stands for (Σ of var[]) */
} ljgap_topo_tab;

/* The isotropic PSD of the map h (grid g). Returns LJGAP_OK; LJGAP_EINVAL with a warning for a
 * bad grid (fewer than LJGAP_TOPO_MIN_SIDE points a side, dx or dy not positive and finite),
 * non-finite heights, a map with nothing left after detrending (all heights equal, or a plane),
 * or a profile whose spectrum is too flat to convert (alpha <= 0.1); LJGAP_ENOMEM;
 * LJGAP_ECANCEL. res is released with ljgap_topo_result_free (also after a failure). */
int ljgap_topo_compute(const double *h, const ljgap_topo_grid *g, const ljgap_topo_opts *o,
                       ljgap_topo_result *res, ljgap_warnings *w);
void ljgap_topo_result_free(ljgap_topo_result *res); /* NULL is fine */

/* The reliable bins from k_from on as a table (k, P, P_err), ready for ljgap_psd_table, whose
 * log-log interpolation carries the variance of the modes it stands for: knots at the lower
 * edge of the first bin (or k_from), at each bin's k and at the upper edge of the last, their
 * values solved so that 2π ∫ k P dk over each bin's band [lo, hi] equals the bin's var (the
 * bin cut at k_from keeps its share). tail_q (NAN: none) sets the last segment's slope so that
 * a tail P ∝ k^tail_q continues it. t's arrays are the caller's (ljgap_topo_tab_free).
 * LJGAP_EINVAL when no reliable bin reaches beyond k_from; LJGAP_ENOMEM. */
int ljgap_topo_table(const ljgap_topo_result *r, double k_from, double tail_q, ljgap_topo_tab *t);
void ljgap_topo_tab_free(ljgap_topo_tab *t);

/* The name of a detrend mode ("mean", "plane", "lines", "curvature"; "auto") and back (-1 for
 * an unknown name). */
const char *ljgap_topo_detrend_name(ljgap_topo_detrend d);
int ljgap_topo_detrend_parse(const char *name);

/* The profile conversion factor: P(k) = ljgap_topo_abel_factor(alpha) PP(k) / k, exact for
 * PP ∝ k^-alpha, alpha > 0 (Γ((alpha+1)/2) / (√π Γ(alpha/2))). */
double ljgap_topo_abel_factor(double alpha);

#ifdef __cplusplus
}
#endif
#endif
