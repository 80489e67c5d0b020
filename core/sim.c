/* sim.c -- the discrete numerical model of the paper's Section 5 (theory.md §5).
 *
 * Units as in ljgap.h: gaps in epsilon, lateral lengths in chi, tractions in sigma0.
 *
 * Surface. A periodic square of side L, n x n points, wavevectors q = (2π/L)(i, j). Each
 * lattice wavevector gets the complex amplitude c_q = sqrt(P(|q|)) (2π/L) e^{iφ_q}, φ_q
 * uniform from GSL's Mersenne twister, c_{-q} = conj(c_q), so the height variance of the
 * realization is exactly the lattice sum m0_grid = Σ_q P(|q|) (2π/L)², a Riemann sum of m0 = 2π∫ k
 * P dk (22). When L is only a few wavelengths of k1 the lattice is coarse where P is largest
 * (m0_grid = 1.75 m0 for D = 2.2, [k1,k2] = [1,8], L = 2π), so by default (opts.match_m0) each
 * realization is scaled to carry the PSD's m0 exactly.
 *
 * Elasticity. The half-space answer to the pressure p̃ = -σ/σ0 is
 *     ũ(q) = (2/(3√3)) p̃(q)/|q|   (q ≠ 0),   since σ0 χ/(E* ε) = 1/(3√3),
 * i.e. the stiffness per wavevector is κ(q) = (3√3/2)|q|, and the gap at prescribed mean gap ḡ
 * is g(x) = ḡ + h(x) + u(x) with u of zero mean.
 *
 * Equations. Equilibrium is the stationary point, over zero-mean u, of the energy per area
 *     E(u) = <½ u K u> + <Φ(ḡ + h + u)>,   Φ(g) = -∫_g^∞ σ dg' (Φ' = σ),
 * whose gradient is the force balance G = K u + σ(g) - <σ(g)> (a traction, units of σ0) and
 * whose Hessian is H v = K v + s v - <s v> with s = σ'(g) = (3√3/2)(9g^-10 - 3g^-4) >= -(3√3/2)k0.
 * So vᵀHv >= (3√3/2)(2π/L - k0)|v|²: when 2π/L > k0 (always for the default L = 2π/k1, since
 * the theory needs k1 > k0) the energy is strictly convex, the equilibrium is unique and
 * there can be no jump or hysteresis; the outward sweep is then skipped (sigma_out = sigma).
 *
 * Solver. Truncated Newton: preconditioned conjugate gradients on H d = -G to a relative
 * tolerance min(0.1, sqrt(|G|)) (Eisenstat-Walker), preconditioner (K + c)^-1 applied in
 * Fourier space (c = the mean positive part of s: the stiff Lennard-Jones wall at points in
 * compression), then a backtracking (Armijo) line search on E that also keeps every gap
 * positive. Negative curvature met by CG (possible only when 2π/L <= k0) ends CG with the
 * last descent direction and marks the step. The stopping test is the honest one: the rms of
 * G over the grid, recomputed with a fresh K u, <= tol * max(1, rms σ).
 *
 * Continuation. Mean gaps are visited from the largest inward (then back out when the energy
 * may be non-convex), in substeps no larger than a quarter of the smallest local gap, so every
 * start is feasible and close; a substep whose solve stalls is halved. A realization "jumps"
 * between two requested gaps when its solver met negative curvature on the way: the branch
 * it followed lost stability.
 *
 * FFTW: plans are made once per run (FFTW_ESTIMATE, under a process-wide lock because the
 * planner is not thread-safe) and executed on many arrays with the new-array interface.
 */
#include "ljgap_sim.h"

#include <fftw3.h>
#include <gsl/gsl_rng.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#define SIM_A 2.598076211353315940 /* 3√3/2 */
#define SIM_NEWTON_MAX 100         /* Newton steps at one substep */
#define SIM_CG_MAX 1000            /* CG iterations in one Newton step */
#define SIM_STEP_FRAC 0.25         /* continuation substep / smallest local gap */
#define SIM_G_START 1.5            /* smallest local gap of a cold start */
#define SIM_STALL 2                /* internal: line search or step control failed */

