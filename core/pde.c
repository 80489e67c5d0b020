/* pde.c -- the continuum limit of the paper's iteration (theory.md §2).
 *
 * The update (18) with the packet variance (17) is one Euler step of the Itô process
 *     dG = f(G,k) √(2π k P(k)) dW_k,   G(k1) = g_ave,
 * so as the bands shrink the gap PDF Phi(g,k) obeys the Fokker-Planck equation and the mean
 * traction (21) the backward Kolmogorov equation. With the generator
 *     (L u)(g) = a(g,k) u''(g),   a = π k P(k) f(g,k)^2   (per unit k),
 *   forward:   dPhi/dk = (a Phi)'',          Phi(k1) = delta(g - g_ave)   -> gap PDFs;
 *   backward:  du/dk = -a u'',               u(g, k2) = sigma(g)/sigma0   -> u(g_ave, k1)
 *              is sigma_bar(g_ave)/sigma0 for every g_ave at once (one solve per curve).
 *
 * Discretisation.
 *  - Gap: a geometric grid g_i = exp(xi0 + i dxi) (relative resolution, right for the
 *    g^-9 wall and the g^-3 tail), the three-point second difference for non-uniform
 *    grids (exact on linear functions), and frozen end points. The discrete generator
 *    annihilates 1 and g, so the forward scheme, built as the exact transpose of the
 *    backward one, conserves mass and mean (the martingale property) to rounding.
 *  - Wavenumber: Crank-Nicolson steps uniform in zeta(k) = ln(k - k0) + beta tau(k)/m0,
 *    where tau is the cumulative variance: ln(k - k0) puts steps where f changes fast
 *    (stiff starts with k1 near k0, the near-wall switch-on at large k, which a march in
 *    tau alone misses: theory.md §3) and tau where the variance is (march.c). Forward
 *    solves: steps DZETA0_FWD at level 0, the first two at k1 as four backward-Euler half steps
 *    (Rannacher), which damps the delta start. Backward solves: steps DZETA0_BWD, all
 *    Crank-Nicolson (their start, sigma(g) at the far end, is smooth), done by fold.c.
 *  - Infinite k2: march to kmax where f(g_lo,kmax) ≈ 1 on the whole grid, then add the
 *    remaining variance m0 - tau(kmax) in steps uniform in tau with a = f^2/2 per unit tau
 *    at k(tau): for D near 3 that tail is not small, and f is not yet 1 near the wall.
 *  - Resolution levels L = 0,1,2,... halve dxi and every step; level L+1 contains the nodes
 *    of level L (the march's nodes are found once per request: zeta_nodes). Richardson
 *    extrapolation R_L = v_L + (v_L - v_{L-1})/3 removes the h^2 term (second order,
 *    checked by the tests). The error estimate of R_L is |R_L - R_{L-1}|/2 for tractions
 *    (RICH_ERR_DIV), |R_L - R_{L-1}| for gap PDFs (whose backward-Euler start leaves an h^3
 *    term). Levels rise until the estimate is below tol*max(1,|v|) or a cap is reached (then a
 *    warning says so).
 *  - Lower grid end: where paths freeze depends on the spectrum (theory.md §3), so it is
 *    lowered until moving it once more changes the answer by less than the tolerance; that
 *    change is added to the error estimate.
 */
#include "ljgap.h"
#include "core.h" /* the core's internals */
#include "fold.h"
#include "march.h"
#include "pde.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DXI0 0.02       /* relative grid spacing at level 0 */
#define MAX_LEVEL 7     /* at most 2^7 times the level-0 resolution */
#define G_HI_MIN 60.0   /* upper end of the traction grid, at least */
#define G_LO_FLOOR 0.04 /* never put the lower end below this (or half the lowest gap asked) */
#define G_LO_FACTOR 0.8 /* each lowering of the lower end */
/* The Richardson value R_L has no h^2 term; what is left falls by 2^p per level with p >= 3
 * (measured over the level ladders of 108 spectra: p = 4.0 in the median, 3.1 at the lowest),
 * so |R_L - R_{L-1}| >= (2^3 - 1) err(R_L) once the levels are in the asymptotic range. The
 * estimate |R_L - R_{L-1}| / 2 keeps a factor 3.5 for levels that are not yet there
 * (bench/stability.c measures how often it holds; test_pde checks p >= 3). */
#define RICH_ERR_DIV 2.0

/* ---- the gap grid ---- */
typedef struct {
    size_t n;   /* number of nodes */
    double *g;  /* nodes */
    double *A;  /* 9 g^-10 - 3 g^-4, so f = k/(k + A) */
    double *lo; /* second-difference weights: (D2 u)_i = lo_i u_{i-1} - (lo_i+hi_i) u_i + hi_i
                   u_{i+1} */
    double *hi;
    double *wt; /* cell widths (for densities) */
} pde_grid;

