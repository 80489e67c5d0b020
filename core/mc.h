/* mc.h -- private interface of mc.c: the Monte Carlo drivers with an explicit step-control
 * constant c, so that the tests can measure the time-step bias by halving it. */
#ifndef LJGAP_MC_H
#define LJGAP_MC_H

#include "ljgap.h"

/* Default step control: each step's increment has standard deviation <= c * local scale,
 * and the step in w = ln(k - k0) is at most c. */
#define LJGAP__MC_C 0.15

int ljgap__mc_traction(const ljgap_psd *psd, const ljgap_opts *o, double c, const double *g_ave,
                       size_t n, ljgap_est *sigma, ljgap_summary *sum, ljgap_warnings *w);
int ljgap__mc_pdf(const ljgap_psd *psd, const ljgap_opts *o, double c, double g_ave,
                  const double *k2, size_t nk2, const double *grid, ljgap_pdf *out,
                  ljgap_warnings *w);

#endif