static pthread_mutex_t sim_fftw_lock = PTHREAD_MUTEX_INITIALIZER;

void ljgap_sim_opts_default(ljgap_sim_opts *o)
{
    memset(o, 0, sizeof *o);
    o->n = 64;
    o->L = 0.0;
    o->realizations = 4;
    o->seed = 1;
    o->tol = 1e-8;
    o->max_iter = 200000;
    o->max_seconds = 600.0;
    o->cancel = NULL;
    o->progress = NULL;
    o->progress_ctx = NULL;
    o->match_m0 = 1;
}

void ljgap_sim_result_free(ljgap_sim_result *res)
{
    if (!res) return;
    free(res->g_ave);
    free(res->sigma);
    free(res->sigma_std);
    free(res->sigma_err);
    free(res->sigma_out);
    free(res->residual);
    free(res->jump);
    free(res->m0_realized);
    memset(res, 0, sizeof *res);
}

/* ---- workspace ---- */

typedef struct {
    int n;
    size_t N, nc;  /* real points, complex (half-spectrum) points */
    double L, dq;  /* side, lattice spacing in q */
    double *kappa; /* stiffness (3√3/2)|q| per complex index (0 at q = 0) */
    double *qabs;  /* |q| per complex index */
    double *h, *u, *Ku, *g, *sig, *s, *G, *d, *Kd, *r, *z, *p, *Hp, *ubak;
    fftw_complex *c; /* scratch spectrum */
    fftw_plan fwd, bwd;
    /* run control */
    const ljgap_sim_opts *o;
    double deadline;
    long iter;   /* Hessian products at the current requested gap */
    int negcurv; /* negative curvature met since last cleared */
} sim_ws;

static void ws_free(sim_ws *w)
{
    double **arr[] = {&w->kappa, &w->qabs, &w->h,  &w->u, &w->Ku, &w->g, &w->sig, &w->s,
                      &w->G,     &w->d,    &w->Kd, &w->r, &w->z,  &w->p, &w->Hp,  &w->ubak};
    for (size_t i = 0; i < sizeof arr / sizeof arr[0]; i++) {
        fftw_free(*arr[i]);
        *arr[i] = NULL;
    }
    fftw_free(w->c);
    w->c = NULL;
    pthread_mutex_lock(&sim_fftw_lock);
    if (w->fwd) fftw_destroy_plan(w->fwd);
    if (w->bwd) fftw_destroy_plan(w->bwd);
    pthread_mutex_unlock(&sim_fftw_lock);
    w->fwd = w->bwd = NULL;
}

static int ws_alloc(sim_ws *w, int n, double L)
{
    memset(w, 0, sizeof *w);
    w->n = n;
    w->N = (size_t)n * (size_t)n;
    w->nc = (size_t)n * (size_t)(n / 2 + 1);
    w->L = L;
    w->dq = 2.0 * M_PI / L;
    double **real[] = {&w->h, &w->u,  &w->Ku, &w->g, &w->sig, &w->s,  &w->G,
                       &w->d, &w->Kd, &w->r,  &w->z, &w->p,   &w->Hp, &w->ubak};
    for (size_t i = 0; i < sizeof real / sizeof real[0]; i++)
        if (!(*real[i] = fftw_alloc_real(w->N))) return LJGAP_ENOMEM;
    if (!(w->kappa = fftw_alloc_real(w->nc)) || !(w->qabs = fftw_alloc_real(w->nc)) ||
        !(w->c = fftw_alloc_complex(w->nc)))
        return LJGAP_ENOMEM;
    pthread_mutex_lock(&sim_fftw_lock);
    w->fwd = fftw_plan_dft_r2c_2d(n, n, w->h, w->c, FFTW_ESTIMATE);
    w->bwd = fftw_plan_dft_c2r_2d(n, n, w->c, w->h, FFTW_ESTIMATE);
    pthread_mutex_unlock(&sim_fftw_lock);
    if (!w->fwd || !w->bwd) return LJGAP_ENOMEM;
    int nh = n / 2 + 1;
    for (int j = 0; j < n; j++) {
        int jj = j <= n / 2 ? j : j - n;
        for (int i = 0; i < nh; i++) {
            double q = w->dq * hypot((double)i, (double)jj);
            w->qabs[(size_t)j * nh + i] = q;
            w->kappa[(size_t)j * nh + i] = SIM_A * q;
        }
    }
    return LJGAP_OK;
}

