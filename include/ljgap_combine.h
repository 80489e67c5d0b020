/* ljgap_combine.h -- one PSD from several measurements of one surface (issue 25, item 5).
 *
 * Labs measure one surface at several scales (AFM scans of 1 and 10 µm, a profilometer line of
 * 1 mm); each gives a PSD table (k, P, P_err) over its own reliable band, in the convention of
 * ljgap_topo.h (angular k, 2π ∫ k P dk = h_rms²). ljgap_combine puts them on one logarithmic
 * grid over the union of their bands, interpolating each input log-log inside its own band only
 * (never extrapolating), and combines the inputs that cover a grid point by inverse-variance
 * weighting of ln P (σ_lnP = P_err/P); where they disagree beyond their errors the point's error
 * is inflated by √χ²_red. A gap between the bands is reported, not filled. A power law is
 * fitted to the combined table. docs/topography.md gives the method and its limits; the
 * tests are in tests/unit/test_combine.c.
 *
 * Knows nothing of JSON or HTTP; returns a status like every core call.
 */
#ifndef LJGAP_COMBINE_H
#define LJGAP_COMBINE_H

#include "ljgap.h"
#include "ljgap_topo.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LJGAP_COMBINE_MIN 2           /* inputs at least */
#define LJGAP_COMBINE_MAX 16          /* inputs at most */
#define LJGAP_COMBINE_GAPS 15         /* gaps reported at most */
#define LJGAP_COMBINE_GRID_MAX 10000  /* grid points at most */
#define LJGAP_COMBINE_REL_ERR_MAX 1e3 /* P_err/P at most: beyond, a point carries nothing */

/* One measurement's PSD table (not owned). */
typedef struct {
    size_t n;            /* points, >= 2 */
    const double *k;     /* strictly increasing, > 0 */
    const double *P;     /* > 0 */
    const double *P_err; /* >= 0: standard error of each P (independent between points) */
    int has_tail;        /* a tail P ∝ k^tail_q beyond k[n-1] was given */
    double tail_q, tail_q_err;
} ljgap_combine_input;

typedef struct {
    double per_decade;          /* grid points per decade of k (10), in [2, 100] */
    const volatile int *cancel; /* optional */
} ljgap_combine_opts;

void ljgap_combine_opts_default(ljgap_combine_opts *o);

typedef struct {
    double k_min, k_max; /* the input's band: its first and last k */
    size_t points;       /* grid points it contributes to */
} ljgap_combine_source;

typedef struct {
    size_t n;      /* grid points covered by at least one input, increasing k */
    double *k;     /* owned: 10^(i/per_decade), i integer */
    double *P;     /* owned: the combined PSD */
    double *P_err; /* owned: its standard error (inflated where the inputs disagree) */
    int *inputs;   /* owned: inputs that cover the point */
    double *chi2;  /* owned: the inputs' χ² about the combination (0 with one input) */
    size_t m;      /* inputs */
    ljgap_combine_source src[LJGAP_COMBINE_MAX]; /* per input */
    size_t ngaps;                                /* stretches no input covers */
    double gap[LJGAP_COMBINE_GAPS][2];           /* each one's k range */
    double chi2_total;  /* Σ χ² over the points with two inputs or more */
    size_t dof;         /* Σ (inputs - 1) over those points */
    double p_value;     /* P(χ² >= chi2_total) for dof degrees of freedom (1 when dof = 0) */
    size_t inflated;    /* points whose error was inflated (χ²_red > 1) */
    int has_fit;        /* 0 when fewer than 3 points */
    ljgap_topo_fit fit; /* P = C k^(2D-8), weighted by the combined errors; fit.bins: points */
    int tail_from;      /* the input whose tail the combination takes (the one covering the
                         * highest k, when it has one); -1: the fit's (when exponent < -2);
                         * -2: no tail */
    double tail_q, tail_q_err;
} ljgap_combine_result;

/* Combines in[0..m) (LJGAP_COMBINE_MIN <= m <= LJGAP_COMBINE_MAX). Returns LJGAP_OK, with
 * warnings for gaps, disagreement and a fitted D outside (2, 3); LJGAP_EINVAL with a warning
 * when the inputs are not valid tables (P_err/P above LJGAP_COMBINE_REL_ERR_MAX too), fewer
 * than two grid points are covered, the bands span more than LJGAP_COMBINE_GRID_MAX grid
 * points, or a combined value is beyond the range of a double;
 * LJGAP_ENOMEM; LJGAP_ECANCEL. res is released with ljgap_combine_result_free (also after a
 * failure). */
int ljgap_combine(const ljgap_combine_input *in, size_t m, const ljgap_combine_opts *o,
                  ljgap_combine_result *res, ljgap_warnings *w);
void ljgap_combine_result_free(ljgap_combine_result *res); /* NULL is fine */

#ifdef __cplusplus
}
#endif
#endif
