/* core.h -- the core's private interface: what its files share beyond the installed ljgap.h.
 *
 * The installed header holds what a user of the library calls (GSL's model); these are the
 * core's own: the solver entry points per method, which solve.c dispatches to (tests and
 * benchmarks call them directly to compare the methods), the traction curve's post-processing
 * and the cancel/deadline test. Prefix ljgap__: internal, not part of the API.
 */
#ifndef LJGAP_CORE_H
#define LJGAP_CORE_H

#include "ljgap.h"

/* ---- curve.c: shared post-processing ---- */
/* Summary (values only; errors zero) of a traction curve u on increasing gaps g[0..n-1]
 * (dense enough for a cubic spline). The area beyond g[n-1] is E[sigma_work(g+X)] with
 * X ~ N(0, m0_tail). Returns LJGAP_EFAIL with a warning when there is no sign change or
 * no interior maximum. */
int ljgap__curve_summary(const double *g, const double *u, size_t n, double m0_tail,
                         ljgap_summary *out, ljgap_warnings *w);

/* ---- solver entry points per method (called by ljgap_traction / ljgap_pdf_compute) ---- */
int ljgap__traction_pde(const ljgap_psd *psd, const ljgap_opts *o, const double *g_ave, size_t n,
                        ljgap_est *sigma, ljgap_summary *sum, ljgap_warnings *w);
int ljgap__traction_paper(const ljgap_psd *psd, const ljgap_opts *o, const double *g_ave, size_t n,
                          ljgap_est *sigma, ljgap_summary *sum, ljgap_warnings *w);
int ljgap__traction_mc(const ljgap_psd *psd, const ljgap_opts *o, const double *g_ave, size_t n,
                       ljgap_est *sigma, ljgap_summary *sum, ljgap_warnings *w);
int ljgap__pdf_pde(const ljgap_psd *psd, const ljgap_opts *o, double g_ave, const double *k2,
                   size_t nk2, const double *grid, ljgap_pdf *out, ljgap_warnings *w);
int ljgap__pdf_paper(const ljgap_psd *psd, const ljgap_opts *o, double g_ave, const double *k2,
                     size_t nk2, const double *grid, ljgap_pdf *out, ljgap_warnings *w);
int ljgap__pdf_mc(const ljgap_psd *psd, const ljgap_opts *o, double g_ave, const double *k2,
                  size_t nk2, const double *grid, ljgap_pdf *out, ljgap_warnings *w);

/* ---- util.c ---- */
double ljgap__now(void); /* monotonic seconds */
/* Nonzero when the computation must stop: cancelled, or past deadline (seconds, from
 * ljgap__now). */
int ljgap__should_stop(const ljgap_opts *o, double deadline);

#endif
