/* ljgap_validity.h -- where the statistical theory holds: the validity map as data.
 *
 * The map (bench/theory_map.sh, bench/theory_map_k2.sh; docs/model.md "Where the theory holds")
 * compares the theory's adhesion summary with the discrete numerical model's for power-law
 * spectra with k1 = 1: per k2/k1 (8, 16, 32, and the continuum k2 = ∞ by extrapolation in k2),
 * D and m0, the relative difference (theory - discrete)/discrete of g_eq, sigma_max and
 * dgamma_eff with its error. bench/validity_table.sh generates the table (core/validity_table.c)
 * from the bench's results; ljgap_validity_at reads it for any spectrum. Dimensionless units as
 * in ljgap.h.
 */
#ifndef LJGAP_VALIDITY_H
#define LJGAP_VALIDITY_H

#include "ljgap.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The quantities of the map, in this order in every array below. */
enum { LJGAP_V_G_EQ = 0, LJGAP_V_SIGMA_MAX = 1, LJGAP_V_DGAMMA_EFF = 2, LJGAP_V_N = 3 };
extern const char *const ljgap_validity_quantities[LJGAP_V_N]; /* "g_eq", ... */

/* One point of the map. */
typedef struct {
    double k2_over_k1;        /* 8, 16, 32, or INFINITY (the continuum) */
    double D, m0;             /* fractal dimension, variance (k1 = 1) */
    double rel[LJGAP_V_N];    /* (theory - discrete)/discrete */
    double err[LJGAP_V_N];    /* its estimated error (realizations, L correction, extrapolation) */
    double L_bias[LJGAP_V_N]; /* the finite-size correction rel(L = 8π) - rel(L = 4π) at k2/k1 = 8
                               * that the row includes (0 where none was needed) */
    double hyb2[LJGAP_V_N];   /* the hybrid's (hybrid - discrete)/discrete at k_split = 2 and 4 */
    double hyb4[LJGAP_V_N];   /* (k2/k1 = 8 only; NAN where not computed) */
} ljgap_validity_row;
extern const ljgap_validity_row ljgap_validity_rows[];
extern const size_t ljgap_validity_nrows;
/* How the map was made, in words (generated with the table). */
typedef struct {
    const char *command;        /* the commands that make it */
    const char *discretisation; /* the discrete model's grid and square per k2/k1 */
    int realizations;           /* of every discrete run */
    const char *convergence;    /* how far the discrete model is converged (grid, L, R) */
    const char *continuum;      /* how the k2 = ∞ rows are extrapolated */
} ljgap_validity_how_info;
extern const ljgap_validity_how_info ljgap_validity_how;

/* What the map says about one spectrum. */
typedef struct {
    double rel[LJGAP_V_N], err[LJGAP_V_N]; /* at the point below: linear in (k1/k2)^(2(3-D)),
                                            * D and ln m0 between the map's points */
    int inside; /* 1: the spectrum lies on the map (rel, err are its values) */
    int bound;  /* 1: m0 below the map's smallest: its values there, an upper bound (the
                 * differences vanish as m0 -> 0) */
    double D, m0, k1, k2_over_k1;      /* the spectrum's (for a table: its effective D) */
    double at_D, at_m0, at_k2_over_k1; /* the point of the map whose values rel, err are (the
                                        * spectrum's, or outside the nearest point of the map) */
    const char *method;                /* how D, m0 and k2/k1 were read from the PSD */
    char reason[200];                  /* why outside ("" inside) */
} ljgap_validity;

/* The map at a power-law spectrum (D, m0, k1, k2; k2 = INFINITY for no cut-off). Returns
 * LJGAP_OK, or LJGAP_EINVAL when an argument is not a finite positive number (k2 may be ∞)
 * or k2 <= k1. Outside the map (D outside its range, k2/k1 below its smallest, m0 above its
 * largest, k1 not 1): inside = 0 with the reason, and rel, err those of the nearest point. */
int ljgap_validity_at(double D, double m0, double k1, double k2, ljgap_validity *out);
/* The same for a PSD: a power law reads its D, m0, k1, k2; a table its variance-weighted
 * D (the mean of (slope + 8)/2 over its segments and tail, weighted by their variance), its
 * m0 and its ends (k2 = ∞ with a tail); a table whose local D spreads by more than 0.1 (the
 * weighted standard deviation) or leaves (2, 3) is not power-law-like: inside = 0. */
int ljgap_validity_of_psd(const ljgap_psd *psd, ljgap_validity *out);

#ifdef __cplusplus
}
#endif
#endif
