/* simlaw.c -- the interface law of the discrete model: Lennard-Jones, or the statistical mean
 * traction of a fine band of roughness (the hybrid model of the paper's Section 6).
 *
 * The hybrid grid carries the roughness of [k1, k_split] only. At every grid point the two
 * surfaces then still have the roughness of (k_split, k2] between them, and the paper's theory
 * gives what that does to the traction at a given local mean gap g: the modified force law
 * σ̄(g) of (21), the mean traction of the fine band alone (Fig. 4). That law replaces the
 * Lennard-Jones law σ(g) of (8),(9) in the discrete model's equations, so the model needs its
 * value, its derivative (the Newton solver's Hessian) and its potential W(g) = ∫_g^∞ σ̄ (the
 * line search's energy) at every grid point in every step: far too often for the PDE, which is
 * why it is tabulated once per run.
 *
 * Table. σ̄ itself is as steep as σ near the wall (σ ~ -g^-9), but the fine band changes it
 * smoothly: δ(g) = σ̄(g) - σ(g) is bounded and vanishes both at the wall, where the gap transfer
 * f (14) freezes the fine waves, and far out. So σ̄ = σ + δ with σ analytic and δ tabulated at
 * nodes uniform in ln g (relative resolution, as the PDE's own grid) from SIMLAW_G_LO to g_hi,
 * where the band's own spread has left the wall far behind (g_hi >= 1.5 + 10 √m0). Between
 * nodes δ is the cubic (in g) Hermite interpolant with slopes from fourth-order differences in
 * ln g (one-sided at the ends): C1, fourth-order accurate, and its integral is exact, which
 * keeps W consistent with σ̄ to rounding (the line search compares energies). Beyond g_hi the
 * fine band acts as a Gaussian blur, f ≈ 1 there: σ̄ = E[σ(g+X)], X ~ N(0, m0), from the
 * series in lj.c, and W likewise. Below SIMLAW_G_LO (σ < -3900, never met in practice) δ
 * continues linearly.
 *
 * Error. Each node carries the PDE's error estimate plus an interpolation error: the same
 * construction on every other node, evaluated at the nodes left out, differs from the table by
 * e_2h; a fourth-order scheme has error e_2h/16 at spacing h, and we take e_2h/8.
 */
#include "simlaw.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LAW_A 2.598076211353315940 /* 3√3/2 */

static void lj_eval(double g, double *s, double *ds)
{
    double g2 = 1.0 / (g * g), g4 = g2 * g2, g3 = g2 / g, g9 = g3 * g3 * g3, g10 = g4 * g4 * g2;
    *s = LAW_A * (g3 - g9);
    *ds = LAW_A * (9.0 * g10 - 3.0 * g4);
}

void sim_law_lj(sim_law *law)
{
    memset(law, 0, sizeof *law);
    law->s_min = -LAW_A * ljgap_k0();
}

void sim_law_free(sim_law *law)
{
    if (!law) return;
    free(law->g);
    free(law->bin);
    sim_law_lj(law);
}

/* Slopes dy/dt of y[0], y[s], y[2s], ... (m values, m >= 5, spacing dt): fourth-order
 * differences, one-sided at both ends. */
static void fd_slopes(const double *y, size_t m, size_t s, double dt, double *out)
{
    double c = 1.0 / (12.0 * dt);
#define Y(i) y[(i)*s]
    out[0] = c * (-25 * Y(0) + 48 * Y(1) - 36 * Y(2) + 16 * Y(3) - 3 * Y(4));
    out[s] = c * (-3 * Y(0) - 10 * Y(1) + 18 * Y(2) - 6 * Y(3) + Y(4));
    for (size_t i = 2; i + 2 < m; i++)
        out[i * s] = c * (Y(i - 2) - 8 * Y(i - 1) + 8 * Y(i + 1) - Y(i + 2));
    size_t l = m - 1;
    out[(l - 1) * s] = c * (3 * Y(l) + 10 * Y(l - 1) - 18 * Y(l - 2) + 6 * Y(l - 3) - Y(l - 4));
    out[l * s] = c * (25 * Y(l) - 48 * Y(l - 1) + 36 * Y(l - 2) - 16 * Y(l - 3) + 3 * Y(l - 4));
#undef Y
}

