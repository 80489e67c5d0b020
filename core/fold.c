/* fold.c -- Crank-Nicolson steps of the backward equation (pde.c) as two-lane sweeps.
 *
 * A step of du/dk = -a u'' with a = s f(g,k)^2 solves one tridiagonal system per step; its
 * cost is the whole traction solve. The system is eliminated from both ends towards the
 * middle (a twisted factorisation): the chain from the top and the chain from the bottom do
 * the same arithmetic on different nodes. Folding the grid -- position t holds node t in
 * lane 0 and node n-1-t in lane 1 -- turns the two chains into one chain of two-lane vectors,
 * so every operation serves two nodes (SSE2 is in every x86-64, NEON in every aarch64; this
 * is the portable build, no -march). In folded coordinates both lanes see the same
 * stencil, "outer" neighbour t-1 and "inner" neighbour t+1, so the loops have no branches;
 * the middle node (n is odd) is the one place where the lanes meet, done in scalar code.
 *
 * One sweep outwards-in does, per position: f^2 at the step's new end (kept for the next
 * step, whose other end it is), the explicit half (I + cb Fb D2) u, and the elimination; one
 * sweep back does the substitution. What does not change between steps -- the weights and
 * their sums per node -- is folded once per grid.
 *
 * Elimination, for rows -c wo x_{t-1} + (1 + c ws) x_t - c wi x_{t+1} = rhs_t (c = ca f^2):
 *   e_t = c_t wo_t inv_{t-1},  r_t = rhs_t + e_t r_{t-1},  q_t = c_t wi_t,
 *   inv_t = 1 / (1 + c_t ws_t - e_t q_{t-1});   then x_t = (r_t + q_t x_{t+1}) inv_t.
 * Frozen rows (both ends) have wo = wi = 0, so they pass through as x = rhs.
 */
#include "ljgap.h"
#include "fold.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NARR 9      /* arrays in F->mem */
#define REUSE_MAX 4 /* largest step ratio cb/ca' that takes the explicit half from x and y */
/* k = infinity (the last steps of an infinite tail) as a number: f = k/(k + A) is then 1
 * exactly, since |A| < 1e34 on any grid (g >= 5e-4). */
#define K_INF 1e300

int ljgap__fold_make(ljgap__fold *F, size_t n, const double *A, const double *lo, const double *hi)
{
    memset(F, 0, sizeof *F);
    if (n < 3 || n % 2 == 0) return LJGAP_EINVAL;
    size_t h = (n - 1) / 2, len = h + 1;
    ljgap__v2 *b = aligned_alloc(sizeof(ljgap__v2), NARR * len * sizeof(ljgap__v2));
    if (!b) return LJGAP_ENOMEM;
    F->n = n;
    F->h = h;
    F->mem = b;
    ljgap__v2 **arr[NARR] = {&F->A, &F->wo, &F->wi, &F->ws, &F->x, &F->y, &F->r, &F->q, &F->inv};
    for (int i = 0; i < NARR; i++)
        *arr[i] = b + (size_t)i * len;
    for (size_t t = 0; t < h; t++) {
        size_t j = n - 1 - t;
        F->A[t] = (ljgap__v2){A[t], A[j]};
        F->wo[t] = (ljgap__v2){lo[t], hi[j]};
        F->wi[t] = (ljgap__v2){hi[t], lo[j]};
        F->ws[t] = F->wo[t] + F->wi[t];
    }
    F->A[h] = (ljgap__v2){A[h], A[h]};
    F->wo[h] = (ljgap__v2){lo[h], hi[h]};
    F->wi[h] = F->ws[h] = (ljgap__v2){0.0, 0.0}; /* (the middle row is done apart) */
    F->k_prev = NAN;
    return LJGAP_OK;
}

void ljgap__fold_free(ljgap__fold *F)
{
    free(F->mem);
    memset(F, 0, sizeof *F);
}

void ljgap__fold_put(const ljgap__fold *F, const double *x, ljgap__v2 *xf)
{
    for (size_t t = 0; t < F->h; t++)
        xf[t] = (ljgap__v2){x[t], x[F->n - 1 - t]};
    xf[F->h] = (ljgap__v2){x[F->h], x[F->h]};
}

