/* solve.c -- method dispatch: one entry point per question, one file per method.
 *
 *   pde         the continuum limit of the paper's algorithm (theory.md §2), pde.c
 *   paper       the paper's iteration (16)-(18) as printed, paper.c
 *   montecarlo  the Itô process behind (18), simulated path by path, mc.c
 *
 * Checks common to every method live here: the theory needs k1 > k0 (19).
 */
#include "ljgap.h"
#include "core.h" /* the core's internals */

#include <math.h>
#include <stdlib.h>

static int check_common(const ljgap_psd *psd, const ljgap_opts *o, ljgap_warnings *w)
{
    if (!psd || !o) return LJGAP_EINVAL;
    if (!(psd->k1 > ljgap_k0())) {
        ljgap_warn(w,
                   "k1 = %g is at or below k0 = %.5f: the gap transfer (14) has a pole "
                   "(negative stiffness, (19)) and the theory does not apply",
                   psd->k1, ljgap_k0());
        return LJGAP_EINVAL;
    }
    if (!(o->tol > 0) || !isfinite(o->tol)) return LJGAP_EINVAL;
    /* the range where the solvers' grids and marches are sized sensibly */
    if (!(psd->m0 <= LJGAP_M0_MAX)) {
        ljgap_warn(w,
                   "m0 = %g is above %g (h_rms above %g epsilon): outside the range this "
                   "service computes",
                   psd->m0, LJGAP_M0_MAX, sqrt(LJGAP_M0_MAX));
        return LJGAP_EINVAL;
    }
    if (!(psd->k1 <= LJGAP_K_MAX) || (isfinite(psd->k2) && !(psd->k2 <= LJGAP_K_MAX))) {
        ljgap_warn(w,
                   "wavenumbers above %g (in units of 1/chi) are outside the range this "
                   "service computes; use k2 = infinity for an unbounded spectrum",
                   LJGAP_K_MAX);
        return LJGAP_EINVAL;
    }
    return LJGAP_OK;
}

int ljgap_traction(const ljgap_psd *psd, const ljgap_opts *o, const double *g_ave, size_t n,
                   ljgap_est *sigma, ljgap_summary *sum, ljgap_warnings *w)
{
    int st = check_common(psd, o, w);
    if (st) return st;
    for (size_t i = 0; i < n; i++)
        if (!(g_ave[i] >= LJGAP_G_MIN && g_ave[i] <= LJGAP_G_MAX)) {
            ljgap_warn(w, "mean gaps must lie in [%g, %g]", LJGAP_G_MIN, LJGAP_G_MAX);
            return LJGAP_EINVAL;
        }
    switch (o->method) {
    case LJGAP_METHOD_PDE:
        return ljgap__traction_pde(psd, o, g_ave, n, sigma, sum, w);
    case LJGAP_METHOD_PAPER:
        return ljgap__traction_paper(psd, o, g_ave, n, sigma, sum, w);
    case LJGAP_METHOD_MC:
        return ljgap__traction_mc(psd, o, g_ave, n, sigma, sum, w);
    }
    return LJGAP_EINVAL;
}

int ljgap_pdf_compute(const ljgap_psd *psd, const ljgap_opts *o, double g_ave, const double *k2,
                      size_t nk2, const double *grid, ljgap_pdf *out, ljgap_warnings *w)
{
    int st = check_common(psd, o, w);
    if (st) return st;
    if (!(g_ave >= LJGAP_G_MIN && g_ave <= LJGAP_G_MAX)) {
        ljgap_warn(w, "mean gaps must lie in [%g, %g]", LJGAP_G_MIN, LJGAP_G_MAX);
        return LJGAP_EINVAL;
    }
    for (size_t i = 0; i < nk2; i++) {
        out[i].g = out[i].phi = NULL;
        out[i].n = 0;
        if (!(k2[i] > psd->k1)) return LJGAP_EINVAL;
    }
    if (grid && !(grid[0] < grid[1] && grid[0] > 0 && grid[2] >= 2)) return LJGAP_EINVAL;
    switch (o->method) {
    case LJGAP_METHOD_PDE:
        return ljgap__pdf_pde(psd, o, g_ave, k2, nk2, grid, out, w);
    case LJGAP_METHOD_PAPER:
        return ljgap__pdf_paper(psd, o, g_ave, k2, nk2, grid, out, w);
    case LJGAP_METHOD_MC:
        return ljgap__pdf_mc(psd, o, g_ave, k2, nk2, grid, out, w);
    }
    return LJGAP_EINVAL;
}
