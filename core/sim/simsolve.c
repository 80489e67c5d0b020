/* simsolve.c -- one realization of the discrete model of the paper's Section 5 (theory.md §5).
 *
 * Units as in ljgap.h: gaps in epsilon, lateral lengths in chi, tractions in sigma0.
 *
 * Surface. A periodic square of side L, n x n points, wavevectors q = (2π/L)(i, j). Each
 * lattice wavevector of the band gets the complex amplitude c_q = sqrt(P(|q|)) (2π/L) e^{iφ_q},
 * φ_q uniform from GSL's Mersenne twister, c_{-q} = conj(c_q), so the height variance of the
 * realization is exactly the lattice sum m0_grid = Σ_q P(|q|) (2π/L)², a Riemann sum of m0 =
 * 2π∫ k P dk (22). When L is only a few wavelengths of k1 the lattice is coarse where P is
 * largest (m0_grid = 1.75 m0 for D = 2.2, [k1,k2] = [1,8], L = 2π), so by default (opts.match_m0)
 * each realization is scaled to carry the band's m0 exactly. The phases are drawn shell by
 * shell, max(|i|,|j|) = 1, 2, ..., in a fixed order within each shell, so the phase of a
 * wavevector depends on the seed and (i, j) alone: one seed gives the same surface on every
 * grid that resolves the band (a convergence study in n sees the discretization alone), and
 * the hybrid's coarse surface is the plain model's surface without its waves above k_split
 * (the comparison of the two sees the model alone, not the sampling).
 *
 * Elasticity. The half-space answer to the pressure p̃ = -σ/σ0 is
 *     ũ(q) = (2/(3√3)) p̃(q)/|q|   (q ≠ 0),   since σ0 χ/(E* ε) = 1/(3√3),
 * i.e. the stiffness per wavevector is κ(q) = (3√3/2)|q|, and the gap at prescribed mean gap ḡ
 * is g(x) = ḡ + h(x) + u(x) with u of zero mean.
 *
 * Equations. Equilibrium is the stationary point, over zero-mean u, of the energy per area
 *     E(u) = <½ u K u> + <Φ(ḡ + h + u)>,   Φ(g) = -∫_g^∞ σ dg' (Φ' = σ),
 * whose gradient is the force balance G = K u + σ(g) - <σ(g)> (a traction, units of σ0) and
 * whose Hessian is H v = K v + s v - <s v> with s = σ'(g). σ is the interface law (simlaw.h):
 * Lennard-Jones, s >= -(3√3/2)k0, or the hybrid's fine-band law, s >= law.s_min. So vᵀHv >=
 * ((3√3/2)2π/L + s_min)|v|²: when that is positive (always for Lennard-Jones at the default
 * L = 2π/k1, since the theory needs k1 > k0) the energy is strictly convex, the equilibrium is
 * unique and there can be no jump or hysteresis (sim.c then skips the outward sweep).
 *
 * Solver. Truncated Newton: preconditioned conjugate gradients on H d = -G to a relative
 * tolerance min(0.1, sqrt(|G|)) (Eisenstat-Walker), preconditioner (K + c)^-1 applied in
 * Fourier space (c = the mean positive part of s: the stiff wall at points in compression),
 * then a backtracking (Armijo) line search on E that also keeps every gap positive. CG keeps
 * its search direction in Fourier space, so one iteration costs three FFTs (r to Fourier for
 * the preconditioner; the direction and K times it back) instead of four, and r·z comes from
 * Parseval. Negative curvature met by CG (possible only when the energy is not convex) ends CG
 * with the last descent direction and marks the step. The stopping test is the honest one: the
 * rms of G over the grid, recomputed with a fresh K u, <= tol * max(1, rms σ).
 *
 * Continuation. sim_ws_goto moves between mean gaps in substeps no larger than a quarter of
 * the smallest local gap, so every start is feasible and close; a substep whose solve stalls
 * is halved.
 *
 * FFTW: the plans are the run's (sim.c), executed here on this workspace's arrays with the new-
 * array interface (thread-safe; every array comes from fftw_alloc, so alignments match).
 */
#include "simsolve.h"
#include "core.h" /* ljgap__now */

#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SIM_NEWTON_MAX 100 /* Newton steps at one substep */
#define SIM_CG_MAX 1000    /* CG iterations in one Newton step */
#define SIM_STEP_FRAC 0.25 /* continuation substep / smallest local gap */
#define SIM_G_START 1.5    /* smallest local gap of a cold start */