void ljgap__fold_get(const ljgap__fold *F, const ljgap__v2 *xf, double *x)
{
    for (size_t t = 0; t < F->h; t++) {
        x[t] = xf[t][0];
        x[F->n - 1 - t] = xf[t][1];
    }
    x[F->h] = xf[F->h][0];
}

/* rhs = (I + cb Fb D2) x by the stencil, Fb = f(g,kb)^2 (kb <= K_INF). */
static void fold_explicit(ljgap__fold *F, double kb, double cb)
{
    const ljgap__v2 *A = F->A, *wo = F->wo, *wi = F->wi, *x = F->x;
    ljgap__v2 *y = F->y;
    size_t h = F->h;
    const ljgap__v2 K = {kb, kb}, CB = {cb, cb};
    y[0] = x[0];
    for (size_t t = 1; t < h; t++) {
        ljgap__v2 f = K / (K + A[t]);
        ljgap__v2 d2 = wo[t] * (x[t - 1] - x[t]) + wi[t] * (x[t + 1] - x[t]);
        y[t] = x[t] + CB * f * f * d2;
    }
    double fm = kb / (kb + A[h][0]), xm = x[h][0];
    double d2 = wo[h][0] * (x[h - 1][0] - xm) + wo[h][1] * (x[h - 1][1] - xm);
    xm += cb * fm * fm * d2;
    y[h] = (ljgap__v2){xm, xm};
}

void ljgap__fold_back(ljgap__fold *F, double ka, double kb, double ca, double cb)
{
    ka = fmin(ka, K_INF);
    kb = fmin(kb, K_INF);
    /* the explicit half: after a step that ended at kb, (I + cb Fb D2) x is a combination of
     * that step's solution x and right-hand side y, since (I - ca' Fb D2) x = y. That
     * multiplies the rounding of x - y by rho = cb/ca', so only for rho <= REUSE_MAX (the
     * march's regular steps have rho = 1; a cut or the start of the tail can have any); else
     * the stencil. */
    double al = 0, be = 1; /* the right-hand side is al x + be y */
    if (F->k_prev == kb && cb <= REUSE_MAX * F->ca_prev) {
        double rho = cb / F->ca_prev;
        al = 1.0 + rho, be = -rho;
    } else {
        fold_explicit(F, kb, cb);
    }
    size_t h = F->h;
    const ljgap__v2 *restrict A = F->A, *restrict wo = F->wo, *restrict wi = F->wi,
                              *restrict ws = F->ws;
    ljgap__v2 *restrict x = F->x, *restrict y = F->y, *restrict r = F->r, *restrict q = F->q,
                        *restrict inv = F->inv;
    const ljgap__v2 one = {1.0, 1.0}, K = {ka, ka}, CA = {ca, ca}, AL = {al, al}, BE = {be, be};
    /* position 0: the frozen end rows */
    ljgap__v2 rp = x[0], qp = {0.0, 0.0}, ip = one;
    y[0] = rp;
    r[0] = rp;
    q[0] = qp;
    inv[0] = ip;
    for (size_t t = 1; t < h; t++) {
        ljgap__v2 yt = AL * x[t] + BE * y[t];
        ljgap__v2 f = K / (K + A[t]);
        ljgap__v2 c = CA * f * f;
        ljgap__v2 e = c * wo[t] * ip;
        y[t] = yt;
        rp = yt + e * rp;
        ip = one / (one + c * ws[t] - e * qp);
        qp = c * wi[t];
        r[t] = rp;
        q[t] = qp;
        inv[t] = ip;
    }
    /* the middle node takes both lanes' eliminated neighbours */
    double fm = ka / (ka + A[h][0]), lo = wo[h][0], hi = wo[h][1];
    double c = ca * fm * fm, ym = al * x[h][0] + be * y[h][0];
    double el = c * lo * inv[h - 1][0], er = c * hi * inv[h - 1][1];
    double dm = 1.0 + c * (lo + hi) - el * q[h - 1][0] - er * q[h - 1][1];
    double xm = (ym + el * r[h - 1][0] + er * r[h - 1][1]) / dm;
    y[h] = (ljgap__v2){ym, ym};
    x[h] = (ljgap__v2){xm, xm};
    ljgap__v2 xn = x[h];
    for (size_t t = h; t-- > 1;) {
        xn = (r[t] + q[t] * xn) * inv[t];
        x[t] = xn;
    }
    F->k_prev = ka;
    F->ca_prev = ca;
}
