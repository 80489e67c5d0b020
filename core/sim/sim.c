/* sim.c -- the discrete numerical model of the paper's Section 5 (theory.md §5), and its hybrid
 * with the statistical theory (Section 6): a run over realizations and mean gaps.
 *
 * One realization (simsolve.c) is a random periodic surface on an n x n grid and the
 * equilibrium of the elastic half-space under the interface law at each prescribed mean gap,
 * visited from the largest inward (then back out when the energy may be non-convex), each
 * solve starting from the last. This file checks the inputs, builds the interface law
 * (simlaw.c: Lennard-Jones, or for the hybrid the statistical law of the band above k_split,
 * computed once by the PDE), makes the FFTW plans once for the run, runs the realizations on
 * up to opts.threads threads and gathers the result: the mean over realizations, their
 * spread, and an error estimate.
 *
 * Hybrid. With k_split the grid carries the lattice wavevectors k1 <= |q| <= k_split, scaled
 * (match_m0) to the variance m0c = 2π∫_{k1}^{k_split} k P dk of that band; the band (k_split,
 * k2] enters through its law. Both limits are exact: k_split = k1 leaves the grid flat, so
 * each point sits at the mean gap and the answer is the law itself (the theory alone);
 * k_split >= k2 leaves no fine band, and the run is the plain model's.
 *
 * Error of sigma at each gap: the standard error over realizations, plus the worst effect of
 * the residual left by the solver (|G| / λ with λ the energy's smallest curvature, bounded
 * below), plus for the hybrid the mean estimated error of the law at the grid's local gaps.
 *
 * Threads. Realizations are independent: each thread takes the next realization, with its
 * own workspace, and writes only that realization's slots; the progress callback is called
 * under a lock with the count of gaps done over all threads. FFTW's planner is not thread-
 * safe, so plans are made (FFTW_ESTIMATE: deterministic, so a seed gives the same numbers in
 * every process, and planning costs ~1 ms, nothing next to a run) under a process-wide lock;
 * executing them on other arrays (fftw_execute_dft_*) is thread-safe. Nothing depends on
 * which thread ran which realization, so the result does not depend on the number of threads.
 */
#include "ljgap_sim.h"
#include "core.h" /* ljgap__now */
#include "simlaw.h"
#include "simsolve.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

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
    o->k_split = 0.0;
    o->law_tol = 1e-6;
    o->threads = 1;
}

void ljgap_sim_result_free(ljgap_sim_result *res)
{
    if (!res) return;
    free(res->g_ave);
    free(res->sigma);
    free(res->sigma_std);
    free(res->sigma_err);
    free(res->sigma_each);
    free(res->sigma_out);
    free(res->residual);
    free(res->jump);
    free(res->m0_realized);
    memset(res, 0, sizeof *res);
}

/* ---- input checks ---- */

/* The grid must carry wavenumbers up to k (k2, or k_split for the hybrid). */
static int check_resolved(const char *what, double k, int n, double L, ljgap_warnings *w)
{
    double kmax = M_PI * n / L;
    if (k <= kmax * (1.0 + 1e-12)) return LJGAP_OK;
    double nneed = ceil(k * L / M_PI);
    if (fmod(nneed, 2.0) != 0.0) nneed += 1.0;
    if (nneed <= LJGAP_SIM_N_MAX)
        ljgap_warn(w,
                   "simulation: the grid does not resolve %s = %g (Nyquist pi*n/L = %g); "
                   "n >= %.0f would do",
                   what, k, kmax, nneed);
    else
        ljgap_warn(w,
                   "simulation: the grid cannot resolve %s = %g with L = %g: it needs n >= "
                   "%.0f > %d; take a smaller L",
                   what, k, L, nneed, LJGAP_SIM_N_MAX);
    return LJGAP_EINVAL;
}