/* out = F^-1[ mult(q) F[in] ] with mult = kappa (op 0) or 1/(kappa + c) (op 1); q = 0 -> 0. */
static void ws_filter(sim_ws *w, const double *in, double *out, int op, double c)
{
    fftw_execute_dft_r2c(w->fwd, (double *)in, w->c);
    double inv = 1.0 / (double)w->N;
    for (size_t k = 1; k < w->nc; k++) {
        double m = op == 0 ? w->kappa[k] : 1.0 / (w->kappa[k] + c);
        w->c[k][0] *= m * inv;
        w->c[k][1] *= m * inv;
    }
    w->c[0][0] = w->c[0][1] = 0.0;
    fftw_execute_dft_c2r(w->bwd, w->c, out);
}

static double dot(const double *a, const double *b, size_t N)
{
    double s = 0.0;
    for (size_t i = 0; i < N; i++)
        s += a[i] * b[i];
    return s;
}

static double mean(const double *a, size_t N)
{
    double s = 0.0;
    for (size_t i = 0; i < N; i++)
        s += a[i];
    return s / (double)N;
}

static double lj_dsigma(double g)
{
    double g2 = 1.0 / (g * g), g4 = g2 * g2, g10 = g4 * g4 * g2;
    return SIM_A * (9.0 * g10 - 3.0 * g4);
}

/* One realization into w->h: random phases (GSL mt19937, seed), amplitudes from the PSD on
 * the lattice, scaled to the PSD's m0 when match. Writes the unscaled lattice variance.
 * The phases are drawn over the band's lattice points |i|,|j| <= k2/dq in an order that does
 * not involve n, so one seed gives the same surface on every grid that resolves the band
 * (a convergence study in n sees the discretization alone). Modes on the Nyquist lines
 * (|i| or |j| = n/2) would alias and are left out; they lie at |q| >= pi n/L >= k2. */
static int make_surface(sim_ws *w, const ljgap_psd *psd, unsigned long seed, int match,
                        double *m0_grid)
{
    gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
    if (!rng) return LJGAP_ENOMEM;
    gsl_rng_set(rng, seed);
    int n = w->n, nh = n / 2 + 1, M = (int)floor(psd->k2 / w->dq);
    double var = 0.0;
    memset(w->c, 0, w->nc * sizeof w->c[0]);
    for (int j = -M; j <= M; j++) {
        for (int i = 0; i <= M; i++) {
            if (i == 0 && j <= 0) continue; /* the other half plane holds the conjugates */
            double phi = 2.0 * M_PI * gsl_rng_uniform(rng);
            double a = sqrt(ljgap_psd_eval(psd, w->dq * hypot(i, j))) * w->dq;
            if (a == 0.0 || i >= n / 2 || abs(j) >= n / 2) continue;
            int jr = j < 0 ? j + n : j;
            size_t k = (size_t)jr * nh + i;
            w->c[k][0] = a * cos(phi), w->c[k][1] = a * sin(phi);
            if (i == 0) { /* the column i = 0 holds its own conjugates */
                size_t kc = (size_t)(n - jr) * nh;
                w->c[kc][0] = a * cos(phi), w->c[kc][1] = -a * sin(phi);
            }
            var += 2.0 * a * a;
        }
    }
    gsl_rng_free(rng);
    *m0_grid = var;
    if (!(var > 0.0)) return LJGAP_EINVAL;
    double scale = match ? sqrt(psd->m0 / var) : 1.0;
    for (size_t k = 0; k < w->nc; k++)
        w->c[k][0] *= scale, w->c[k][1] *= scale;
    fftw_execute_dft_c2r(w->bwd, w->c, w->h);
    double mh = mean(w->h, w->N);
    for (size_t i = 0; i < w->N; i++)
        w->h[i] -= mh; /* round-off only */
    return LJGAP_OK;
}