/* The arrays share one block that starts at g. */
static void grid_free(pde_grid *G)
{
    free(G->g);
    memset(G, 0, sizeof *G);
}

static int grid_make(pde_grid *G, double xi0, double dxi, size_t n)
{
    memset(G, 0, sizeof *G);
    double *b = calloc(5 * n, sizeof(double)); /* zeros: lo = hi = 0 freeze the end rows */
    if (!b) return LJGAP_ENOMEM;
    G->n = n;
    G->g = b;
    G->A = b + n;
    G->lo = b + 2 * n;
    G->hi = b + 3 * n;
    G->wt = b + 4 * n;
    for (size_t i = 0; i < n; i++) {
        double g = exp(xi0 + (double)i * dxi);
        double g2 = g * g, g4 = g2 * g2, g10 = g4 * g4 * g2;
        G->g[i] = g;
        G->A[i] = 9.0 / g10 - 3.0 / g4;
    }
    for (size_t i = 1; i + 1 < n; i++) {
        double hm = G->g[i] - G->g[i - 1], hp = G->g[i + 1] - G->g[i];
        G->lo[i] = 2.0 / (hm * (hm + hp));
        G->hi[i] = 2.0 / (hp * (hm + hp));
    }
    for (size_t i = 0; i < n; i++) {
        double hm = i > 0 ? G->g[i] - G->g[i - 1] : 0, hp = i + 1 < n ? G->g[i + 1] - G->g[i] : 0;
        G->wt[i] = 0.5 * (hm + hp);
    }
    return LJGAP_OK;
}

/* ---- time stepping ---- */
typedef struct {
    double *mem;                /* one block holding every array below */
    double *fa, *fb;            /* f^2 on the grid at the two ends of the current step */
    double kb_cur;              /* which step's upper end fb belongs to (NAN: none) */
    double *ca, *cb;            /* coefficients s*f^2 at the two ends of a step */
    double *dl, *dd, *du, *rhs; /* tridiagonal system */
    double *tmp;
} pde_work;

static void work_free(pde_work *W)
{
    free(W->mem);
    memset(W, 0, sizeof *W);
}

static int work_alloc(pde_work *W, size_t n)
{
    memset(W, 0, sizeof *W);
    double *b = malloc(9 * n * sizeof(double));
    if (!b) return LJGAP_ENOMEM;
    double **arr[9] = {&W->fa, &W->fb, &W->ca, &W->cb, &W->dl, &W->dd, &W->du, &W->rhs, &W->tmp};
    for (int i = 0; i < 9; i++)
        *arr[i] = b + (size_t)i * n;
    W->mem = b;
    W->kb_cur = NAN;
    return LJGAP_OK;
}

/* Thomas algorithm, in place: dl sub, dd diag, du super, rhs -> solution. */
static void tridiag(size_t n, double *dl, double *dd, double *du, double *x)
{
    for (size_t i = 1; i < n; i++) {
        double w = dl[i] / dd[i - 1];
        dd[i] -= w * du[i - 1];
        x[i] -= w * x[i - 1];
    }
    x[n - 1] /= dd[n - 1];
    for (size_t i = n - 1; i-- > 0;)
        x[i] = (x[i] - du[i] * x[i + 1]) / dd[i];
}

/* p <- S^T p: solve (I - theta Ba)^T y = p, then p = (I + (1-theta) Bb)^T y. */
static void step_forward(const pde_grid *G, pde_work *W, const pde_step *st, double *p)
{
    size_t n = G->n;
    const double *lo = G->lo, *hi = G->hi;
    double th = st->theta;
    for (size_t i = 0; i < n; i++) {
        W->ca[i] = st->sa * W->fa[i];
        W->cb[i] = st->sb * W->fb[i];
    }
    for (size_t i = 0; i < n; i++) {
        W->dd[i] = 1.0 + th * W->ca[i] * (lo[i] + hi[i]);
        W->dl[i] = i > 0 ? -th * W->ca[i - 1] * hi[i - 1] : 0;
        W->du[i] = i + 1 < n ? -th * W->ca[i + 1] * lo[i + 1] : 0;
        W->rhs[i] = p[i];
    }
    tridiag(n, W->dl, W->dd, W->du, W->rhs);
    const double *y = W->rhs;
    double *v = W->tmp;
    for (size_t i = 0; i < n; i++)
        v[i] = W->cb[i] * y[i];
    for (size_t i = 0; i < n; i++) {
        /* (D2^T v)_i = hi_{i-1} v_{i-1} - (lo_i + hi_i) v_i + lo_{i+1} v_{i+1} */
        double t = -(lo[i] + hi[i]) * v[i];
        if (i > 0) t += hi[i - 1] * v[i - 1];
        if (i + 1 < n) t += lo[i + 1] * v[i + 1];
        p[i] = y[i] + (1.0 - th) * t;
    }
}

