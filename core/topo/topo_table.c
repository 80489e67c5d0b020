/* topo_table.c -- the psd object of a measured PSD: its table (ljgap_topo_table, ljgap_topo.h).
 *
 * The reliable bins as knots of a log-log table whose variance is the bins' (a solve that keeps
 * it), with P_err propagated through that solve (neighbouring knots' errors anticorrelated) and
 * an optional power-law tail: what /v1/psd returns to send as it is to the adhesion endpoints.
 */
#include "ljgap_topo.h"
#include "topo_parts.h"

#include <float.h>
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_sf_gamma.h>
#include <gsl/gsl_sf_psi.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void ljgap_topo_tab_free(ljgap_topo_tab *t)
{
    if (!t) return;
    free(t->k);
    free(t->P);
    free(t->P_err);
    free(t->corr);
    memset(t, 0, sizeof *t);
}

/* 2π ∫ k P dk over [x1, x2] of the table's log-log interpolation (knots K, log values V). */
static double tab_int(const double *K, const double *V, size_t m, double x1, double x2)
{
    double sum = 0;
    for (size_t j = 0; j + 1 < m; j++) {
        double a = fmax(x1, K[j]), b = fmin(x2, K[j + 1]);
        if (!(b > a)) continue;
        double s = (V[j + 1] - V[j]) / log(K[j + 1] / K[j]);
        sum += ljgap__topo_seg_var(K[j], exp(V[j]), s, a, b);
    }
    return sum;
}

/* The knots' errors: the values solve g_b(V) = ln ∫_b (the table) − ln S_b = 0, so a change
 * δ ln S of the bins' sums moves the free values by δV = J⁻¹ δ ln S, J_bc = ∂ ln ∫_b / ∂V_c
 * (numerical, the edge knots tied to their neighbours as in the solve). The bins' relative
 * errors are independent: cov V = J⁻¹ diag(P_err/P)² J⁻ᵀ. rel[j] receives the knot's relative
 * error √cov_jj, corr[j] the correlation of knots j and j + 1 (0 for the last). The solve is a
 * deconvolution of the interpolation's overlap between neighbouring bins, which amplifies
 * alternating noise: the bins' own relative errors understate the knots' (issue 29). 0, or -1
 * out of memory. */
static int tab_errors(const ljgap_topo_result *r, size_t first, const double *K, const double *V0,
                      size_t mm, size_t idx0, size_t nb, int lead, int trail, double s_end,
                      const double *blo, const double *bhi, double *rel, double *corr)
{
    int st = -1;
    double *V = malloc(mm * sizeof *V), *g0 = malloc(nb * sizeof *g0);
    gsl_matrix *J = gsl_matrix_alloc(nb, nb), *X = gsl_matrix_calloc(nb, nb);
    gsl_permutation *perm = gsl_permutation_alloc(nb);
    if (!V || !g0 || !J || !X || !perm) goto out;
    memcpy(V, V0, mm * sizeof *V);
    for (size_t b = 0; b < nb; b++)
        g0[b] = log(tab_int(K, V, mm, blo[b], bhi[b]));
    const double h = 1e-6;
    for (size_t c = 0; c < nb; c++) {
        V[idx0 + c] += h;
        if (lead) V[0] = V[1];
        if (trail) V[mm - 1] = V[mm - 2] + s_end * log(K[mm - 1] / K[mm - 2]);
        for (size_t b = 0; b < nb; b++)
            gsl_matrix_set(J, b, c, (log(tab_int(K, V, mm, blo[b], bhi[b])) - g0[b]) / h);
        memcpy(V, V0, mm * sizeof *V);
    }
    /* X = J⁻¹ diag(rel_b): column b solves J x = rel_b e_b */
    int sgn;
    if (gsl_linalg_LU_decomp(J, perm, &sgn)) goto out;
    for (size_t b = 0; b < nb; b++) {
        gsl_vector_view col = gsl_matrix_column(X, b);
        gsl_vector_set(&col.vector, b, r->P_err[first + b] / r->P[first + b]);
        if (gsl_linalg_LU_svx(J, perm, &col.vector)) goto out;
    }
    /* the knot j's row of X (the edge knots: their neighbour's) */
    for (size_t j = 0; j < mm; j++) {
        size_t a = j < idx0 ? 0 : j - idx0 >= nb ? nb - 1 : j - idx0;
        size_t a2 = j + 1 < idx0 ? 0 : j + 1 - idx0 >= nb ? nb - 1 : j + 1 - idx0;
        double vaa = 0, vbb = 0, vab = 0;
        for (size_t b = 0; b < nb; b++) {
            double x = gsl_matrix_get(X, a, b), y = gsl_matrix_get(X, a2, b);
            vaa += x * x, vbb += y * y, vab += x * y;
        }
        rel[j] = sqrt(vaa);
        corr[j] = j + 1 < mm && vaa > 0 && vbb > 0 ? vab / sqrt(vaa * vbb) : 0;
        if (!(rel[j] > 0) || !isfinite(rel[j])) /* a singular solve: the bin's own */
            rel[j] = r->P_err[first + a] / r->P[first + a], corr[j] = 0;
    }
    st = 0;
out:
    free(V);
    free(g0);
    gsl_matrix_free(J);
    gsl_matrix_free(X);
    gsl_permutation_free(perm);
    return st;
}