static int ws_stop(sim_ws *w)
{
    if (w->o->cancel && *w->o->cancel) return LJGAP_ECANCEL;
    if (ljgap_now() > w->deadline) return LJGAP_ECAP;
    return LJGAP_OK;
}

/* Gap, traction, stiffness and force balance at u (w->Ku must hold K u). Returns rms G and
 * writes <σ> and the rms of σ. Fails (returns -1) when a gap is not positive. */
static double ws_eval(sim_ws *w, double gbar, double *sbar, double *srms)
{
    size_t N = w->N;
    double ss = 0.0, s2 = 0.0;
    for (size_t i = 0; i < N; i++) {
        double g = gbar + w->h[i] + w->u[i];
        if (!(g > 0.0)) return -1.0;
        w->g[i] = g;
        w->sig[i] = ljgap_sigma(g);
        w->s[i] = lj_dsigma(g);
        ss += w->sig[i];
        s2 += w->sig[i] * w->sig[i];
    }
    double m = ss / (double)N;
    for (size_t i = 0; i < N; i++)
        w->G[i] = w->Ku[i] + w->sig[i] - m;
    *sbar = m;
    *srms = sqrt(s2 / (double)N);
    return sqrt(dot(w->G, w->G, N) / (double)N);
}

/* H v = K v + s v - <s v> (zero-mean v). */
static void ws_hess(sim_ws *w, const double *v, double *out)
{
    ws_filter(w, v, out, 0, 0.0);
    double m = 0.0;
    for (size_t i = 0; i < w->N; i++)
        m += w->s[i] * v[i];
    m /= (double)w->N;
    for (size_t i = 0; i < w->N; i++)
        out[i] += w->s[i] * v[i] - m;
}

/* PCG for H d = -G to |r| <= eta |G|; d = 0 start. Returns a status (stop checks). */
static int ws_cg(sim_ws *w, double eta, double c)
{
    size_t N = w->N;
    for (size_t i = 0; i < N; i++)
        w->d[i] = 0.0, w->r[i] = -w->G[i];
    double r0 = sqrt(dot(w->r, w->r, N)), target = eta * r0;
    ws_filter(w, w->r, w->z, 1, c);
    memcpy(w->p, w->z, N * sizeof *w->p);
    double rz = dot(w->r, w->z, N);
    for (int it = 0; it < SIM_CG_MAX; it++) {
        int st = ws_stop(w);
        if (st) return st;
        ws_hess(w, w->p, w->Hp);
        w->iter++;
        double pHp = dot(w->p, w->Hp, N);
        if (!(pHp > 0.0)) {
            w->negcurv = 1;
            if (it == 0) memcpy(w->d, w->z, N * sizeof *w->d); /* preconditioned gradient */
            return LJGAP_OK;
        }
        double a = rz / pHp;
        for (size_t i = 0; i < N; i++)
            w->d[i] += a * w->p[i], w->r[i] -= a * w->Hp[i];
        if (sqrt(dot(w->r, w->r, N)) <= target || w->iter >= w->o->max_iter) return LJGAP_OK;
        ws_filter(w, w->r, w->z, 1, c);
        double rz1 = dot(w->r, w->z, N), b = rz1 / rz;
        rz = rz1;
        for (size_t i = 0; i < N; i++)
            w->p[i] = w->z[i] + b * w->p[i];
    }
    return LJGAP_OK;
}