void sim_ws_free(sim_ws *w)
{
    double **arr[] = {&w->kappa, &w->h,  &w->u, &w->Ku, &w->g,  &w->sig,  &w->s, &w->G,
                      &w->d,     &w->Kd, &w->r, &w->p,  &w->Kp, &w->ubak, &w->W};
    for (size_t i = 0; i < sizeof arr / sizeof arr[0]; i++) {
        fftw_free(*arr[i]);
        *arr[i] = NULL;
    }
    fftw_free(w->c);
    fftw_free(w->c2);
    fftw_free(w->P);
    w->c = w->c2 = w->P = NULL;
}

int sim_ws_alloc(sim_ws *w, const sim_shared *sh)
{
    memset(w, 0, sizeof *w);
    int n = sh->n, nh = n / 2 + 1;
    w->sh = sh;
    w->N = (size_t)n * (size_t)n;
    w->nc = (size_t)n * (size_t)nh;
    double **real[] = {&w->h, &w->u,  &w->Ku, &w->g, &w->sig, &w->s,    &w->G,
                       &w->d, &w->Kd, &w->r,  &w->p, &w->Kp,  &w->ubak, &w->W};
    for (size_t i = 0; i < sizeof real / sizeof real[0]; i++)
        if (!(*real[i] = fftw_alloc_real(w->N))) return LJGAP_ENOMEM;
    if (!(w->kappa = fftw_alloc_real(w->nc)) || !(w->c = fftw_alloc_complex(w->nc)) ||
        !(w->c2 = fftw_alloc_complex(w->nc)) || !(w->P = fftw_alloc_complex(w->nc)))
        return LJGAP_ENOMEM;
    for (int j = 0; j < n; j++) {
        int jj = j <= n / 2 ? j : j - n;
        for (int i = 0; i < nh; i++)
            w->kappa[(size_t)j * nh + i] = SIM_A * sh->dq * hypot((double)i, (double)jj);
    }
    return LJGAP_OK;
}

