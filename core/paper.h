/* paper.h -- private interface of paper.c: one level of the paper's iteration (16)-(18) at a
 * fixed band variance Vmax and grid spacing h, for the public drivers and the unit tests.
 *
 *   ljgap__paper_ws *ws = ljgap__paper_alloc(psd, vmax, h, g_lo, g_hi, ks, nks);
 *   ljgap__paper_forward(ws, psd, p, 0, ws->snap[0], NULL, 0);   // PDF at ks[0]
 *   ljgap__paper_free(ws);
 */
#ifndef LJGAP_PAPER_H
#define LJGAP_PAPER_H

#include "ljgap.h"

typedef struct {
    double g_lo;  /* first grid point */
    double h;     /* grid spacing */
    size_t n;     /* number of grid points g_i = g_lo + i h */
    double vmax;  /* packet variance (17) of every band at g* (the last one may be smaller) */
    size_t nb;    /* number of bands */
    size_t cap;   /* allocated length of ka, kb, vfix */
    double *ka;   /* band b adds the wavenumbers [ka[b], kb[b]] */
    double *kb;   /* (see ka) */
    double *vfix; /* vfix[b] >= 0: closing heat-kernel step of that variance (f = 1 beyond
                   * kmax); < 0: the band's variance is (17) at each grid point */
    size_t nsnap; /* number of snapshots */
    size_t *snap; /* snap[s]: number of bands applied when snapshot s (ascending k) is reached */
    double *tmp;  /* scratch, n entries */
    double *tmp2; /* scratch, n entries (leak vector) */
    double *e;    /* scratch, emax + 1 Gaussian weights exp(-(m h)^2 / 2V) */
    size_t emax;  /* largest window half-width in grid points */
    long work;    /* window operations (grid point x neighbour) done so far */
    double leak;  /* forward runs: probability renormalized away at the lower grid end */
} ljgap__paper_ws;

/* Grid [g_lo, g_hi] of spacing h and the bands from k1 to the largest snapshot ks[nks-1]
 * (ascending; values >= psd->k2, INFINITY included, mean the whole PSD; nks = 0 means one
 * snapshot at the whole PSD). Returns NULL when out of memory or the input is unusable. */
ljgap__paper_ws *ljgap__paper_alloc(const ljgap_psd *psd, double vmax, double h, double g_lo,
                                    double g_hi, const double *ks, size_t nks);
void ljgap__paper_free(ljgap__paper_ws *ws);

/* Forward iteration (18) of the grid masses p (n entries) through bands [b0, b1).
 * o (may be NULL) and deadline stop it: LJGAP_ECANCEL or LJGAP_ECAP. LJGAP_EFAIL when a
 * value is not finite. */
int ljgap__paper_forward(ljgap__paper_ws *ws, const ljgap_psd *psd, double *p, size_t b0, size_t b1,
                         const ljgap_opts *o, double deadline);

/* Transposed iteration through all bands, last to first: u (n entries) holds sigma(g_i) on
 * entry and sigma_bar(g_ave = g_i) on return. leak (NULL or n entries) receives the
 * probability that a path started at g_i was renormalized at the lower grid end. */
int ljgap__paper_backward(ljgap__paper_ws *ws, const ljgap_psd *psd, double *u, double *leak,
                          const ljgap_opts *o, double deadline);

/* One level at a fixed Vmax (grid spacing by the rule below, the drivers' initial grid ends),
 * without refinement or error estimate: for measuring error against run time. o gives the
 * time cap and cancel flag only (o->max_seconds: LJGAP_ECAP).
 * ljgap__paper_summary_at: the adhesion summary (errors zero) of the traction curve.
 * ljgap__paper_pdf_at: the PDF at g_ave for the PSD truncated at k2, at the nodes or on grid
 * {min,max,n}; sigma.err and phi_err are zero. Release out with ljgap_pdf_release. */
int ljgap__paper_summary_at(const ljgap_psd *psd, const ljgap_opts *o, double vmax,
                            ljgap_summary *sum);
int ljgap__paper_pdf_at(const ljgap_psd *psd, const ljgap_opts *o, double vmax, double g_ave,
                        double k2, const double *grid, ljgap_pdf *out);

/* Grid spacing rule: min(0.005, sqrt(vmax)/10). */
double ljgap__paper_h(double vmax);

#endif