/* Energy change E(u + a d) - E(u) per point; +INFINITY when a gap would not be positive. */
static double ws_dE(sim_ws *w, double a, double dKu, double dKd)
{
    double s = 0.0;
    for (size_t i = 0; i < w->N; i++) {
        double g1 = w->g[i] + a * w->d[i];
        if (!(g1 > 0.0)) return INFINITY;
        s += ljgap_sigma_work(w->g[i]) - ljgap_sigma_work(g1);
    }
    return a * dKu + 0.5 * a * a * dKd + s / (double)w->N;
}

typedef struct {
    double sigma;    /* <σ> */
    double residual; /* rms G / max(1, rms σ) */
    double srms_s;   /* rms of σ' (for the error estimate) */
} sim_point;

/* Solves at mean gap gbar from the current u. Returns LJGAP_OK (pt filled; residual may
 * exceed tol when max_iter ran out), SIM_STALL, or a stop status. */
static int ws_solve(sim_ws *w, double gbar, sim_point *pt)
{
    size_t N = w->N;
    double mu = mean(w->u, N);
    for (size_t i = 0; i < N; i++)
        w->u[i] -= mu;
    ws_filter(w, w->u, w->Ku, 0, 0.0);
    for (int k = 0;; k++) {
        double sbar, srms, grms = ws_eval(w, gbar, &sbar, &srms);
        if (grms < 0.0) return SIM_STALL;
        double scale = srms > 1.0 ? srms : 1.0;
        if (grms <= w->o->tol * scale || k >= SIM_NEWTON_MAX || w->iter >= w->o->max_iter) {
            pt->sigma = sbar;
            pt->residual = grms / scale;
            pt->srms_s = sqrt(dot(w->s, w->s, N) / (double)N);
            return LJGAP_OK;
        }
        double c = 0.0;
        for (size_t i = 0; i < N; i++)
            c += w->s[i] > 0.0 ? w->s[i] : 0.0;
        c /= (double)N;
        double eta = sqrt(grms / scale);
        int st = ws_cg(w, eta < 0.1 ? eta : 0.1, c);
        if (st) return st;
        double slope = dot(w->G, w->d, N) / (double)N;
        if (!(slope < 0.0)) { /* not a descent direction: fall back to -M^-1 G */
            ws_filter(w, w->G, w->d, 1, c);
            for (size_t i = 0; i < N; i++)
                w->d[i] = -w->d[i];
            slope = dot(w->G, w->d, N) / (double)N;
            if (!(slope < 0.0)) return SIM_STALL;
        }
        ws_filter(w, w->d, w->Kd, 0, 0.0);
        double dKu = dot(w->d, w->Ku, N) / (double)N, dKd = dot(w->d, w->Kd, N) / (double)N;
        /* round-off floor of the energy difference */
        double floor_e = 0.0;
        for (size_t i = 0; i < N; i += 7)
            floor_e += fabs(ljgap_sigma_work(w->g[i]));
        floor_e *= 7.0 / (double)N * 64.0 * 2.2e-16;
        double a = 1.0;
        int ok = 0;
        for (int ls = 0; ls < 60; ls++, a *= 0.5) {
            double dE = ws_dE(w, a, dKu, dKd);
            if (dE <= 1e-4 * a * slope + floor_e) {
                ok = 1;
                break;
            }
        }
        if (!ok) return SIM_STALL;
        for (size_t i = 0; i < N; i++)
            w->u[i] += a * w->d[i], w->Ku[i] += a * w->Kd[i];
        if (k % 8 == 7) ws_filter(w, w->u, w->Ku, 0, 0.0); /* refresh against drift */
    }
}

/* Moves the solution from mean gap *gcur to gt in feasible substeps; pt holds the answer at
 * gt. */
static int ws_goto(sim_ws *w, double *gcur, double gt, sim_point *pt)
{
    size_t N = w->N;
    double frac = SIM_STEP_FRAC;
    while (1) {
        double gmin = INFINITY;
        for (size_t i = 0; i < N; i++) {
            double g = *gcur + w->h[i] + w->u[i];
            if (g < gmin) gmin = g;
        }
        double step = frac * gmin, gn = gt;
        if (fabs(gt - *gcur) > step) gn = *gcur + (gt > *gcur ? step : -step);
        memcpy(w->ubak, w->u, N * sizeof *w->u);
        int st = ws_solve(w, gn, pt);
        if (st == SIM_STALL) {
            memcpy(w->u, w->ubak, N * sizeof *w->u);
            frac *= 0.5;
            if (frac < 1e-6) return LJGAP_EFAIL;
            continue;
        }
        if (st) return st;
        *gcur = gn;
        if (gn == gt) return LJGAP_OK;
        if (frac < SIM_STEP_FRAC) frac *= 2.0;
    }
}