/* f(g_i,k)^2 on the grid (1 at k = infinity). */
static void fsq(const pde_grid *G, double k, double *f2)
{
    if (isinf(k)) {
        for (size_t i = 0; i < G->n; i++)
            f2[i] = 1.0;
        return;
    }
    for (size_t i = 0; i < G->n; i++) {
        double f = k / (k + G->A[i]);
        f2[i] = f * f;
    }
}

/* Make W->fa/W->fb hold f^2 at the ends of step st, reusing the previous step's upper end
 * when the march moves on by one node. */
static void fsq_step(const pde_grid *G, pde_work *W, const pde_step *st)
{
    if (W->kb_cur == st->ka) {
        double *t = W->fa;
        W->fa = W->fb, W->fb = t;
    } else {
        fsq(G, st->ka, W->fa);
    }
    fsq(G, st->kb, W->fb);
    W->kb_cur = st->kb;
}

/* ---- domain ---- */

/* Upper bound S^2 of the gap variance: ∫ 2π k P f_max(k)^2 dk with f_max = k/(k - k0). */
static double variance_bound(const ljgap_psd *psd)
{
    const double k0 = ljgap_k0();
    double k2 = isinf(psd->k2) ? 1e12 * psd->k1 : psd->k2;
    /* trapezoid in ln(k - k0) on 400 panels, plus the tail as f = 1 */
    double xa = log(psd->k1 - k0), xb = log(k2 - k0), sum = 0;
    int np = 400;
    for (int i = 0; i <= np; i++) {
        double k = k0 + exp(xa + (xb - xa) * i / np);
        double f = k / (k - k0);
        double v = 2.0 * M_PI * k * ljgap_psd_eval(psd, k) * f * f * (k - k0);
        sum += (i == 0 || i == np ? 0.5 : 1.0) * v;
    }
    sum *= (xb - xa) / np;
    sum += psd->m0 - ljgap_psd_cumvar(psd, k2);
    return fmax(sum, psd->m0);
}

/* ---- one solve at one level ---- */
typedef struct {
    const ljgap_psd *psd;
    const ljgap_opts *o;
    double deadline;
    long work;        /* grid points x steps spent */
    zeta_nodes nodes; /* the march nodes found so far */
} pde_ctx;

/* Which cap stopped a computation, for the warnings. */
static const char *cap_reason(const pde_ctx *C)
{
    return ljgap__now() > C->deadline ? "time cap (max_seconds)" : "work cap (max_work)";
}

/* Backward solve: u on the grid of level L between ln g_lo and ln g_hi (fold.c steps); the
 * march's end follows g_k <= g_lo (see ljgap__march_make). */
static int solve_curve(pde_ctx *C, double g_lo, double g_k, double g_hi, int L, pde_grid *G,
                       double **uout)
{
    double dxi = DXI0 / ldexp(1.0, L);
    size_t n0 = (size_t)ceil(log(g_hi / g_lo) / DXI0);
    n0 += n0 % 2; /* an odd number of nodes at every level (fold.c) */
    size_t n = n0 * ((size_t)1 << L) + 1;
    double cut = INFINITY;
    if (isfinite(C->psd->k2)) cut = C->psd->k2;
    pde_march M = {0};
    ljgap__fold F = {0};
    double *u = NULL;
    /* anchored at g_hi, so that a lower g_lo only adds nodes below */
    int st = grid_make(G, log(g_hi) - (double)n0 * DXI0, dxi, n);
    if (st) return st;
    st = ljgap__march_make(&M, C->psd, &cut, 1, L, g_k, 1, &C->nodes);
    if (st) goto fail;
    if ((double)C->work + (double)n * (double)M.m > (double)C->o->max_work) {
        st = LJGAP_ECAP;
        goto fail;
    }
    st = ljgap__fold_make(&F, n, G->A, G->lo, G->hi);
    if (st) goto fail;
    u = malloc(n * sizeof *u);
    if (!u) {
        st = LJGAP_ENOMEM;
        goto fail;
    }
    for (size_t i = 0; i < n; i++)
        u[i] = ljgap_sigma(G->g[i]);
    ljgap__fold_put(&F, u, F.x);
    for (size_t j = M.m; j-- > 0;) {
        const pde_step *s = &M.s[j];
        ljgap__fold_back(&F, s->ka, s->kb, s->theta * s->sa, (1.0 - s->theta) * s->sb);
        if ((j & 31) == 0 && ljgap__should_stop(C->o, C->deadline)) {
            st = (C->o->cancel && *C->o->cancel) ? LJGAP_ECANCEL : LJGAP_ECAP;
            goto fail;
        }
    }
    C->work += (long)(n * M.m);
    ljgap__fold_get(&F, F.x, u);
    for (size_t i = 0; i < n; i++)
        if (!isfinite(u[i])) {
            st = LJGAP_EFAIL;
            goto fail;
        }
    ljgap__fold_free(&F);
    ljgap__march_free(&M);
    *uout = u;
    return LJGAP_OK;
fail:
    ljgap__march_free(&M);
    ljgap__fold_free(&F);
    free(u);
    grid_free(G);
    return st;
}