static int check_inputs(const ljgap_psd *psd, const ljgap_sim_opts *o, const double *g_ave,
                        size_t n_gap, double *L, ljgap_warnings *w)
{
    if (!psd || !o) {
        ljgap_warn(w, "simulation: the PSD and the options are required");
        return LJGAP_EINVAL;
    }
    const double ks = o->k_split;
    const int hybrid = ks > 0.0 && ks < psd->k2;
    if (!(ks == 0.0 || (ks >= psd->k1 && ks <= LJGAP_K_MAX))) {
        ljgap_warn(w, "simulation: k_split must be 0 (none) or in [k1, %g] = [%g, %g]", LJGAP_K_MAX,
                   psd->k1, LJGAP_K_MAX);
        return LJGAP_EINVAL;
    }
    if (!(psd->k1 > 0.0) || !(psd->k2 > psd->k1) || (!hybrid && !isfinite(psd->k2)) ||
        (isfinite(psd->k2) && psd->k2 > LJGAP_K_MAX)) {
        ljgap_warn(w,
                   "simulation: the PSD must be band-limited, 0 < k1 < k2 <= %g (k2 may be "
                   "infinite for the hybrid, with k_split)",
                   LJGAP_K_MAX);
        return LJGAP_EINVAL;
    }
    if (hybrid && !(ks > ljgap_k0())) {
        ljgap_warn(w,
                   "simulation: the fine band's statistical law needs k_split > k0 = %.5f (19): "
                   "below it the gap transfer (14) has a pole",
                   ljgap_k0());
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
    if (o->threads < 1 || o->threads > LJGAP_SIM_THREADS_MAX) {
        ljgap_warn(w, "simulation: threads must be in [1, %d] (got %d)", LJGAP_SIM_THREADS_MAX,
                   o->threads);
        return LJGAP_EINVAL;
    }
    if (!(o->tol >= 1e-14 && o->tol <= 1e-2)) {
        ljgap_warn(w, "simulation: tol must be in [1e-14, 1e-2]");
        return LJGAP_EINVAL;
    }
    if (hybrid && !(o->law_tol >= 1e-10 && o->law_tol <= 1e-2)) {
        ljgap_warn(w, "simulation: law_tol must be in [1e-10, 1e-2]");
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
    int st = hybrid ? check_resolved("k_split", ks, o->n, *L, w)
                    : check_resolved("k2", psd->k2, o->n, *L, w);
    if (st) return st;
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

/* Everything the realizations of one run share, and their separate outputs. */
typedef struct {
    sim_shared sh;
    sim_band band;
    const double *g_ave;
    size_t n_gap;
    const size_t *order; /* gap indices, largest gap first */
    int R, passes;       /* realizations; 1 (convex: inward only) or 2 (in and back out) */
    atomic_int abort;    /* first failure's status: the other realizations stop */
    pthread_mutex_t lock;
    int next;           /* next realization to take (under lock) */
    double done, total; /* gap solves done / to do, for progress (under lock) */
    double lam;         /* energy curvature bound for the residual's effect */
    /* per realization r: slots [r * n_gap, (r+1) * n_gap) */
    double *sin_, *sout, *resid, *eres, *elaw;
    int *jump;
    double *m0_realized, *m0_grid, *law_max, *g_min;
    int *unconverged;
    int *status;          /* status of each realization */
    ljgap_warnings *warn; /* warnings of each realization */
} sim_run;

static int run_realization(sim_run *run, sim_ws *ws, int r)
{
    const ljgap_sim_opts *o = run->sh.o;
    const size_t ng = run->n_gap;
    ljgap_warnings *w = &run->warn[r];
    int st = sim_ws_surface(ws, &run->band, o->seed + (unsigned long)r, &run->m0_grid[r]);
    if (st) {
        if (st == LJGAP_EINVAL)
            ljgap_warn(w, "simulation: the grid's wavevectors carry none of the PSD");
        return st;
    }
    double hh = 0.0;
    for (size_t i = 0; i < ws->N; i++)
        hh += ws->h[i] * ws->h[i];
    run->m0_realized[r] = hh / (double)ws->N;
    double gcur;
    sim_ws_start(ws, run->g_ave[run->order[0]], &gcur);
    run->g_min[r] = INFINITY;
    for (int pass = 0; pass < run->passes; pass++) {
        for (size_t jj = 0; jj < ng; jj++) {
            size_t idx = pass == 0 ? run->order[jj] : run->order[ng - 1 - jj], k = r * ng + idx;
            sim_point pt;
            ws->iter = 0;
            ws->negcurv = 0;
            st = sim_ws_goto(ws, &gcur, run->g_ave[idx], &pt);
            if (st == LJGAP_EFAIL)
                ljgap_warn(w, "simulation: the solver stalled at g_ave = %g", run->g_ave[idx]);
            if (st) return st;
            if (pt.residual > o->tol) run->unconverged[r] = 1;
            if (pass == 0) {
                run->sin_[k] = pt.sigma;
                if (run->passes == 2 && jj > 0 && ws->negcurv) run->jump[k] = 1;
            } else {
                run->sout[k] = pt.sigma;
            }
            run->resid[k] = fmax(run->resid[k], pt.residual);
            run->eres[k] =
                fmax(run->eres[k], pt.srms_s * pt.residual * fmax(1.0, fabs(pt.sigma)) / run->lam);
            run->elaw[k] = fmax(run->elaw[k], pt.law_err);
            run->law_max[r] = fmax(run->law_max[r], pt.law_max);
            run->g_min[r] = fmin(run->g_min[r], pt.g_min);
            pthread_mutex_lock(&run->lock);
            run->done += 1.0;
            if (o->progress) o->progress(o->progress_ctx, run->done / run->total);
            pthread_mutex_unlock(&run->lock);
        }
    }
    if (run->passes == 1) memcpy(run->sout + r * ng, run->sin_ + r * ng, ng * sizeof(double));
    return LJGAP_OK;
}

/* A thread: takes realizations until none is left or one has failed. */
static void *worker(void *arg)
{
    sim_run *run = arg;
    sim_ws ws;
    int st = sim_ws_alloc(&ws, &run->sh);
    for (;;) {
        pthread_mutex_lock(&run->lock);
        int r = run->next < run->R && !atomic_load(&run->abort) ? run->next++ : -1;
        pthread_mutex_unlock(&run->lock);
        if (r < 0) break;
        if (!st) st = run_realization(run, &ws, r);
        run->status[r] = st;
        if (st) {
            int zero = 0;
            atomic_compare_exchange_strong(&run->abort, &zero, st);
            break;
        }
    }
    sim_ws_free(&ws);
    return NULL;
}

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
    res->sigma_each = calloc(ng * (size_t)R, sizeof(double));
    res->sigma_out = calloc(ng, sizeof(double));
    res->residual = calloc(ng, sizeof(double));
    res->jump = calloc(ng, sizeof(int));
    res->m0_realized = calloc((size_t)R, sizeof(double));
    if (!res->g_ave || !res->sigma || !res->sigma_std || !res->sigma_err || !res->sigma_each ||
        !res->sigma_out || !res->residual || !res->jump || !res->m0_realized)
        return LJGAP_ENOMEM;
    return LJGAP_OK;
}

static void run_free(sim_run *run)
{
    free(run->sin_);
    free(run->sout);
    free(run->resid);
    free(run->eres);
    free(run->elaw);
    free(run->jump);
    free(run->m0_realized);
    free(run->m0_grid);
    free(run->law_max);
    free(run->g_min);
    free(run->unconverged);
    free(run->status);
    free(run->warn);
    pthread_mutex_lock(&sim_fftw_lock);
    if (run->sh.fwd) fftw_destroy_plan(run->sh.fwd);
    if (run->sh.bwd) fftw_destroy_plan(run->sh.bwd);
    pthread_mutex_unlock(&sim_fftw_lock);
}

static int run_alloc(sim_run *run, size_t ng, int R)
{
    size_t m = ng * (size_t)R;
    run->sin_ = calloc(m, sizeof(double));
    run->sout = calloc(m, sizeof(double));
    run->resid = calloc(m, sizeof(double));
    run->eres = calloc(m, sizeof(double));
    run->elaw = calloc(m, sizeof(double));
    run->jump = calloc(m, sizeof(int));
    run->m0_realized = calloc((size_t)R, sizeof(double));
    run->m0_grid = calloc((size_t)R, sizeof(double));
    run->law_max = calloc((size_t)R, sizeof(double));
    run->g_min = calloc((size_t)R, sizeof(double));
    run->unconverged = calloc((size_t)R, sizeof(int));
    run->status = calloc((size_t)R, sizeof(int));
    run->warn = calloc((size_t)R, sizeof(ljgap_warnings));
    if (!run->sin_ || !run->sout || !run->resid || !run->eres || !run->elaw || !run->jump ||
        !run->m0_realized || !run->m0_grid || !run->law_max || !run->g_min || !run->unconverged ||
        !run->status || !run->warn)
        return LJGAP_ENOMEM;
    /* plans on scratch arrays of the workspaces' alignment (FFTW_ESTIMATE touches no data) */
    int n = run->sh.n;
    double *a = fftw_alloc_real((size_t)n * n);
    fftw_complex *c = fftw_alloc_complex((size_t)n * (n / 2 + 1));
    if (a && c) {
        pthread_mutex_lock(&sim_fftw_lock);
        run->sh.fwd = fftw_plan_dft_r2c_2d(n, n, a, c, FFTW_ESTIMATE);
        run->sh.bwd = fftw_plan_dft_c2r_2d(n, n, c, a, FFTW_ESTIMATE);
        pthread_mutex_unlock(&sim_fftw_lock);
    }
    fftw_free(a);
    fftw_free(c);
    return run->sh.fwd && run->sh.bwd ? LJGAP_OK : LJGAP_ENOMEM;
}

/* The Lennard-Jones law's own adhesion summary (exact): the modified law of an empty band. */
static void lj_summary(ljgap_summary *s)
{
    memset(s, 0, sizeof *s);
    s->g_eq.value = 1.0;
    s->sigma_max.value = 1.0;
    s->g_at_max.value = ljgap_g_sigma_max();
    s->dgamma_eff.value = 1.0;
    s->k0 = ljgap_k0();
}

/* The interface law of the run: Lennard-Jones, or the statistical law of the band above
 * k_split (res gets its summary). */
static int make_law(const ljgap_psd *psd, const ljgap_sim_opts *o, double deadline, sim_law *law,
                    ljgap_sim_result *res, ljgap_warnings *w)
{
    sim_law_lj(law);
    if (o->k_split == 0.0) return LJGAP_OK;
    res->k_split = o->k_split;
    if (o->k_split >= psd->k2) {
        lj_summary(&res->fine);
        return LJGAP_OK;
    }
    /* the band above k_split (k_split = k1: the whole PSD) */
    ljgap_psd above = {0};
    const ljgap_psd *fine = psd;
    if (o->k_split > psd->k1) {
        int st = ljgap_psd_above(&above, psd, o->k_split);
        if (st) return st;
        fine = &above;
    }
    ljgap_opts po;
    ljgap_opts_default(&po);
    po.tol = o->law_tol;
    po.max_seconds = deadline - ljgap__now();
    po.cancel = o->cancel;
    int st = po.max_seconds > 0 ? sim_law_fine(law, fine, &po, w) : LJGAP_ECAP;
    if (!st) {
        res->m0_fine = fine->m0;
        res->fine = law->sum;
    }
    ljgap_psd_free(&above);
    return st;
}

int ljgap_sim_run(const ljgap_psd *psd, const ljgap_sim_opts *o, const double *g_ave, size_t n_gap,
                  ljgap_sim_result *res, ljgap_warnings *w)
{
    double t0 = ljgap__now(), L = 0.0;
    if (!res) {
        ljgap_warn(w, "simulation: no result to write");
        return LJGAP_EINVAL;
    }
    memset(res, 0, sizeof *res);
    int st = check_inputs(psd, o, g_ave, n_gap, &L, w);
    if (st) return st;
    const int R = o->realizations;
    const int hybrid = o->k_split > 0.0 && o->k_split < psd->k2;
    sim_law law;
    sim_run run;
    memset(&run, 0, sizeof run);
    pthread_mutex_init(&run.lock, NULL);
    atomic_init(&run.abort, 0);
    size_t *order = malloc(n_gap * sizeof *order);
    pthread_t *tid = NULL;
    int started = 0;
    run.sh.n = o->n;
    run.sh.L = L;
    run.sh.dq = 2.0 * M_PI / L;
    run.sh.o = o;
    run.sh.deadline = t0 + o->max_seconds;
    run.sh.abort = &run.abort;
    run.sh.law = &law;
    sim_law_lj(&law);
    if (!order || run_alloc(&run, n_gap, R) || result_alloc(res, n_gap, R)) {
        st = LJGAP_ENOMEM;
        goto end;
    }
    st = make_law(psd, o, run.sh.deadline, &law, res, w);
    if (st) goto end;
    run.band.psd = psd;
    run.band.k_top = hybrid ? o->k_split : psd->k2;
    run.band.m0 = hybrid ? ljgap_psd_cumvar(psd, o->k_split) : psd->m0;
    run.band.match = o->match_m0;
    run.g_ave = g_ave;
    run.n_gap = n_gap;
    run.order = order;
    run.R = R;
    sort_desc(g_ave, n_gap, order);
    /* the smallest curvature of the energy: (3√3/2)|q|min + min σ' (simsolve.c) */
    const double kq = SIM_A * run.sh.dq, curv = kq + law.s_min;
    run.passes = curv > 0.0 ? 1 : 2;
    run.lam = fmax(curv, 0.1 * kq);
    run.total = (double)R * (double)n_gap * run.passes;
    /* the realizations, on up to opts.threads threads (this one included) */
    int T = o->threads < R ? o->threads : R;
    if (T > 1 && !(tid = calloc((size_t)T - 1, sizeof *tid))) {
        st = LJGAP_ENOMEM;
        goto end;
    }
    for (int t = 0; t + 1 < T; t++) {
        if (pthread_create(&tid[t], NULL, worker, &run)) break;
        started++;
    }
    worker(&run);
    for (int t = 0; t < started; t++)
        pthread_join(tid[t], NULL);
    st = atomic_load(&run.abort);
    for (int r = 0; r < R; r++)
        for (int i = 0; i < run.warn[r].n; i++)
            ljgap_warn(w, "%s", run.warn[r].msg[i]);
    if (st) goto end;
    /* gather */
    res->n_gap = n_gap;
    res->realizations = R;
    res->m0_target = psd->m0;
    res->m0_grid = run.m0_grid[0];
    res->L = L;
    res->n = o->n;
    res->g_min = INFINITY;
    memcpy(res->g_ave, g_ave, n_gap * sizeof *g_ave);
    memcpy(res->m0_realized, run.m0_realized, (size_t)R * sizeof(double));
    memcpy(res->sigma_each, run.sin_, n_gap * (size_t)R * sizeof(double));
    int unconverged = 0;
    for (int r = 0; r < R; r++) {
        unconverged |= run.unconverged[r];
        res->law_err = fmax(res->law_err, run.law_max[r]);
        res->g_min = fmin(res->g_min, run.g_min[r]);
    }
    for (size_t i = 0; i < n_gap; i++) {
        double m = 0.0, mo = 0.0, v = 0.0, eres = 0.0, elaw = 0.0;
        for (int r = 0; r < R; r++) {
            size_t k = (size_t)r * n_gap + i;
            m += run.sin_[k], mo += run.sout[k];
            res->jump[i] |= run.jump[k];
            res->residual[i] = fmax(res->residual[i], run.resid[k]);
            eres = fmax(eres, run.eres[k]);
            elaw = fmax(elaw, run.elaw[k]);
        }
        m /= R, mo /= R;
        for (int r = 0; r < R; r++) {
            double d = run.sin_[(size_t)r * n_gap + i] - m;
            v += d * d;
        }
        double sd = R > 1 ? sqrt(v / (R - 1)) : 0.0;
        res->sigma[i] = m;
        res->sigma_out[i] = mo;
        res->sigma_std[i] = sd;
        res->sigma_err[i] = sd / sqrt((double)R) + eres + elaw;
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
    if (run.band.m0 > 0.0 &&
        (res->m0_grid < 0.95 * run.band.m0 || res->m0_grid > 1.05 * run.band.m0))
        ljgap_warn(w,
                   "simulation: the lattice of wavevectors carries m0_grid = %.4g of m0 = %.4g%s",
                   res->m0_grid, run.band.m0,
                   o->match_m0 ? " (realizations scaled to m0)" : "; a larger L resolves the band");
    if (hybrid && res->g_min < law.g_lo)
        ljgap_warn(w,
                   "hybrid: local gaps down to %g, below the fine band's table (%g): its law was "
                   "extrapolated there",
                   res->g_min, law.g_lo);
    st = LJGAP_OK;
end:
    sim_law_free(&law);
    run_free(&run);
    pthread_mutex_destroy(&run.lock);
    free(tid);
    free(order);
    if (st) ljgap_sim_result_free(res);
    return st;
}