/* ---- input checks ---- */

static int check_inputs(const ljgap_psd *psd, const ljgap_sim_opts *o, const double *g_ave,
                        size_t n_gap, double *L, ljgap_warnings *w)
{
    if (!psd || !o) {
        ljgap_warn(w, "simulation: the PSD and the options are required");
        return LJGAP_EINVAL;
    }
    if (!(psd->k1 > 0.0) || !isfinite(psd->k2) || !(psd->k2 > psd->k1) || psd->k2 > LJGAP_K_MAX) {
        ljgap_warn(w, "simulation: the PSD must be band-limited, 0 < k1 < k2 <= %g", LJGAP_K_MAX);
        return LJGAP_EINVAL;
    }
    if (!(psd->m0 > 0.0) || psd->m0 > LJGAP_M0_MAX) {
        ljgap_warn(w, "simulation: m0 must be in (0, %g]", LJGAP_M0_MAX);
        return LJGAP_EINVAL;
    }
    if (o->n < 8 || o->n > LJGAP_SIM_N_MAX || o->n % 2) {
        ljgap_warn(w, "simulation: n must be even, 8 <= n <= %d (got %d)", LJGAP_SIM_N_MAX, o->n);
        return LJGAP_EINVAL;
    }
    if (o->realizations < 1 || o->realizations > LJGAP_SIM_REALIZATIONS_MAX) {
        ljgap_warn(w, "simulation: realizations must be in [1, %d] (got %d)",
                   LJGAP_SIM_REALIZATIONS_MAX, o->realizations);
        return LJGAP_EINVAL;
    }
    if (!(o->tol >= 1e-14 && o->tol <= 1e-2)) {
        ljgap_warn(w, "simulation: tol must be in [1e-14, 1e-2]");
        return LJGAP_EINVAL;
    }
    if (o->max_iter < 1 || !(o->max_seconds > 0.0) || !isfinite(o->max_seconds)) {
        ljgap_warn(w, "simulation: max_iter and max_seconds must be positive");
        return LJGAP_EINVAL;
    }
    double Lmin = 2.0 * M_PI / psd->k1;
    *L = o->L == 0.0 ? Lmin : o->L;
    if (!isfinite(*L) || *L < Lmin * (1.0 - 1e-12) || *L > 1e4 * Lmin) {
        ljgap_warn(w,
                   "simulation: L must be 0 (2π/k1) or in [2π/k1, 1e4·2π/k1] = [%.6g, %.6g], "
                   "so that the grid carries the band's longest wave",
                   Lmin, 1e4 * Lmin);
        return LJGAP_EINVAL;
    }
    double kmax = M_PI * o->n / *L;
    if (psd->k2 > kmax * (1.0 + 1e-12)) {
        double nneed = ceil(psd->k2 * *L / M_PI);
        if (fmod(nneed, 2.0) != 0.0) nneed += 1.0;
        if (nneed <= LJGAP_SIM_N_MAX)
            ljgap_warn(w,
                       "simulation: the grid does not resolve k2 = %g (Nyquist pi*n/L = %g); "
                       "n >= %.0f would do",
                       psd->k2, kmax, nneed);
        else
            ljgap_warn(w,
                       "simulation: the grid cannot resolve k2 = %g with L = %g: it needs n >= "
                       "%.0f > %d; take a smaller L",
                       psd->k2, *L, nneed, LJGAP_SIM_N_MAX);
        return LJGAP_EINVAL;
    }
    if (n_gap < 1 || n_gap > LJGAP_SIM_GAPS_MAX || !g_ave) {
        ljgap_warn(w, "simulation: between 1 and %d mean gaps are needed", LJGAP_SIM_GAPS_MAX);
        return LJGAP_EINVAL;
    }
    for (size_t i = 0; i < n_gap; i++)
        if (!(g_ave[i] >= LJGAP_G_MIN && g_ave[i] <= LJGAP_G_MAX)) {
            ljgap_warn(w, "simulation: g_ave[%zu] = %g is outside [%g, %g]", i, g_ave[i],
                       LJGAP_G_MIN, LJGAP_G_MAX);
            return LJGAP_EINVAL;
        }
    return LJGAP_OK;
}

