/* pde.h -- internals of the PDE solver exposed for tests and benchmarks. */
#ifndef LJGAP_PDE_H
#define LJGAP_PDE_H

#include "ljgap.h"

/* The adhesion summary from one backward solve at resolution level `level` (grid spacing
 * and steps halve per level) on [g_lo, g_hi], without extrapolation: for measuring the
 * convergence order. */
int ljgap__pde_summary_at_level(const ljgap_psd *psd, double g_lo, double g_hi, int level,
                               ljgap_summary *sum);

/* The gap PDF at g_ave for the PSD truncated at k2, from one forward solve at resolution
 * level `level` on [g_lo, g_hi] (g_ave a node), without extrapolation: the density at the
 * nodes (sigma.err and phi_err zero). Release out with ljgap_pdf_release. */
int ljgap__pde_pdf_at_level(const ljgap_psd *psd, double g_ave, double k2, double g_lo, double g_hi,
                           int level, ljgap_pdf *out);

#endif
