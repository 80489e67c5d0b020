/* fold.h -- private interface of fold.c: time steps of the PDE solver (pde.c) on the folded
 * gap grid, where one two-lane vector holds node t and node n-1-t. */
#ifndef LJGAP_FOLD_H
#define LJGAP_FOLD_H

#include <stddef.h>

/* Two doubles that the compiler keeps in one vector register (SSE2 on x86-64, NEON on
 * aarch64, a pair of scalars elsewhere): GCC and Clang vector extensions, no intrinsics. */
typedef double ljgap__v2 __attribute__((vector_size(16)));

typedef struct {
    size_t n;       /* nodes of the gap grid, odd */
    size_t h;       /* (n-1)/2: position t < h holds nodes t (lane 0) and n-1-t (lane 1),
                     * position h the middle node in both lanes */
    ljgap__v2 *mem; /* one block holding every array below, h+1 entries each */
    ljgap__v2 *A;   /* 9 g^-10 - 3 g^-4, so that f = k/(k + A) */
    ljgap__v2 *wo;  /* second-difference weight towards the outer neighbour (position t-1);
                     * at h: the middle node's weights towards lane 0 and lane 1 */
    ljgap__v2 *wi;  /* weight towards the inner neighbour (position t+1) */
    ljgap__v2 *ws;  /* wo + wi */
    ljgap__v2 *x;   /* the solution u, folded: the caller puts and gets it */
    ljgap__v2 *y;   /* the last step's right-hand side */
    double k_prev;  /* the last step's lower end (NAN: no step yet) */
    double ca_prev; /* and its implicit coefficient */
    ljgap__v2 *r;   /* elimination: right-hand side, */
    ljgap__v2 *q;   /* coupling to the inner neighbour, */
    ljgap__v2 *inv; /* inverse pivot */
} ljgap__fold;

/* Fold a grid of n nodes (odd, n >= 3) with second-difference weights lo, hi ((D2 u)_i =
 * lo_i (u_{i-1} - u_i) + hi_i (u_{i+1} - u_i); lo = hi = 0 freezes a row, as at both ends) and
 * A_i = 9 g_i^-10 - 3 g_i^-4. Returns LJGAP_OK or LJGAP_ENOMEM. */
int ljgap__fold_make(ljgap__fold *F, size_t n, const double *A, const double *lo, const double *hi);
void ljgap__fold_free(ljgap__fold *F); /* zeroes F; a zeroed F is fine */

/* x (n values, node order) into the h+1 pairs of the folded layout, and back. */
void ljgap__fold_put(const ljgap__fold *F, const double *x, ljgap__v2 *xf);
void ljgap__fold_get(const ljgap__fold *F, const ljgap__v2 *xf, double *x);

/* One backward step x <- (I - ca Fa D2)^-1 (I + cb Fb D2) x from kb down to ka, with Fa, Fb
 * the diagonals of f(g,k)^2 at ka and kb (either may be INFINITY, where f = 1), ca = theta sa,
 * cb = (1 - theta) sb, on F->x. */
void ljgap__fold_back(ljgap__fold *F, double ka, double kb, double ca, double cb);

#endif