/* Everything a traction solve reports, at one level and one lower end. */
typedef struct {
    size_t n;
    double *sig; /* sigma at the requested points */
    ljgap_summary sum;
    int sum_ok;
} curve_result;

static void curve_result_free(curve_result *r)
{
    free(r->sig);
    r->sig = NULL;
}

static int curve_at(pde_ctx *C, double g_lo, double g_k, double g_hi, int L, const double *g_ave,
                    size_t n, curve_result *R, ljgap_warnings *w)
{
    pde_grid G;
    double *u = NULL;
    memset(R, 0, sizeof *R);
    int st = solve_curve(C, g_lo, g_k, g_hi, L, &G, &u);
    if (st) return st;
    R->n = n;
    R->sig = malloc((n ? n : 1) * sizeof(double));
    if (!R->sig) {
        st = LJGAP_ENOMEM;
        goto end;
    }
    /* values at requested points: degree 5 through the six nearest nodes (Lagrange in xi,
     * where the nodes are uniform). Its error, O(dxi^6), changes with the point's place
     * between the nodes from level to level, so it must stay far below the scheme's error
     * (a cubic left ~1e-9 to 2e-8 that no extrapolation removes). */
    static const double den[6] = {-120, 24, -12, 12, -24, 120}; /* prod_{b!=a} (a-b) */
    double xi0 = log(G.g[0]), dxi = log(G.g[1]) - xi0;
    for (size_t j = 0; j < n; j++) {
        double x = (log(g_ave[j]) - xi0) / dxi;
        long i = (long)floor(x) - 2;
        if (i < 0) i = 0;
        if (i > (long)G.n - 6) i = (long)G.n - 6;
        double t = x - (double)i, v = 0;
        for (int a = 0; a < 6; a++) {
            double l = 1;
            for (int b = 0; b < 6; b++)
                if (b != a) l *= t - b;
            v += l / den[a] * u[i + a];
        }
        R->sig[j] = v;
    }
    R->sum_ok = ljgap__curve_summary(G.g, u, G.n, C->psd->m0, &R->sum, w) == LJGAP_OK;
end:
    free(u);
    grid_free(&G);
    if (st) curve_result_free(R);
    return st;
}

/* Largest relative difference between two results over everything reported. */
static double curve_diff(const curve_result *a, const curve_result *b, int with_sum)
{
    double d = 0;
    for (size_t j = 0; j < a->n; j++)
        d = fmax(d, fabs(a->sig[j] - b->sig[j]) / fmax(1.0, fabs(b->sig[j])));
    if (with_sum && a->sum_ok && b->sum_ok) {
        const ljgap_est *x = &a->sum.g_eq, *y = &b->sum.g_eq;
        for (int q = 0; q < 4; q++)
            d = fmax(d, fabs(x[q].value - y[q].value) / fmax(1.0, fabs(y[q].value)));
    }
    return d;
}

