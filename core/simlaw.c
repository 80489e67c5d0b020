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

/* The cubic Hermite interpolant on [a, b] (values ya, yb, slopes sa, sb in g) at x: value,
 * slope, and ∫_x^b. */
static void hermite(double a, double b, double ya, double yb, double sa, double sb, double x,
                    double *y, double *dy, double *integ)
{
    double h = b - a, s = (x - a) / h, s2 = s * s, s3 = s2 * s;
    double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
    if (y) *y = h00 * ya + h10 * h * sa + h01 * yb + h11 * h * sb;
    if (dy)
        *dy = (6 * s2 - 6 * s) * (ya - yb) / h + (3 * s2 - 4 * s + 1) * sa + (3 * s2 - 2 * s) * sb;
    if (integ) {
        /* antiderivatives of the basis in s, from s to 1 */
        double s4 = s2 * s2;
        double H00 = 0.5 - (s - s3 + 0.5 * s4),
               H10 = 1.0 / 12 - (0.5 * s2 - 2.0 / 3 * s3 + 0.25 * s4), H01 = 0.5 - (s3 - 0.5 * s4),
               H11 = -1.0 / 12 - (-s3 / 3 + 0.25 * s4);
        *integ = h * (H00 * ya + H10 * h * sa + H01 * yb + H11 * h * sb);
    }
}

/* The cell holding g (g_lo < g < g_hi). */
static size_t cell(const sim_law *L, double g)
{
    double x = (log(g) - L->t0) / L->dt;
    size_t i = x > 0 ? (size_t)x : 0;
    return i < L->n - 1 ? i : L->n - 2;
}

void sim_law_eval(const sim_law *L, double g, double *sigma, double *dsigma)
{
    double s, ds, d, dd;
    if (!L->tabulated) {
        lj_eval(g, sigma, dsigma);
        return;
    }
    if (g >= L->g_hi) {
        *sigma = ljgap_sigma_smoothed(g, L->m0);
        *dsigma = ljgap_dsigma_smoothed(g, L->m0);
        return;
    }
    lj_eval(g, &s, &ds);
    if (g <= L->g_lo) {
        d = L->d[0] + L->dd[0] * (g - L->g_lo);
        dd = L->dd[0];
    } else {
        size_t i = cell(L, g);
        hermite(L->g[i], L->g[i + 1], L->d[i], L->d[i + 1], L->dd[i], L->dd[i + 1], g, &d, &dd,
                NULL);
    }
    *sigma = s + d;
    *dsigma = ds + dd;
}

double sim_law_work(const sim_law *L, double g)
{
    if (!L->tabulated) return ljgap_sigma_work(g);
    if (g >= L->g_hi) return ljgap_sigma_work_smoothed(g, L->m0);
    double D;
    if (g <= L->g_lo) {
        double x = L->g_lo - g;
        D = L->I[0] + L->d[0] * x - 0.5 * L->dd[0] * x * x;
    } else {
        size_t i = cell(L, g);
        double part;
        hermite(L->g[i], L->g[i + 1], L->d[i], L->d[i + 1], L->dd[i], L->dd[i + 1], g, NULL, NULL,
                &part);
        D = L->I[i + 1] + part;
    }
    return ljgap_sigma_work(g) + L->D_hi + D;
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
    ljgap_est *est = malloc(L.n * sizeof *est);
    double *half = malloc(L.n * sizeof *half);
    if (!(L.g = malloc(5 * L.n * sizeof *L.g)) || !est || !half) {
        free(est);
        free(half);
        sim_law_free(&L);
        return LJGAP_ENOMEM;
    }
    L.d = L.g + L.n, L.dd = L.g + 2 * L.n, L.I = L.g + 3 * L.n, L.e = L.g + 4 * L.n;
    for (size_t i = 0; i < L.n; i++)
        L.g[i] = exp(L.t0 + (double)i * L.dt);
    L.g[0] = L.g_lo, L.g[L.n - 1] = L.g_hi;
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
        double y;
        hermite(L.g[i - 1], L.g[i + 1], L.d[i - 1], L.d[i + 1], half[i - 1], half[i + 1], L.g[i],
                &y, NULL, NULL);
        double ie = fabs(y - L.d[i]) / 8.0;
        for (size_t j = i - 1; j <= i + 1; j++)
            L.e[j] += ie;
    }
    /* integrals from the top, and the far field */
    L.I[L.n - 1] = 0.0;
    for (size_t i = L.n - 1; i-- > 0;) {
        double part;
        hermite(L.g[i], L.g[i + 1], L.d[i], L.d[i + 1], L.dd[i], L.dd[i + 1], L.g[i], NULL, NULL,
                &part);
        L.I[i] = L.I[i + 1] + part;
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
            sim_law_eval(&L, x, &s, &ds);
            L.s_min = fmin(L.s_min, ds);
        }
    free(est);
    free(half);
    *law = L;
    return LJGAP_OK;
}
