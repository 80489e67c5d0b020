/* mc.c -- PLACEHOLDER while the method is being written; returns LJGAP_EFAIL. */
#include "ljgap.h"

int ljgap_traction_mc(const ljgap_psd *psd, const ljgap_opts *o, const double *g_ave, size_t n,
                      ljgap_est *sigma, ljgap_summary *sum, ljgap_warnings *w)
{
    ljgap_warn(w, "method not implemented yet");
    return LJGAP_EFAIL;
}

int ljgap_pdf_mc(const ljgap_psd *psd, const ljgap_opts *o, double g_ave, const double *k2,
                 size_t nk2, const double *grid, ljgap_pdf *out, ljgap_warnings *w)
{
    ljgap_warn(w, "method not implemented yet");
    return LJGAP_EFAIL;
}