int ljgap__traction_pde(const ljgap_psd *psd, const ljgap_opts *o, const double *g_ave, size_t n,
                        ljgap_est *sigma, ljgap_summary *sum, ljgap_warnings *w)
{
    pde_ctx C = {.psd = psd, .o = o, .deadline = ljgap__now() + o->max_seconds};
    double gmin = 1.0, gmax = 1.0;
    for (size_t j = 0; j < n; j++)
        gmin = fmin(gmin, g_ave[j]), gmax = fmax(gmax, g_ave[j]);
    double S = sqrt(variance_bound(psd));
    double g_hi = fmax(G_HI_MIN, fmax(3.0 * gmax, gmax + 30.0 * S));
    g_hi = fmax(g_hi, 12.0 * sqrt(psd->m0)); /* the analytic tail needs m0/g_hi^2 <= 0.01 */
    double lo_floor = fmin(G_LO_FLOOR, 0.5 * gmin);
    double g_lo = fmax(0.6 * gmin, lo_floor / G_LO_FACTOR);
    int want_sum = sum != NULL;
    curve_result A = {0}, B = {0}, P = {0};
    int st;
    double trunc = 0; /* error from the lower end */

    /* Lower the lower end until the level-0 answer stops changing. The two solves compared
     * share the march (its end follows the lower of the two ends), so that their difference
     * is what the grid's end does and not a change of the level-0 discretisation (which
     * alone is ~1e-7 for Fig. 4 and would ask for needless lowerings). */
    st = curve_at(&C, g_lo, g_lo * G_LO_FACTOR, g_hi, 0, g_ave, n, &A, w);
    if (st) goto end;
    for (;;) {
        double g2 = g_lo * G_LO_FACTOR;
        st = curve_at(&C, g2, g2, g_hi, 0, g_ave, n, &B, w);
        if (st) goto end;
        double d = curve_diff(&A, &B, want_sum);
        curve_result_free(&A);
        A = B;
        B = (curve_result){0};
        g_lo = g2;
        trunc = d;
        if (d < 0.1 * o->tol) break;
        if (g_lo * G_LO_FACTOR < lo_floor) {
            ljgap_warn(w,
                       "moving the lower grid end to g = %g still changes the answer by %.2g "
                       "(relative): paths reach the wall region; the error includes this",
                       g_lo, d);
            break;
        }
        /* the next comparison's upper solve: this end, the next end's march */
        curve_result_free(&A);
        st = curve_at(&C, g_lo, g_lo * G_LO_FACTOR, g_hi, 0, g_ave, n, &A, w);
        if (st) goto end;
    }
    /* Refine. v_L: the answer at level L; R_L = v_L + (v_L - v_{L-1})/3 removes the h^2
     * term, and R_L converges at order 3.5-4 (see RICH_ERR_DIV); the error estimate of R_L is
     * |R_L - R_{L-1}| / RICH_ERR_DIV, plus the lower-end change. */
    double est = INFINITY;
    int L = 0, nR = 0;
    for (;;) {
        st = curve_at(&C, g_lo, g_lo, g_hi, L + 1, g_ave, n, &B, w);
        if (st == LJGAP_ECAP && L > 0) {
            ljgap_warn(w,
                       "%s reached at resolution level %d: the error estimate is above the "
                       "requested tolerance",
                       cap_reason(&C), L);
            st = LJGAP_OK;
            break;
        }
        if (st) goto end;
        if (want_sum && !B.sum_ok) {
            st = LJGAP_EFAIL;
            goto end;
        }
        /* B <- Richardson(B, A); P keeps the previous Richardson value */
        for (size_t j = 0; j < n; j++) {
            double d = B.sig[j] - A.sig[j];
            A.sig[j] = B.sig[j];
            B.sig[j] += d / 3.0;
        }
        ljgap_est *x = &B.sum.g_eq, *y = &A.sum.g_eq;
        for (int q = 0; q < 4; q++) {
            double d = x[q].value - y[q].value;
            y[q].value = x[q].value;
            x[q].value += d / 3.0;
            x[q].err = fabs(d) / 3.0; /* two-level estimate, used if no third level */
        }
        for (size_t j = 0; j < n; j++)
            sigma[j].err = fabs(A.sig[j] - B.sig[j]);
        /* now A = plain level L+1, B = Richardson at L+1 */
        if (nR > 0) {
            est = curve_diff(&B, &P, want_sum) / RICH_ERR_DIV + trunc;
            for (size_t j = 0; j < n; j++)
                sigma[j].err = fabs(B.sig[j] - P.sig[j]) / RICH_ERR_DIV;
            ljgap_est *p = &P.sum.g_eq;
            for (int q = 0; q < 4; q++)
                x[q].err = fabs(x[q].value - p[q].value) / RICH_ERR_DIV;
        } else {
            est = curve_diff(&B, &A, want_sum) + trunc;
        }
        curve_result_free(&P);
        P = B;
        B = (curve_result){0};
        nR++;
        L++;
        if (nR >= 2 && est <= o->tol) break;
        if (L >= MAX_LEVEL) {
            ljgap_warn(w, "finest resolution level reached: the error estimate is above the "
                          "requested tolerance");
            break;
        }
    }
    /* P holds the last Richardson values with their error estimates */
    for (size_t j = 0; j < n; j++) {
        sigma[j].value = P.sig[j];
        sigma[j].err += trunc * fmax(1.0, fabs(P.sig[j]));
    }
    if (want_sum) {
        *sum = P.sum;
        ljgap_est *x = &sum->g_eq;
        for (int q = 0; q < 4; q++)
            x[q].err += trunc * fmax(1.0, fabs(x[q].value));
    }
    st = LJGAP_OK;
end:
    curve_result_free(&A);
    curve_result_free(&B);
    curve_result_free(&P);
    ljgap__nodes_free(&C.nodes);
    return st;
}

/* ---- gap PDFs ---- */

/* Forward solve at level L on a grid that has g_ave as a node; snapshots of the discrete
 * masses at each cut. */