#define TOPO_TAB_ITER                                                                              \
    500 /* iterations of the table's values (each divides the misfit by 2 or more) */

int ljgap_topo_table(const ljgap_topo_result *r, double k_from, double tail_q, ljgap_topo_tab *t)
{
    memset(t, 0, sizeof *t);
    if (!r || r->n == 0 || r->rel_last < r->rel_first || r->rel_last >= r->n) return LJGAP_EINVAL;
    size_t first = r->rel_first, last = r->rel_last;
    while (first <= last && r->hi[first] <= k_from * (1 + 1e-12))
        first++;
    if (first > last) return LJGAP_EINVAL;
    const size_t nb = last - first + 1;
    double lo0 = fmax(r->lo[first], k_from), hiN = fmin(r->hi[last], r->rel_kmax);
    if (!(hiN > lo0)) return LJGAP_EINVAL;
    /* knots: [lo0,] c_first ... c_last [, hiN]; c_b the bin's k inside its band */
    size_t m = nb + 2, lead, idx0;
    double *K = malloc(m * sizeof *K), *V = malloc(m * sizeof *V), *S = malloc(nb * sizeof *S);
    double *blo = calloc(nb, sizeof *blo), *bhi = calloc(nb, sizeof *bhi);
    double *dv = malloc(nb * sizeof *dv);
    int st = LJGAP_ENOMEM;
    if (!K || !V || !S || !blo || !bhi || !dv) goto end;
    for (size_t b = 0; b < nb; b++) {
        size_t i = first + b;
        blo[b] = b == 0 ? lo0 : r->lo[i];
        bhi[b] = b + 1 == nb ? hiN : r->hi[i];
        S[b] = r->var[i];
        if (b == 0 && lo0 > r->lo[i]) /* the share of the bin above k_from, by its local slope */
            S[b] *= ljgap__topo_seg_var(r->k[i], 1, r->slope[i], lo0, r->hi[i]) /
                    ljgap__topo_seg_var(r->k[i], 1, r->slope[i], r->lo[i], r->hi[i]);
    }
    double c0 = fmin(fmax(r->k[first], blo[0]), bhi[0]);
    lead = lo0 < c0 * (1 - 1e-12);
    idx0 = lead;
    if (lead) K[0] = lo0;
    for (size_t b = 0; b < nb; b++) {
        double c = fmin(fmax(r->k[first + b], blo[b]), bhi[b]);
        if (idx0 + b > 0 && !(c > K[idx0 + b - 1])) c = K[idx0 + b - 1] * (1 + 1e-9);
        K[idx0 + b] = c;
        V[idx0 + b] = log(r->P[first + b]);
    }
    size_t mm = idx0 + nb;
    int trail = hiN > K[mm - 1] * (1 + 1e-12);
    double s_end = isfinite(tail_q) ? tail_q : fmin(fmax(r->slope[last], TOPO_SLOPE_MIN), 0);
    if (trail) K[mm++] = hiN;
    if (mm < 2) {
        st = LJGAP_EINVAL;
        goto end;
    }
    for (int it = 0; it < TOPO_TAB_ITER; it++) {
        double worst = 0;
        if (lead) V[0] = V[1];
        if (trail) V[mm - 1] = V[mm - 2] + s_end * log(K[mm - 1] / K[mm - 2]);
        for (size_t b = 0; b < nb; b++) { /* Jacobi: every bin from the same values */
            double I = tab_int(K, V, mm, blo[b], bhi[b]);
            dv[b] = S[b] > 0 && I > 0 ? log(S[b] / I) : 0;
            worst = fmax(worst, fabs(dv[b]));
        }
        for (size_t b = 0; b < nb; b++)
            V[idx0 + b] += dv[b];
        if (worst < 1e-12) break;
    }
    if (lead) V[0] = V[1];
    if (trail) V[mm - 1] = V[mm - 2] + s_end * log(K[mm - 1] / K[mm - 2]);
    t->k = malloc(mm * sizeof *t->k);
    t->P = malloc(mm * sizeof *t->P);
    t->P_err = malloc(mm * sizeof *t->P_err);
    t->corr = calloc(mm, sizeof *t->corr);
    if (!t->k || !t->P || !t->P_err || !t->corr) goto end;
    for (size_t j = 0; j < mm; j++) {
        t->k[j] = K[j];
        t->P[j] = exp(V[j]);
        if (!(t->P[j] > 0) || !isfinite(t->P[j])) { /* a bin without power (a constant map, an */
            st = LJGAP_EINVAL;                        /* underflow): no table the PSD calls take */
            goto end;
        }
    }
    if (tab_errors(r, first, K, V, mm, idx0, nb, lead, trail, s_end, blo, bhi, t->P_err, t->corr))
        goto end;
    for (size_t j = 0; j < mm; j++)
        t->P_err[j] *= t->P[j];
    t->n = mm;
    t->m0 = tab_int(K, V, mm, K[0], K[mm - 1]);
    t->m0_modes = 0;
    for (size_t b = 0; b < nb; b++)
        t->m0_modes += S[b];
    st = LJGAP_OK;
end:
    free(K);
    free(V);
    free(S);
    free(blo);
    free(bhi);
    free(dv);
    if (st) ljgap_topo_tab_free(t);
    return st;
}