/* The cubic Hermite interpolant on a cell of width h (values y0, y1 and slopes s0, s1 at its
 * ends) as c0 + c1 x + c2 x² + c3 x³ in x = g - (its left end). */
static void cubic_coef(double h, double y0, double y1, double s0, double s1, double *c)
{
    double D = (y1 - y0) / h;
    c[0] = y0;
    c[1] = s0;
    c[2] = (3 * D - 2 * s0 - s1) / h;
    c[3] = (s0 + s1 - 2 * D) / (h * h);
}

/* The cubic c at x: value, slope and its integral from 0 to x (each may be NULL). */
static void cubic_at(const double *c, double x, double *y, double *dy, double *integ)
{
    if (y) *y = c[0] + x * (c[1] + x * (c[2] + x * c[3]));
    if (dy) *dy = c[1] + x * (2 * c[2] + x * 3 * c[3]);
    if (integ) *integ = x * (c[0] + x * (c[1] / 2 + x * (c[2] / 3 + x * c[3] / 4)));
}

/* The cell holding g (g_lo < g < g_hi): bins no wider than the narrowest cell give it, or the
 * cell before it (no logarithm in the solver's inner loop). */
static size_t cell(const sim_law *L, double g)
{
    size_t b = (size_t)((g - L->g_lo) * L->inv_bw), i;
    i = L->bin[b < L->nbin ? b : L->nbin - 1];
    while (i + 2 < L->n && g >= L->g[i + 1])
        i++;
    return i;
}

void sim_law_eval(const sim_law *L, double g, double *sigma, double *dsigma, double *work)
{
    double s, ds, d, dd, part = 0.0;
    if (!L->tabulated) {
        lj_eval(g, sigma, dsigma);
        if (work) *work = ljgap_sigma_work(g);
        return;
    }
    if (g >= L->g_hi) {
        *sigma = ljgap_sigma_smoothed(g, L->m0);
        *dsigma = ljgap_dsigma_smoothed(g, L->m0);
        if (work) *work = ljgap_sigma_work_smoothed(g, L->m0);
        return;
    }
    lj_eval(g, &s, &ds);
    if (g <= L->g_lo) {
        double x = L->g_lo - g;
        d = L->d[0] - L->dd[0] * x;
        dd = L->dd[0];
        part = L->I[0] + L->d[0] * x - 0.5 * L->dd[0] * x * x;
    } else {
        size_t i = cell(L, g);
        double F = 0.0;
        cubic_at(L->c + 4 * i, g - L->g[i], &d, &dd, work ? &F : NULL);
        part = L->I[i] - F;
    }
    *sigma = s + d;
    *dsigma = ds + dd;
    if (work) *work = ljgap_sigma_work(g) + L->D_hi + part;
}

double sim_law_work(const sim_law *L, double g)
{
    double s, ds, w;
    sim_law_eval(L, g, &s, &ds, &w);
    return w;
}

double sim_law_err(const sim_law *L, double g)
{
    if (!L->tabulated) return 0.0;
    if (g >= L->g_hi) return L->e_hi;
    if (g <= L->g_lo) return L->e[0];
    size_t i = cell(L, g);
    return fmax(L->e[i], L->e[i + 1]);
}

