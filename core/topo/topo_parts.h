/* topo_parts.h -- what the files of the topography PSD share (topo.c, topo_fit.c, topo_table.c).
 * Private to the core; the API is include/ljgap_topo.h.
 */
#ifndef LJGAP_TOPO_PARTS_H
#define LJGAP_TOPO_PARTS_H

#include "ljgap_topo.h"

#include <stddef.h>

/* a windowed map's bins correlate with the next TOPO_LAGS bins (the window's ±2 modes reach
 * further over narrow low bins, but 3 lags changed the errors of D by 0.1 % and looked to slow
 * the core on a 2048² map by up to a third, measured at load 7: noisy) */
#define TOPO_LAGS 1
#define TOPO_SLOPE_MIN -10.0 /* bounds of the local slope the curvature correction uses */
#define TOPO_SLOPE_MAX 2.0
#define TOPO_FLOOR_END 0.2 /* with a floor, the band ends where it reaches 20 % of the law */

/* The power-law fit of bins k, P (modes, neighbour correlations rho, bin edges edge) over the
 * band [lo, hi] (detected unless fix_lo, fix_hi), var_extra a variance common to every bin:
 * LJGAP_OK with *f, or a core status (topo_fit.c). */
int ljgap__topo_fit_band(const double *k, const double *P, const double *modes, const double *rho,
                         const double *edge, double var_extra, size_t lo, size_t hi, int fix_lo,
                         int fix_hi, ljgap_topo_fit *f);

/* Detrends the nx × ny map a in place as mode says; Hann-windows it (topo_prep.c). */
void ljgap__topo_detrend(double *a, size_t nx, size_t ny, ljgap_topo_detrend mode);
void ljgap__topo_window(double *a, size_t nx, size_t ny);

/* 2π ∫ k P dk over [x1, x2] of the power law P = Pa (k/ka)^s (topo.c). */
double ljgap__topo_seg_var(double ka, double Pa, double s, double x1, double x2);

#endif