static int solve_pdf(pde_ctx *C, double g_ave, double g_lo, double g_hi, const double *cuts,
                     size_t nc, int L, pde_grid *G, double **snaps)
{
    double dxi = DXI0 / ldexp(1.0, L);
    double lx = log(g_ave);
    size_t below = (size_t)ceil((lx - log(g_lo)) / DXI0);
    size_t above = (size_t)ceil((log(g_hi) - lx) / DXI0);
    if (below < 4) below = 4;
    if (above < 4) above = 4;
    size_t scale = (size_t)1 << L;
    size_t n = (below + above) * scale + 1, i0 = below * scale;
    pde_march M;
    pde_work W = {0};
    double *p = NULL;
    int st = grid_make(G, lx - (double)i0 * dxi, dxi, n);
    if (st) return st;
    st = ljgap__march_make(&M, C->psd, cuts, nc, L, g_lo, 0, &C->nodes);
    if (st) goto fail;
    if ((double)C->work + (double)n * (double)M.m > (double)C->o->max_work) {
        st = LJGAP_ECAP;
        goto fail_m;
    }
    st = work_alloc(&W, n);
    if (st) goto fail_m;
    p = calloc(n, sizeof *p);
    if (!p) {
        st = LJGAP_ENOMEM;
        goto fail_m;
    }
    for (size_t c = 0; c < nc; c++)
        snaps[c] = NULL;
    p[i0] = 1.0;
    for (size_t j = 0; j < M.m; j++) {
        fsq_step(G, &W, &M.s[j]);
        step_forward(G, &W, &M.s[j], p);
        if (M.s[j].snap >= 0) {
            double *s = malloc(n * sizeof *s);
            if (!s) {
                st = LJGAP_ENOMEM;
                goto fail_m;
            }
            memcpy(s, p, n * sizeof *s);
            snaps[M.s[j].snap] = s;
        }
        if ((j & 31) == 0 && ljgap__should_stop(C->o, C->deadline)) {
            st = (C->o->cancel && *C->o->cancel) ? LJGAP_ECANCEL : LJGAP_ECAP;
            goto fail_m;
        }
    }
    C->work += (long)(n * M.m);
    for (size_t c = 0; c < nc; c++)
        if (!snaps[c]) {
            st = LJGAP_EFAIL;
            goto fail_m;
        }
    free(p);
    work_free(&W);
    ljgap__march_free(&M);
    return LJGAP_OK;
fail_m:
    ljgap__march_free(&M);
    for (size_t c = 0; c < nc; c++)
        free(snaps[c]), snaps[c] = NULL;
fail:
    free(p);
    work_free(&W);
    grid_free(G);
    return st;
}

typedef struct {
    pde_grid G;
    double **p; /* nc snapshots of masses */
} pdf_level;

static void pdf_level_free(pdf_level *P, size_t nc)
{
    if (P->p)
        for (size_t c = 0; c < nc; c++)
            free(P->p[c]);
    free(P->p);
    grid_free(&P->G);
    P->p = NULL;
}

static int pdf_level_run(pde_ctx *C, double g_ave, double g_lo, double g_hi, const double *cuts,
                         size_t nc, int L, pdf_level *P)
{
    P->p = calloc(nc, sizeof *P->p);
    if (!P->p) return LJGAP_ENOMEM;
    int st = solve_pdf(C, g_ave, g_lo, g_hi, cuts, nc, L, &P->G, P->p);
    if (st) {
        free(P->p);
        P->p = NULL;
    }
    return st;
}

/* sigma of a snapshot: Σ p_i sigma(g_i) */
static double snap_sigma(const pde_grid *G, const double *p)
{
    double s = 0;
    for (size_t i = 0; i < G->n; i++)
        s += p[i] * ljgap_sigma(G->g[i]);
    return s;
}