/* out = F^-1[ mult(q) F[in] ] with mult = kappa (op 0) or 1/(kappa + c) (op 1); q = 0 -> 0. */
static void ws_filter(sim_ws *w, const double *in, double *out, int op, double c)
{
    fftw_execute_dft_r2c(w->sh->fwd, (double *)in, w->c);
    double inv = 1.0 / (double)w->N;
    for (size_t k = 1; k < w->nc; k++) {
        double m = op == 0 ? w->kappa[k] : 1.0 / (w->kappa[k] + c);
        w->c[k][0] *= m * inv;
        w->c[k][1] *= m * inv;
    }
    w->c[0][0] = w->c[0][1] = 0.0;
    fftw_execute_dft_c2r(w->sh->bwd, w->c, out);
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

/* Point t (0 <= t < 4m) of shell m: the wavevectors of the half plane (i > 0, or i = 0 and
 * j > 0) with max(|i|,|j|) = m, in a fixed order: the column i = m (j = -m..m), then the rows
 * j = m (i = 0..m-1) and j = -m (i = 1..m-1). */
static void shell_point(int m, int t, int *i, int *j)
{
    if (t <= 2 * m)
        *i = m, *j = t - m;
    else if (t <= 3 * m)
        *i = t - 2 * m - 1, *j = m;
    else
        *i = t - 3 * m, *j = -m;
}

int sim_ws_surface(sim_ws *w, const sim_band *b, unsigned long seed, double *m0_grid)
{
    const int n = w->sh->n, nh = n / 2 + 1;
    const double dq = w->sh->dq;
    double var = 0.0;
    memset(w->c, 0, w->nc * sizeof w->c[0]);
    *m0_grid = 0.0;
    if (!(b->m0 > 0.0)) { /* the theory alone: nothing on the grid */
        memset(w->h, 0, w->N * sizeof *w->h);
        return LJGAP_OK;
    }
    gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
    if (!rng) return LJGAP_ENOMEM;
    gsl_rng_set(rng, seed);
    /* modes on the Nyquist lines (|i| or |j| = n/2) would alias and are left out; they lie at
     * |q| >= pi n/L >= k_top */
    int M = (int)fmin(floor(b->k_top / dq), n / 2);
    for (int m = 1; m <= M; m++)
        for (int t = 0; t < 4 * m; t++) {
            int i, j;
            shell_point(m, t, &i, &j);
            double phi = 2.0 * M_PI * gsl_rng_uniform(rng);
            double k = dq * hypot(i, j);
            double a = k <= b->k_top ? sqrt(ljgap_psd_eval(b->psd, k)) * dq : 0.0;
            if (a == 0.0 || i >= n / 2 || abs(j) >= n / 2) continue;
            int jr = j < 0 ? j + n : j;
            size_t kk = (size_t)jr * nh + i;
            w->c[kk][0] = a * cos(phi), w->c[kk][1] = a * sin(phi);
            if (i == 0) { /* the column i = 0 holds its own conjugates */
                size_t kc = (size_t)(n - jr) * nh;
                w->c[kc][0] = a * cos(phi), w->c[kc][1] = -a * sin(phi);
            }
            var += 2.0 * a * a;
        }
    gsl_rng_free(rng);
    *m0_grid = var;
    if (!(var > 0.0)) return LJGAP_EINVAL;
    double scale = b->match ? sqrt(b->m0 / var) : 1.0;
    for (size_t k = 0; k < w->nc; k++)
        w->c[k][0] *= scale, w->c[k][1] *= scale;
    fftw_execute_dft_c2r(w->sh->bwd, w->c, w->h);
    double mh = mean(w->h, w->N);
    for (size_t i = 0; i < w->N; i++)
        w->h[i] -= mh; /* round-off only */
    return LJGAP_OK;
}

static int ws_stop(const sim_ws *w)
{
    const sim_shared *sh = w->sh;
    int a = atomic_load_explicit(sh->abort, memory_order_relaxed);
    if (a) return a;
    if (sh->o->cancel && *sh->o->cancel) return LJGAP_ECANCEL;
    if (ljgap__now() > sh->deadline) return LJGAP_ECAP;
    return LJGAP_OK;
}

/* Gap, traction, stiffness, potential and force balance at u (w->Ku must hold K u). Returns rms G
 * and writes <σ> and the rms of σ. Fails (returns -1) when a gap is not positive. */
static double ws_eval(sim_ws *w, double gbar, double *sbar, double *srms)
{
    const sim_law *law = w->sh->law;
    size_t N = w->N;
    double ss = 0.0, s2 = 0.0;
    for (size_t i = 0; i < N; i++) {
        double g = gbar + w->h[i] + w->u[i];
        if (!(g > 0.0)) return -1.0;
        w->g[i] = g;
        if (law->tabulated) {
            sim_law_eval(law, g, &w->sig[i], &w->s[i], &w->W[i]);
        } else {
            double g2 = 1.0 / (g * g), g4 = g2 * g2, g3 = g2 / g;
            w->sig[i] = SIM_A * (g3 - g3 * g3 * g3);
            w->s[i] = SIM_A * (9.0 * g4 * g4 * g2 - 3.0 * g4);
            w->W[i] = SIM_A * (0.5 * g2 - 0.125 * g4 * g4);
        }
        ss += w->sig[i];
        s2 += w->sig[i] * w->sig[i];
    }
    double m = ss / (double)N, gg = 0.0;
    for (size_t i = 0; i < N; i++) {
        w->G[i] = w->Ku[i] + w->sig[i] - m;
        gg += w->G[i] * w->G[i];
    }
    *sbar = m;
    *srms = sqrt(s2 / (double)N);
    return sqrt(gg / (double)N);
}

/* w->c <- Z = M F[r]/N, M = (kappa + c)^-1 on q != 0 (the preconditioned residual's spectrum,
 * normalised so that z = F^-1 Z); returns r·z = (1/N) Σ_q M |F[r]|² = N Σ_q (kappa + c)|Z|²
 * (Parseval) over the full spectrum, whose half the array holds: its columns 1..n/2-1 count
 * twice. */
static double ws_precond(sim_ws *w, double c)
{
    fftw_execute_dft_r2c(w->sh->fwd, w->r, w->c);
    const int n = w->sh->n, nh = n / 2 + 1;
    const double inv = 1.0 / (double)w->N;
    double s = 0.0;
    w->c[0][0] = w->c[0][1] = 0.0;
    for (int j = 0; j < n; j++) {
        fftw_complex *z = w->c + (size_t)j * nh;
        const double *kap = w->kappa + (size_t)j * nh;
        double row = 0.0;
        for (int i = j == 0; i < nh; i++) {
            double k = kap[i] + c, m = inv / k;
            z[i][0] *= m, z[i][1] *= m;
            row += (i == 0 || i == n / 2 ? 0.5 : 1.0) * k * (z[i][0] * z[i][0] + z[i][1] * z[i][1]);
        }
        s += 2.0 * row;
    }
    return s * (double)w->N;
}

/* The new CG direction P <- Z + b P (b = 0: Z), and its copies for the two inverse transforms:
 * w->c = P and w->c2 = kappa P (c2r destroys its input). */
static void ws_direction(sim_ws *w, double b)
{
    for (size_t k = 0; k < w->nc; k++) {
        double re = w->c[k][0], im = w->c[k][1];
        if (b != 0.0) re += b * w->P[k][0], im += b * w->P[k][1];
        w->P[k][0] = w->c[k][0] = re, w->P[k][1] = w->c[k][1] = im;
        w->c2[k][0] = w->kappa[k] * re, w->c2[k][1] = w->kappa[k] * im;
    }
}

/* PCG for H d = -G to |r| <= eta |G|; d = 0 start. The direction P lives in Fourier space
 * (p = F^-1 P); p and K p are formed from it each iteration. Returns a status (stop checks). */
static int ws_cg(sim_ws *w, double eta, double c)
{
    size_t N = w->N;
    double rr = 0.0;
    for (size_t i = 0; i < N; i++) {
        w->d[i] = 0.0, w->r[i] = -w->G[i];
        rr += w->r[i] * w->r[i];
    }
    double target = eta * sqrt(rr);
    double rz = ws_precond(w, c);
    ws_direction(w, 0.0);
    for (int it = 0; it < SIM_CG_MAX; it++) {
        int st = ws_stop(w);
        if (st) return st;
        fftw_execute_dft_c2r(w->sh->bwd, w->c, w->p);
        fftw_execute_dft_c2r(w->sh->bwd, w->c2, w->Kp);
        w->iter++;
        /* H p = K p + s p - <s p>; pHp = Σ p (K p + s p) - <s p> Σ p */
        double sp = 0.0, pkp = 0.0, psum = 0.0;
        for (size_t i = 0; i < N; i++) {
            double t = w->s[i] * w->p[i];
            sp += t;
            pkp += w->p[i] * (w->Kp[i] + t);
            psum += w->p[i];
        }
        double msp = sp / (double)N, pHp = pkp - msp * psum;
        if (!(pHp > 0.0)) {
            w->negcurv = 1;
            if (it == 0) memcpy(w->d, w->p, N * sizeof *w->d); /* preconditioned gradient */
            return LJGAP_OK;
        }
        double a = rz / pHp;
        rr = 0.0;
        for (size_t i = 0; i < N; i++) {
            w->d[i] += a * w->p[i];
            w->r[i] -= a * (w->Kp[i] + w->s[i] * w->p[i] - msp);
            rr += w->r[i] * w->r[i];
        }
        if (sqrt(rr) <= target || w->iter >= w->sh->o->max_iter) return LJGAP_OK;
        double rz1 = ws_precond(w, c);
        ws_direction(w, rz1 / rz);
        rz = rz1;
    }
    return LJGAP_OK;
}

/* Energy change E(u + a d) - E(u) per point; +INFINITY when a gap would not be positive. */
static double ws_dE(sim_ws *w, double a, double dKu, double dKd)
{
    const sim_law *law = w->sh->law;
    double s = 0.0;
    for (size_t i = 0; i < w->N; i++) {
        double g1 = w->g[i] + a * w->d[i];
        if (!(g1 > 0.0)) return INFINITY;
        s += w->W[i] - sim_law_work(law, g1);
    }
    return a * dKu + 0.5 * a * a * dKd + s / (double)w->N;
}

/* The law's error over the grid at the solution (hybrid): mean and largest. */
static void ws_law_err(sim_ws *w, sim_point *pt)
{
    const sim_law *law = w->sh->law;
    double sum = 0.0, mx = 0.0, gmin = INFINITY;
    for (size_t i = 0; i < w->N; i++) {
        gmin = fmin(gmin, w->g[i]);
        if (!law->tabulated) continue;
        double e = sim_law_err(law, w->g[i]);
        sum += e;
        mx = fmax(mx, e);
    }
    pt->law_err = sum / (double)w->N;
    pt->law_max = mx;
    pt->g_min = gmin;
}

/* Solves at mean gap gbar from the current u. Returns LJGAP_OK (pt filled; residual may
 * exceed tol when max_iter ran out), SIM_STALL, or a stop status. */
static int ws_solve(sim_ws *w, double gbar, sim_point *pt)
{
    const ljgap_sim_opts *o = w->sh->o;
    size_t N = w->N;
    double mu = mean(w->u, N);
    for (size_t i = 0; i < N; i++)
        w->u[i] -= mu;
    ws_filter(w, w->u, w->Ku, 0, 0.0);
    for (int k = 0;; k++) {
        double sbar, srms, grms = ws_eval(w, gbar, &sbar, &srms);
        if (grms < 0.0) return SIM_STALL;
        double scale = srms > 1.0 ? srms : 1.0;
        if (grms <= o->tol * scale || k >= SIM_NEWTON_MAX || w->iter >= o->max_iter) {
            pt->sigma = sbar;
            pt->residual = grms / scale;
            pt->srms_s = sqrt(dot(w->s, w->s, N) / (double)N);
            ws_law_err(w, pt);
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
            floor_e += fabs(w->W[i]);
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

void sim_ws_start(sim_ws *w, double g_top, double *gcur)
{
    double hmin = INFINITY;
    for (size_t i = 0; i < w->N; i++)
        hmin = fmin(hmin, w->h[i]);
    *gcur = fmax(g_top, SIM_G_START - hmin);
    memset(w->u, 0, w->N * sizeof *w->u);
}

int sim_ws_goto(sim_ws *w, double *gcur, double gt, sim_point *pt)
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