/* ---- the run ---- */

/* order[] = indices of g in decreasing order (insertion sort: at most GAPS_MAX entries). */
static void sort_desc(const double *g, size_t n, size_t *order)
{
    for (size_t i = 0; i < n; i++) {
        size_t j = i;
        for (; j > 0 && g[order[j - 1]] < g[i]; j--)
            order[j] = order[j - 1];
        order[j] = i;
    }
}

static int result_alloc(ljgap_sim_result *res, size_t ng, int R)
{
    memset(res, 0, sizeof *res);
    res->g_ave = calloc(ng, sizeof(double));
    res->sigma = calloc(ng, sizeof(double));
    res->sigma_std = calloc(ng, sizeof(double));
    res->sigma_err = calloc(ng, sizeof(double));
    res->sigma_out = calloc(ng, sizeof(double));
    res->residual = calloc(ng, sizeof(double));
    res->jump = calloc(ng, sizeof(int));
    res->m0_realized = calloc((size_t)R, sizeof(double));
    if (!res->g_ave || !res->sigma || !res->sigma_std || !res->sigma_err || !res->sigma_out ||
        !res->residual || !res->jump || !res->m0_realized)
        return LJGAP_ENOMEM;
    return LJGAP_OK;
}

int ljgap_sim_run(const ljgap_psd *psd, const ljgap_sim_opts *o, const double *g_ave, size_t n_gap,
                  ljgap_sim_result *res, ljgap_warnings *w)
{
    double t0 = ljgap_now(), L = 0.0;
    if (!res) {
        ljgap_warn(w, "simulation: no result to write");
        return LJGAP_EINVAL;
    }
    memset(res, 0, sizeof *res);
    int st = check_inputs(psd, o, g_ave, n_gap, &L, w);
    if (st) return st;
    const int R = o->realizations;
    const int convex = 2.0 * M_PI / L > ljgap_k0();
    size_t *order = malloc(n_gap * sizeof *order);
    double *sin_ = malloc(n_gap * (size_t)R * sizeof(double));
    double *sout = malloc(n_gap * (size_t)R * sizeof(double));
    double *eres = calloc(n_gap, sizeof(double)); /* residual effect on sigma, worst case */
    sim_ws ws;
    int wst = ws_alloc(&ws, o->n, L);
    st = result_alloc(res, n_gap, R);
    if (!order || !sin_ || !sout || !eres || wst || st) {
        st = LJGAP_ENOMEM;
        goto end;
    }
    ws.o = o;
    ws.deadline = t0 + o->max_seconds;
    sort_desc(g_ave, n_gap, order);
    res->n_gap = n_gap;
    res->realizations = R;
    res->m0_target = psd->m0;
    res->L = L;
    res->n = o->n;
    memcpy(res->g_ave, g_ave, n_gap * sizeof *g_ave);
    const double total = (double)R * (double)n_gap * (convex ? 1.0 : 2.0);
    double done = 0.0;
    const double lam = SIM_A * fmax(2.0 * M_PI / L - ljgap_k0(), 0.1 * 2.0 * M_PI / L);
    int unconverged = 0;
    for (int r = 0; r < R; r++) {
        st = make_surface(&ws, psd, o->seed + (unsigned long)r, o->match_m0, &res->m0_grid);
        if (st) {
            ljgap_warn(w, "simulation: the grid's wavevectors carry none of the PSD");
            goto end;
        }
        res->m0_realized[r] = dot(ws.h, ws.h, ws.N) / (double)ws.N;
        /* cold start: flat elastic surface at a mean gap where every local gap >= 1.5 */
        double hmin = INFINITY;
        for (size_t i = 0; i < ws.N; i++)
            hmin = fmin(hmin, ws.h[i]);
        double gtop = g_ave[order[0]], gcur = fmax(gtop, SIM_G_START - hmin);
        memset(ws.u, 0, ws.N * sizeof *ws.u);
        sim_point pt;
        for (int pass = 0; pass < (convex ? 1 : 2); pass++) {
            for (size_t jj = 0; jj < n_gap; jj++) {
                size_t idx = pass == 0 ? order[jj] : order[n_gap - 1 - jj];
                ws.iter = 0;
                ws.negcurv = 0;
                st = ws_goto(&ws, &gcur, g_ave[idx], &pt);
                if (st == LJGAP_EFAIL)
                    ljgap_warn(w, "simulation: the solver stalled at g_ave = %g", g_ave[idx]);
                if (st) goto end;
                if (pt.residual > o->tol) unconverged = 1;
                if (pass == 0) {
                    sin_[(size_t)r * n_gap + idx] = pt.sigma;
                    if (!convex && jj > 0 && ws.negcurv) res->jump[idx] = 1;
                } else {
                    sout[(size_t)r * n_gap + idx] = pt.sigma;
                }
                if (pt.residual > res->residual[idx]) res->residual[idx] = pt.residual;
                double e = pt.srms_s * pt.residual * fmax(1.0, fabs(pt.sigma)) / lam;
                if (e > eres[idx]) eres[idx] = e;
                done += 1.0;
                if (o->progress) o->progress(o->progress_ctx, done / total);
            }
        }
        if (convex)
            memcpy(sout + (size_t)r * n_gap, sin_ + (size_t)r * n_gap, n_gap * sizeof(double));
    }
    for (size_t i = 0; i < n_gap; i++) {
        double m = 0.0, mo = 0.0, v = 0.0;
        for (int r = 0; r < R; r++)
            m += sin_[(size_t)r * n_gap + i], mo += sout[(size_t)r * n_gap + i];
        m /= R, mo /= R;
        for (int r = 0; r < R; r++) {
            double d = sin_[(size_t)r * n_gap + i] - m;
            v += d * d;
        }
        double sd = R > 1 ? sqrt(v / (R - 1)) : 0.0;
        res->sigma[i] = m;
        res->sigma_out[i] = mo;
        res->sigma_std[i] = sd;
        res->sigma_err[i] = sd / sqrt((double)R) + eres[i];
        if (!isfinite(m) || !isfinite(mo) || !isfinite(res->sigma_err[i])) {
            ljgap_warn(w, "simulation: non-finite traction at g_ave = %g", g_ave[i]);
            st = LJGAP_EFAIL;
            goto end;
        }
    }
    if (R == 1)
        ljgap_warn(w, "simulation: one realization: its spread is unknown, so sigma_std is 0 and "
                      "the error holds only the solver's residual; ask for 2 or more "
                      "realizations for an error estimate");
    if (unconverged)
        ljgap_warn(w,
                   "simulation: the residual target %g was not met everywhere (max_iter = %ld); "
                   "see residual",
                   o->tol, o->max_iter);
    if (res->m0_grid < 0.95 * psd->m0 || res->m0_grid > 1.05 * psd->m0)
        ljgap_warn(w,
                   "simulation: the lattice of wavevectors carries m0_grid = %.4g of m0 = %.4g%s",
                   res->m0_grid, psd->m0,
                   o->match_m0 ? " (realizations scaled to m0)" : "; a larger L resolves the band");
    st = LJGAP_OK;
end:
    ws_free(&ws);
    free(order);
    free(sin_);
    free(sout);
    free(eres);
    if (st) ljgap_sim_result_free(res);
    return st;
}