int ljgap__pdf_pde(const ljgap_psd *psd, const ljgap_opts *o, double g_ave, const double *k2,
                   size_t nk2, const double *grid, ljgap_pdf *out, ljgap_warnings *w)
{
    pde_ctx C = {.psd = psd, .o = o, .deadline = ljgap__now() + o->max_seconds};
    /* march through the cuts in increasing order; out[] keeps the request's order */
    size_t *ord = malloc((nk2 ? nk2 : 1) * sizeof *ord);
    double *cuts = malloc((nk2 ? nk2 : 1) * sizeof *cuts);
    pdf_level A = {0}, B = {0};
    int st = LJGAP_ENOMEM;
    if (!ord || !cuts) goto end;
    for (size_t i = 0; i < nk2; i++)
        ord[i] = i;
    for (size_t i = 1; i < nk2; i++)
        for (size_t j = i; j > 0 && k2[ord[j]] < k2[ord[j - 1]]; j--) {
            size_t t = ord[j];
            ord[j] = ord[j - 1];
            ord[j - 1] = t;
        }
    for (size_t i = 0; i < nk2; i++)
        cuts[i] = fmin(k2[ord[i]], psd->k2);
    double S = sqrt(variance_bound(psd));
    double g_hi = g_ave + 10.0 * S;
    double g_lo = fmax(fmin(0.6, 0.6 * g_ave), g_ave - 10.0 * S);
    double lo_floor = fmin(G_LO_FLOOR, 0.5 * g_ave);
    g_lo = fmax(g_lo, lo_floor);
    /* lower end: lower while the snapshot tractions change at level 0 */
    st = pdf_level_run(&C, g_ave, g_lo, g_hi, cuts, nk2, 0, &A);
    if (st) goto end;
    double trunc = 0;
    while (g_lo > lo_floor && g_lo > g_ave - 10.0 * S) {
        double g2 = fmax(g_lo * G_LO_FACTOR, lo_floor);
        st = pdf_level_run(&C, g_ave, g2, g_hi, cuts, nk2, 0, &B);
        if (st) goto end;
        double d = 0;
        for (size_t c = 0; c < nk2; c++) {
            double a = snap_sigma(&A.G, A.p[c]), b = snap_sigma(&B.G, B.p[c]);
            d = fmax(d, fabs(a - b) / fmax(1.0, fabs(b)));
        }
        pdf_level_free(&A, nk2);
        A = B;
        B = (pdf_level){0};
        g_lo = g2;
        trunc = d;
        if (d < 0.1 * o->tol) break;
        if (g_lo <= lo_floor) {
            ljgap_warn(w, "probability reaches the lower grid end g = %g", g_lo);
            break;
        }
    }
    /* Refine. Per snapshot: sigma and the density phi at the nodes of the coarser of the
     * two finest levels, both Richardson-extrapolated (R = fine + (fine - coarse)/3); the
     * error estimates compare R with the previous R (sigma; phi in L1 on the common nodes). */
    int L = 0, nR = 0;
    double *sig_prev = calloc(nk2, sizeof *sig_prev), *sig_cur = calloc(nk2, sizeof *sig_cur);
    double *l1 = calloc(nk2, sizeof *l1), *serr = calloc(nk2, sizeof *serr);
    double **ext = calloc(nk2, sizeof *ext);
    pde_grid *eg = &A.G; /* grid on whose nodes ext lives (A's, once A is the coarser) */
    pdf_level E = {0};   /* keeps the grid of ext */
    if (!sig_prev || !sig_cur || !l1 || !serr || !ext) {
        st = LJGAP_ENOMEM;
        goto done;
    }
    for (;;) {
        st = pdf_level_run(&C, g_ave, g_lo, g_hi, cuts, nk2, L + 1, &B);
        if (st == LJGAP_ECAP && nR > 0) {
            ljgap_warn(w,
                       "%s reached at resolution level %d: the error estimate is above the "
                       "requested tolerance",
                       cap_reason(&C), L);
            st = LJGAP_OK;
            break;
        }
        if (st) break;
        double est = 0;
        for (size_t c = 0; c < nk2; c++) {
            double sa = snap_sigma(&A.G, A.p[c]), sb = snap_sigma(&B.G, B.p[c]);
            double r = sb + (sb - sa) / 3.0;
            serr[c] = nR > 0 ? fabs(r - sig_prev[c]) : fabs(sb - sa) / 3.0;
            sig_prev[c] = r;
            sig_cur[c] = r;
            est = fmax(est, serr[c] / fmax(1.0, fabs(r)));
            /* extrapolated density on A's nodes */
            double *e = malloc(A.G.n * sizeof *e);
            if (!e) {
                st = LJGAP_ENOMEM;
                break;
            }
            for (size_t i = 0; i < A.G.n; i++) {
                double pc = A.p[c][i] / A.G.wt[i], pf = B.p[c][2 * i] / B.G.wt[2 * i];
                e[i] = pf + (pf - pc) / 3.0;
            }
            if (nR > 0) { /* ext_old lives on the even nodes of A */
                double d = 0;
                for (size_t i = 0; 2 * i < A.G.n; i++)
                    d += fabs(e[2 * i] - ext[c][i]) * E.G.wt[i];
                l1[c] = d;
            } else {
                double d = 0;
                for (size_t i = 0; i < A.G.n; i++)
                    d += fabs(e[i] - B.p[c][2 * i] / B.G.wt[2 * i]) * A.G.wt[i];
                l1[c] = d;
            }
            free(ext[c]);
            ext[c] = e;
            est = fmax(est, l1[c]);
        }
        if (st) break;
        /* A (level L) becomes the grid of ext; B becomes the new A */
        pdf_level_free(&E, nk2);
        E = A;
        A = B;
        B = (pdf_level){0};
        eg = &E.G;
        L++;
        nR++;
        if (nR >= 2 && est <= o->tol) break;
        if (L >= MAX_LEVEL - 1) {
            ljgap_warn(w, "finest resolution level reached: the error estimate is above the "
                          "requested tolerance");
            break;
        }
    }
    if (st == LJGAP_OK) {
        /* output the extrapolated density on eg's nodes; mass and mean of the finest
         * discrete solution (the invariants of the scheme) */
        const pde_grid *G = eg;
        for (size_t c = 0; c < nk2 && st == LJGAP_OK; c++) {
            ljgap_pdf *P = &out[ord[c]];
            const double *phi = ext[c];
            P->k2 = k2[ord[c]];
            double mass = 0, mean = 0;
            for (size_t i = 0; i < A.G.n; i++)
                mass += A.p[c][i], mean += A.p[c][i] * A.G.g[i];
            P->mass = mass;
            P->mean = mean;
            P->sigma.value = sig_cur[c];
            P->sigma.err = serr[c] + trunc * fmax(1.0, fabs(sig_cur[c]));
            P->phi_err = l1[c];
            if (grid) {
                size_t m = (size_t)grid[2];
                P->n = m;
                P->g = malloc(m * sizeof(double));
                P->phi = malloc(m * sizeof(double));
                if (!P->g || !P->phi) {
                    st = LJGAP_ENOMEM;
                    break;
                }
                size_t i = 0;
                for (size_t q = 0; q < m; q++) {
                    double x = grid[0] + (grid[1] - grid[0]) * (double)q / (double)(m - 1);
                    P->g[q] = x;
                    if (x < G->g[0] || x > G->g[G->n - 1]) {
                        P->phi[q] = 0;
                        continue;
                    }
                    while (i + 2 < G->n && G->g[i + 1] < x)
                        i++;
                    double t = (x - G->g[i]) / (G->g[i + 1] - G->g[i]);
                    P->phi[q] = (1 - t) * phi[i] + t * phi[i + 1];
                }
            } else {
                /* the nodes where the density is not negligible, at most ~2000 */
                double pmax = 0;
                for (size_t i = 0; i < G->n; i++)
                    pmax = fmax(pmax, phi[i]);
                size_t a0 = 0, b0 = G->n - 1;
                while (a0 < b0 && fabs(phi[a0]) < 1e-12 * pmax)
                    a0++;
                while (b0 > a0 && fabs(phi[b0]) < 1e-12 * pmax)
                    b0--;
                a0 = a0 > 0 ? a0 - 1 : a0;
                b0 = b0 + 1 < G->n ? b0 + 1 : b0;
                size_t stride = 1;
                while ((b0 - a0) / stride > 2000)
                    stride++;
                size_t m = (b0 - a0) / stride + 1;
                P->n = m;
                P->g = malloc(m * sizeof(double));
                P->phi = malloc(m * sizeof(double));
                if (!P->g || !P->phi) {
                    st = LJGAP_ENOMEM;
                    break;
                }
                for (size_t q = 0; q < m; q++) {
                    P->g[q] = G->g[a0 + q * stride];
                    P->phi[q] = phi[a0 + q * stride];
                }
            }
        }
    }
done:
    if (ext)
        for (size_t c = 0; c < nk2; c++)
            free(ext[c]);
    free(ext);
    free(serr);
    pdf_level_free(&E, nk2);
    free(sig_prev);
    free(sig_cur);
    free(l1);
end:
    pdf_level_free(&A, nk2);
    pdf_level_free(&B, nk2);
    free(ord);
    free(cuts);
    ljgap__nodes_free(&C.nodes);
    return st;
}