int sim_law_fine(sim_law *law, const ljgap_psd *fine, const ljgap_opts *o, ljgap_warnings *w)
{
    sim_law L;
    sim_law_lj(&L);
    L.tabulated = 1;
    L.m0 = fine->m0;
    L.g_lo = SIMLAW_G_LO;
    L.g_hi = fmax(SIMLAW_G_HI, 1.5 + 10.0 * sqrt(fine->m0));
    L.t0 = log(L.g_lo);
    size_t cells = (size_t)ceil((log(L.g_hi) - L.t0) / SIMLAW_DT);
    cells += cells % 2; /* even: the half table keeps both ends */
    L.n = cells + 1;
    L.dt = (log(L.g_hi) - L.t0) / (double)cells;
    L.g = malloc(9 * L.n * sizeof *L.g);
    for (size_t i = 0; L.g && i < L.n; i++)
        L.g[i] = exp(L.t0 + (double)i * L.dt);
    if (L.g) L.g[0] = L.g_lo, L.g[L.n - 1] = L.g_hi;
    L.inv_bw = L.g ? 1.0 / (L.g[1] - L.g[0]) : 0.0;
    L.nbin = (size_t)((L.g_hi - L.g_lo) * L.inv_bw) + 1;
    L.bin = malloc(L.nbin * sizeof *L.bin);
    ljgap_est *est = malloc(L.n * sizeof *est);
    double *half = malloc(L.n * sizeof *half);
    if (!L.g || !L.bin || !est || !half) {
        free(est);
        free(half);
        sim_law_free(&L);
        return LJGAP_ENOMEM;
    }
    L.d = L.g + L.n, L.dd = L.g + 2 * L.n, L.I = L.g + 3 * L.n, L.e = L.g + 4 * L.n;
    L.c = L.g + 5 * L.n;
    for (size_t b = 0, i = 0; b < L.nbin; b++) { /* the cell of each bin's left end */
        double x = L.g_lo + (double)b / L.inv_bw;
        while (i + 2 < L.n && x >= L.g[i + 1])
            i++;
        L.bin[b] = i;
    }
    int st = ljgap_traction(fine, o, L.g, L.n, est, &L.sum, w);
    if (st) {
        free(est);
        free(half);
        sim_law_free(&L);
        return st;
    }
    for (size_t i = 0; i < L.n; i++)
        L.d[i] = est[i].value - ljgap_sigma(L.g[i]);
    /* slopes in g from slopes in t = ln g; the half table's at the even nodes */
    fd_slopes(L.d, L.n, 1, L.dt, L.dd);
    fd_slopes(L.d, cells / 2 + 1, 2, 2 * L.dt, half);
    for (size_t i = 0; i < L.n; i++)
        L.dd[i] /= L.g[i];
    for (size_t i = 0; i < L.n; i += 2)
        half[i] /= L.g[i];
    /* interpolation error: the half table at the odd nodes */
    for (size_t i = 0; i < L.n; i++)
        L.e[i] = est[i].err;
    for (size_t i = 1; i < L.n; i += 2) {
        double c[4], y;
        cubic_coef(L.g[i + 1] - L.g[i - 1], L.d[i - 1], L.d[i + 1], half[i - 1], half[i + 1], c);
        cubic_at(c, L.g[i] - L.g[i - 1], &y, NULL, NULL);
        double ie = fabs(y - L.d[i]) / 8.0;
        for (size_t j = i - 1; j <= i + 1; j++)
            L.e[j] += ie;
    }
    /* the cells' cubics, and ∫_{g_i}^{g_hi} from the top (I has a last entry: 0) */
    L.I[L.n - 1] = 0.0;
    for (size_t i = L.n - 1; i-- > 0;) {
        double h = L.g[i + 1] - L.g[i], whole;
        cubic_coef(h, L.d[i], L.d[i + 1], L.dd[i], L.dd[i + 1], L.c + 4 * i);
        cubic_at(L.c + 4 * i, h, NULL, NULL, &whole);
        L.I[i] = L.I[i + 1] + whole;
    }
    L.D_hi = ljgap_sigma_work_smoothed(L.g_hi, L.m0) - ljgap_sigma_work(L.g_hi);
    double far = ljgap_sigma_smoothed(L.g_hi, L.m0) - ljgap_sigma(L.g_hi);
    L.e_hi = L.e[L.n - 1] + fabs(far - L.d[L.n - 1]);
    if (fabs(far - L.d[L.n - 1]) > 10.0 * o->tol)
        ljgap_warn(w,
                   "hybrid: the fine band's law differs from its far-field form by %.2g at "
                   "g = %g (included in its error)",
                   fabs(far - L.d[L.n - 1]), L.g_hi);
    /* the smallest slope, sampled */
    L.s_min = 0.0;
    for (size_t i = 0; i + 1 < L.n; i++)
        for (int q = 0; q < 4; q++) {
            double x = L.g[i] + 0.25 * q * (L.g[i + 1] - L.g[i]), s, ds;
            sim_law_eval(&L, x, &s, &ds, NULL);
            L.s_min = fmin(L.s_min, ds);
        }
    free(est);
    free(half);
    *law = L;
    return LJGAP_OK;
}
