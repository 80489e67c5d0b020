/* march.h -- private interface of march.c: the steps in wavenumber of the PDE solver (pde.c). */
#ifndef LJGAP_MARCH_H
#define LJGAP_MARCH_H

#include "ljgap.h"

/* One step from ka up to kb. */
typedef struct {
    double ka, kb; /* wavenumbers at the two ends (kb may be INFINITY) */
    double sa, sb; /* coefficient scale: the step's operator is s * f(g,k)^2 * D2 */
    double theta;  /* 1 backward Euler, 0.5 Crank-Nicolson */
    int snap;      /* index of the snapshot taken after this step, or -1 */
} pde_step;

/* The steps of one level. */
typedef struct {
    size_t m;       /* number of steps */
    pde_step *s;    /* steps from k1 upward */
    double kmax;    /* end of the zeta march */
    double tau_rem; /* variance added by the tail part */
} pde_march;

/* The regular nodes k_j = zeta^-1(zeta(k1) + j dz) of the marches of one request, with
 * rate_of at them, at the finest spacing asked so far (entries not yet needed are NAN). A
 * march of level L takes every 2^(finest - L)-th entry, since level L+1 holds every node of
 * level L: the lower-end search and the refinement levels find each node once, and a node
 * between two known ones starts Newton halfway between them. */
typedef struct {
    double dz;     /* spacing of the entries (0: none yet) */
    size_t n;      /* entries */
    double *k, *r; /* node and rate (one block) */
} zeta_nodes;

void ljgap__nodes_free(zeta_nodes *Z); /* zeroes Z; a zeroed Z is fine */

/* The steps of level L (see march.c), or LJGAP_EFAIL / LJGAP_ECAP / LJGAP_ENOMEM. Z (may be NULL)
 * keeps the nodes for the next march of the same request. */
int ljgap__march_make(pde_march *M, const ljgap_psd *psd, const double *cuts, size_t nc, int L,
                      double g_k, int backward, zeta_nodes *Z);
void ljgap__march_free(pde_march *M);

#endif