int ljgap__pde_summary_at_level(const ljgap_psd *psd, double g_lo, double g_hi, int level,
                               ljgap_summary *sum)
{
    ljgap_opts o;
    ljgap_opts_default(&o);
    pde_ctx C = {.psd = psd, .o = &o, .deadline = ljgap__now() + o.max_seconds};
    curve_result R;
    int st = curve_at(&C, g_lo, g_lo, g_hi, level, NULL, 0, &R, NULL);
    ljgap__nodes_free(&C.nodes);
    if (st) return st;
    *sum = R.sum;
    st = R.sum_ok ? LJGAP_OK : LJGAP_EFAIL;
    curve_result_free(&R);
    return st;
}

int ljgap__pde_pdf_at_level(const ljgap_psd *psd, double g_ave, double k2, double g_lo, double g_hi,
                           int level, ljgap_pdf *out)
{
    if (!(g_lo > 0 && g_lo < g_ave && g_ave < g_hi) || level < 0 || level > MAX_LEVEL)
        return LJGAP_EINVAL;
    ljgap_opts o;
    ljgap_opts_default(&o);
    pde_ctx C = {.psd = psd, .o = &o, .deadline = ljgap__now() + o.max_seconds};
    double cut = fmin(k2, psd->k2);
    pdf_level P = {0};
    memset(out, 0, sizeof *out);
    int st = pdf_level_run(&C, g_ave, g_lo, g_hi, &cut, 1, level, &P);
    ljgap__nodes_free(&C.nodes);
    if (st) return st;
    const pde_grid *G = &P.G;
    out->k2 = k2;
    out->n = G->n;
    out->g = malloc(G->n * sizeof(double));
    out->phi = malloc(G->n * sizeof(double));
    if (!out->g || !out->phi) {
        ljgap_pdf_release(out, 1);
        pdf_level_free(&P, 1);
        return LJGAP_ENOMEM;
    }
    for (size_t i = 0; i < G->n; i++) {
        out->g[i] = G->g[i];
        out->phi[i] = P.p[0][i] / G->wt[i];
        out->mass += P.p[0][i];
        out->mean += P.p[0][i] * G->g[i];
    }
    out->sigma = (ljgap_est){snap_sigma(G, P.p[0]), 0.0};
    pdf_level_free(&P, 1);
    return LJGAP_OK;
}
