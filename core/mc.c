/* mc.c -- Monte Carlo of the Itô process behind the paper's update (18) (theory.md §2).
 *
 * The gap at one point of the interface, as wave numbers are added from k1 to k2, is
 *
 *   dG = f(G, k) √(2π k P(k)) dW_k,   G(k1) = g_ave,                           (14),(17),(18)
 *
 * and the mean traction is sigma_bar(g_ave) = E sigma(G(k2))                     (21).
 * Paths are marched in w = ln(k - k0), k0 of (19), which spreads out the stiff start when k1
 * is near k0. One step [k_a, k_b] adds f(G, k_mid)·√(2π∫ s P ds)·ξ, ξ ~ N(0,1), the band
 * variance exact and f taken at the start gap (Itô) and the midpoint in w. Step control per
 * path: the increment's standard deviation is at most c·ℓ, ℓ = min(0.1 G, f/|∂f/∂g|) the
 * length over which the transfer changes, and the step in w at most c (default c = 0.15,
 * mc.h; the bias, O(c^2), is checked in the tests by halving c). A gap that falls to
 * g <= 0.05 is clamped there and counted (a warning). For k2 = ∞ a path is marched until
 * f ≈ 1 (1 - 1e-4) even 8 standard deviations of the remaining variance below it, and the
 * remaining variance m0 - cumvar(k) is added as one Gaussian step.
 *
 * Random numbers: a gsl_rng_mt19937 master stream seeded from o->seed (and the batch) gives
 * each path the seed of its own gsl_rng_taus2 stream, so that path i sees the same random
 * numbers at every g_ave (common random numbers: the traction curve is smooth across g_ave)
 * whatever the number of steps the path takes; gsl_ran_gaussian_ziggurat draws.
 *
 * Errors: sigma_bar at given g_ave, the standard error over paths; the summary (curve of 48
 * g_ave on [0.8, max(8, 12√m0 + 1)], denser at the low end, through ljgap__curve_summary)
 * by 16 batch means; both plus the step bias measured by a run at 2c (ljgap__traction_mc),
 * and so are the PDFs' sigma and L1 error (ljgap__pdf_mc). Work (path steps summed over points) is
 * capped by o->max_work and time by o->max_seconds: a pilot batch measures the cost and the number
 * of paths is reduced with a warning when needed.
 */
#include "mc.h"
#include "core.h" /* the core's internals */

#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define MC_GFLOOR 0.05     /* gaps are clamped here */
#define MC_TAIL_F 1e-4     /* k2 = ∞: 1 - f below which the path is still marched */
#define MC_KSTOP 1e14      /* ... but never beyond this k */
#define MC_MAXSTEPS 200000 /* per path */
#define MC_NB 16           /* batches */
#define MC_NCURVE 48       /* g_ave points of the summary's curve */

typedef struct {
    const ljgap_psd *psd; /* the spectrum */
    double c;             /* step control */
    double k0;            /* (19) */
    gsl_rng *r;           /* the path's stream */
    long steps;           /* steps taken */
    long clamp;           /* gaps clamped at MC_GFLOOR */
    long cross;           /* closing Gaussian steps that crossed MC_GFLOOR */
    long capped;          /* paths stopped at MC_MAXSTEPS */
} mc_state;

static uint64_t mix64(uint64_t x)
{
    x += 0x9E3779B97F4A7C15ULL;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
    return x ^ (x >> 31);
}

/* f(g,k) of (14) and the length den/|∂den/∂g| = f/|∂f/∂g| over which it changes. */
static double f_len(double g, double k, double *len)
{
    double g2 = g * g, g4 = g2 * g2, g5 = g4 * g, g10 = g5 * g5;
    double den = k + 9.0 / g10 - 3.0 / g4, dden = -90.0 / (g10 * g) + 12.0 / g5;
    *len = dden != 0.0 ? den / fabs(dden) : INFINITY;
    return k / den;
}

static double clamp_floor(mc_state *m, double G, long *count)
{
    if (G > MC_GFLOOR) return G;
    (*count)++;
    return MC_GFLOOR;
}

/* March G from w = ln(k - k0) to the wavenumber kend (finite, <= psd->k2, or INFINITY for an
 * infinite PSD, which ends with the closing Gaussian step). */
static double mc_march(mc_state *m, double G, double *w, double kend)
{
    const ljgap_psd *psd = m->psd;
    const double k0 = m->k0, c = m->c;
    const int tail = isinf(kend);
    const double wend = tail ? INFINITY : log(kend - k0);
    for (long s = 0; *w < wend; s++) {
        double k = k0 + exp(*w);
        if (tail) {
            double vrem = psd->m0 - ljgap_psd_cumvar(psd, k);
            if (vrem < 0) vrem = 0;
            double gl = G - 8.0 * sqrt(vrem);
            if ((gl > MC_GFLOOR && ljgap_f(gl, k) >= 1.0 - MC_TAIL_F) || k > MC_KSTOP) {
                G += sqrt(vrem) * gsl_ran_gaussian_ziggurat(m->r, 1.0);
                return clamp_floor(m, G, &m->cross);
            }
        }
        if (s >= MC_MAXSTEPS) {
            m->capped++;
            return G;
        }
        double len, f = f_len(G, k, &len);
        double ell = fmin(0.1 * G, len), dv = c * ell;
        double rate = 2.0 * M_PI * k * ljgap_psd_eval(psd, k) * (k - k0) * f * f;
        double dw = c;
        if (rate * dw > dv * dv) dw = dv * dv / rate;
        double w1 = *w + dw, kb;
        if (w1 >= wend) {
            w1 = wend;
            kb = kend;
        } else {
            kb = k0 + exp(w1);
        }
        double var = ljgap_psd_var(psd, k, kb);
        double fm = ljgap_f(G, k0 + exp(0.5 * (*w + w1)));
        G += fm * sqrt(var) * gsl_ran_gaussian_ziggurat(m->r, 1.0);
        G = clamp_floor(m, G, &m->clamp);
        *w = w1;
        m->steps++;
    }
    return G;
}

/* One path from g_ave through the ascending snapshots ks[0..nk) (values >= psd->k2 mean the
 * whole PSD); Gs receives the gap at each. */
static void mc_path(mc_state *m, unsigned long seed, double g_ave, const double *ks, size_t nk,
                    double *Gs)
{
    gsl_rng_set(m->r, seed);
    double G = g_ave, w = log(m->psd->k1 - m->k0);
    for (size_t s = 0; s < nk; s++) {
        double kt = ks[s] >= m->psd->k2 ? m->psd->k2 : ks[s];
        G = mc_march(m, G, &w, kt);
        Gs[s] = G;
    }
}

static void mc_report(const mc_state *m, ljgap_warnings *w)
{
    if (m->clamp)
        ljgap_warn(w, "montecarlo: %ld steps reached the gap floor g = %g and were clamped",
                   m->clamp, MC_GFLOOR);
    if (m->cross)
        ljgap_warn(w,
                   "montecarlo: the closing Gaussian step (k2 = infinity) crossed g = %g "
                   "for %ld paths",
                   MC_GFLOOR, m->cross);
    if (m->capped)
        ljgap_warn(w, "montecarlo: %ld paths stopped after %d steps", m->capped, MC_MAXSTEPS);
}

static int stop_status(const ljgap_opts *o, double deadline)
{
    if (!ljgap__should_stop(o, deadline)) return LJGAP_OK;
    return (o->cancel && *o->cancel) ? LJGAP_ECANCEL : LJGAP_ECAP;
}

/* A cancel check every MC_CANCEL_EVERY paths (path i of a loop): a request whose client went
 * away stops within milliseconds, whatever the number of paths per batch. */
#define MC_CANCEL_EVERY 32
#define MC_PILOT_SHARE 0.1 /* the pilot's share of the time budget, at most */
static int cancelled_now(const ljgap_opts *o, long i)
{
    return (i % MC_CANCEL_EVERY) == MC_CANCEL_EVERY - 1 && o->cancel && *o->cancel;
}

/* ---- traction ---- */

int ljgap__mc_traction(const ljgap_psd *psd, const ljgap_opts *o, double c, const double *g_ave,
                       size_t n, ljgap_est *sigma, ljgap_summary *sum, ljgap_warnings *w)
{
    if (!(c > 0) || o->samples < 2 * MC_NB || (n && !sigma)) return LJGAP_EINVAL;
    const double t0 = ljgap__now(), deadline = t0 + o->max_seconds;
    const size_t nc = sum ? MC_NCURVE : 0, np = n + nc;
    if (np == 0) return LJGAP_OK;
    double *g = malloc(np * sizeof *g), *s1 = calloc(np, sizeof *s1), *s2 = calloc(np, sizeof *s2);
    double *bm = calloc(MC_NB * np, sizeof *bm);
    mc_state m = {psd, c, ljgap_k0(), gsl_rng_alloc(gsl_rng_taus2), 0, 0, 0, 0};
    gsl_rng *master = gsl_rng_alloc(gsl_rng_mt19937);
    int st = LJGAP_ENOMEM;
    if (!g || !s1 || !s2 || !bm || !m.r || !master) goto end;
    if (n) memcpy(g, g_ave, n * sizeof *g);
    const double gend = fmax(8.0, 12.0 * sqrt(psd->m0) + 1.0);
    for (size_t i = 0; i < nc; i++)
        g[n + i] = 0.8 + (gend - 0.8) * pow((double)i / (double)(nc - 1), 1.5);
    const double kfull = psd->k2;

    /* pilot: cost per path and point, round-robin over the points so that a pilot cut short
     * (it may use at most MC_PILOT_SHARE of the time budget) still sees every point */
    long B = (o->samples + MC_NB - 1) / MC_NB, Bp = B / 16 > 8 ? B / 16 : 8, done = 0;
    double tp = ljgap__now(), Gend;
    gsl_rng_set(master, mix64(o->seed ^ 0x5bd1e995ULL));
    for (long i = 0; i < Bp; i++) {
        if (cancelled_now(o, i)) {
            st = LJGAP_ECANCEL;
            goto end;
        }
        if (i > 0 && ljgap__now() - tp > MC_PILOT_SHARE * o->max_seconds) break;
        for (size_t p = 0; p < np; p++, done++)
            mc_path(&m, gsl_rng_get(master), g[p], &kfull, 1, &Gend);
    }
    double per_path = (ljgap__now() - tp) / (double)done;
    double steps_pp = (double)m.steps / (double)done;
    double left = deadline - ljgap__now();
    double Bw = (double)o->max_work / (MC_NB * (double)np * fmax(steps_pp, 1.0));
    double Bt = 0.9 * left / (MC_NB * (double)np * fmax(per_path, 1e-9));
    double Bmax = fmin(Bw, Bt);
    if ((double)B > Bmax) {
        long B1 = (long)Bmax;
        if (B1 < 2) {
            ljgap_warn(w, "montecarlo: the caps allow fewer than %d paths per point", 2 * MC_NB);
            st = LJGAP_ECAP;
            goto end;
        }
        ljgap_warn(w,
                   "montecarlo: reduced to %ld paths per point (from %ld) to stay within the "
                   "%s cap",
                   B1 * MC_NB, o->samples, Bw < Bt ? "work" : "time");
        B = B1;
    }
    m.steps = m.clamp = m.cross = m.capped = 0;

    int nb = 0;
    for (int b = 0; b < MC_NB; b++) {
        int stop = 0;
        for (size_t p = 0; p < np && !stop; p++) {
            gsl_rng_set(master, mix64(o->seed * MC_NB + (unsigned long)b));
            double a = 0.0;
            for (long i = 0; i < B; i++) {
                if (cancelled_now(o, i)) {
                    st = LJGAP_ECANCEL;
                    goto end;
                }
                mc_path(&m, gsl_rng_get(master), g[p], &kfull, 1, &Gend);
                a += ljgap_sigma(Gend);
                s2[p] += ljgap_sigma(Gend) * ljgap_sigma(Gend);
            }
            bm[b * np + p] = a / (double)B;
            st = stop_status(o, deadline);
            if (st == LJGAP_ECANCEL) goto end;
            stop = st != LJGAP_OK;
        }
        if (stop) {
            break; /* the partial batch is dropped (its second moments too: see below) */
        }
        for (size_t p = 0; p < np; p++)
            s1[p] += bm[b * np + p] * (double)B;
        nb++;
    }
    if (nb < MC_NB) {
        if (nb < 2) {
            ljgap_warn(w, "montecarlo: time cap reached after %d batch(es)", nb);
            st = LJGAP_ECAP;
            goto end;
        }
        ljgap_warn(w, "montecarlo: time cap reached: %d of %d batches done", nb, MC_NB);
    }
    mc_report(&m, w);
    for (size_t p = 0; p < n; p++) {
        double N = (double)(nb * B), mean = s1[p] / N, var;
        if (nb == MC_NB) {
            var = (s2[p] - N * mean * mean) / (N - 1.0);
        } else { /* second moments were dropped: batch means give the variance */
            double v = 0.0;
            for (int b = 0; b < nb; b++)
                v += pow(bm[b * np + p] - mean, 2);
            var = v / (nb - 1) * (double)B;
        }
        sigma[p].value = mean;
        sigma[p].err = sqrt(fmax(var, 0.0) / N);
        if (!isfinite(mean) || !isfinite(sigma[p].err)) {
            ljgap_warn(w, "montecarlo: non-finite mean traction at g_ave = %g", g[p]);
            st = LJGAP_EFAIL;
            goto end;
        }
    }
    if (sum) {
        double *u = malloc(nc * sizeof *u), acc[4][2] = {{0}};
        if (!u) goto end;
        int nok = 0;
        for (int b = 0; b < nb; b++) {
            ljgap_summary sb;
            for (size_t i = 0; i < nc; i++)
                u[i] = bm[b * np + n + i];
            if (ljgap__curve_summary(g + n, u, nc, psd->m0, &sb, NULL)) continue;
            double v[4] = {sb.g_eq.value, sb.sigma_max.value, sb.g_at_max.value,
                           sb.dgamma_eff.value};
            for (int q = 0; q < 4; q++)
                acc[q][0] += v[q], acc[q][1] += v[q] * v[q];
            nok++;
        }
        for (size_t i = 0; i < nc; i++)
            u[i] = s1[n + i] / (double)(nb * B);
        st = ljgap__curve_summary(g + n, u, nc, psd->m0, sum, w);
        free(u);
        if (st) goto end;
        if (nok < 2) {
            ljgap_warn(w, "montecarlo: the summary failed on all but %d batches", nok);
            st = LJGAP_EFAIL;
            goto end;
        }
        if (nok < nb)
            ljgap_warn(w, "montecarlo: the summary failed on %d of %d batches", nb - nok, nb);
        ljgap_est *e[4] = {&sum->g_eq, &sum->sigma_max, &sum->g_at_max, &sum->dgamma_eff};
        for (int q = 0; q < 4; q++) {
            double mu = acc[q][0] / nok, v = (acc[q][1] - nok * mu * mu) / (nok - 1);
            e[q]->err = sqrt(fmax(v, 0.0) / nok);
        }
        sum->m0 = psd->m0;
        sum->k0 = ljgap_k0();
    }
    st = LJGAP_OK;
end:
    gsl_rng_free(m.r);
    gsl_rng_free(master);
    free(g);
    free(s1);
    free(s2);
    free(bm);
    return st;
}

/* The step control leaves a bias of order c^2 (the scheme is weakly first order in the step
 * variance). A second run at 2c, a quarter of the cost, measures it: b = (r(2c) - r(c))/3.
 * The answer is r(c) - b, and |b| is added to the standard error, so the estimate covers
 * the discretisation as well as the sampling. The two runs share their path seeds. */
int ljgap__traction_mc(const ljgap_psd *psd, const ljgap_opts *o, const double *g_ave, size_t n,
                       ljgap_est *sigma, ljgap_summary *sum, ljgap_warnings *w)
{
    ljgap_opts o1 = *o, o2 = *o;
    o1.max_seconds = 0.75 * o->max_seconds;
    o2.max_seconds = 0.25 * o->max_seconds;
    o1.max_work = (long)(0.75 * (double)o->max_work);
    o2.max_work = (long)(0.25 * (double)o->max_work);
    ljgap_est *s2 = n ? malloc(n * sizeof *s2) : NULL;
    ljgap_summary sum2;
    if (n && !s2) return LJGAP_ENOMEM;
    int st = ljgap__mc_traction(psd, &o1, LJGAP__MC_C, g_ave, n, sigma, sum, w);
    if (st == LJGAP_OK)
        st = ljgap__mc_traction(psd, &o2, 2.0 * LJGAP__MC_C, g_ave, n, s2, sum ? &sum2 : NULL, w);
    if (st == LJGAP_OK) {
        for (size_t i = 0; i < n; i++) {
            double b = (s2[i].value - sigma[i].value) / 3.0;
            sigma[i].value -= b;
            sigma[i].err += fabs(b);
        }
        if (sum) {
            ljgap_est *x = &sum->g_eq;
            const ljgap_est *y = &sum2.g_eq;
            for (int q = 0; q < 4; q++) {
                double b = (y[q].value - x[q].value) / 3.0;
                x[q].value -= b;
                x[q].err += fabs(b);
            }
        }
    }
    free(s2);
    return st;
}

/* ---- PDF ---- */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int ljgap__mc_pdf(const ljgap_psd *psd, const ljgap_opts *o, double c, double g_ave,
                  const double *k2, size_t nk2, const double *grid, ljgap_pdf *out,
                  ljgap_warnings *w)
{
    if (!(c > 0) || o->samples < 2) return LJGAP_EINVAL;
    if (nk2 == 0) return LJGAP_OK;
    const double deadline = ljgap__now() + o->max_seconds;
    const long N0 = o->samples;
    double *ks = malloc(nk2 * sizeof *ks), *G = malloc((size_t)N0 * nk2 * sizeof *G);
    mc_state m = {psd, c, ljgap_k0(), gsl_rng_alloc(gsl_rng_taus2), 0, 0, 0, 0};
    gsl_rng *master = gsl_rng_alloc(gsl_rng_mt19937);
    int st = LJGAP_ENOMEM;
    if (!ks || !G || !m.r || !master) goto end;
    for (size_t i = 0; i < nk2; i++)
        ks[i] = fmin(k2[i], psd->k2);
    qsort(ks, nk2, sizeof *ks, cmp_double);
    gsl_rng_set(master, mix64(o->seed));
    long N = 0;
    while (N < N0) {
        long chunk = N0 - N < 1024 ? N0 - N : 1024;
        for (long i = 0; i < chunk; i++, N++)
            mc_path(&m, gsl_rng_get(master), g_ave, ks, nk2, G + (size_t)N * nk2);
        st = stop_status(o, deadline);
        if (st == LJGAP_ECANCEL) goto end;
        if (N < N0 && (st || m.steps > o->max_work)) {
            ljgap_warn(w, "montecarlo: %s cap reached after %ld of %ld paths", st ? "time" : "work",
                       N, N0);
            break;
        }
    }
    if (N < 2) {
        st = LJGAP_ECAP;
        goto end;
    }
    mc_report(&m, w);
    for (size_t i = 0; i < nk2; i++) {
        double kq = fmin(k2[i], psd->k2);
        size_t s = 0;
        while (s + 1 < nk2 && ks[s] != kq)
            s++;
        double lo = INFINITY, hi = -INFINITY, sm = 0.0, ss = 0.0, gm = 0.0;
        for (long j = 0; j < N; j++) {
            double x = G[(size_t)j * nk2 + s], sg = ljgap_sigma(x);
            lo = fmin(lo, x);
            hi = fmax(hi, x);
            sm += sg;
            ss += sg * sg;
            gm += x;
        }
        size_t npt = grid ? (size_t)grid[2] : 201;
        double g0 = grid ? grid[0] : lo, g1 = grid ? grid[1] : hi;
        if (!(g1 > g0)) g1 = g0 + 1e-6;
        double dg = (g1 - g0) / (double)(npt - 1);
        out[i].k2 = k2[i];
        out[i].n = npt;
        out[i].g = malloc(npt * sizeof *out[i].g);
        out[i].phi = calloc(npt, sizeof *out[i].phi);
        if (!out[i].g || !out[i].phi) {
            st = LJGAP_ENOMEM;
            goto end;
        }
        for (size_t j = 0; j < npt; j++)
            out[i].g[j] = g0 + (double)j * dg;
        for (long j = 0; j < N; j++) { /* bins centred on the grid points */
            double x = (G[(size_t)j * nk2 + s] - g0) / dg + 0.5;
            if (x >= 0.0 && x < (double)npt) out[i].phi[(size_t)x] += 1.0;
        }
        double mass = 0.0, l1 = 0.0;
        for (size_t j = 0; j < npt; j++) {
            double q = out[i].phi[j] / (double)N;
            l1 += sqrt(2.0 / M_PI * q * (1.0 - q) / (double)N);
            out[i].phi[j] = q / dg;
            mass += q;
        }
        double mean = sm / (double)N, var = (ss - (double)N * mean * mean) / (double)(N - 1);
        out[i].mass = mass;
        out[i].mean = gm / (double)N;
        out[i].sigma = (ljgap_est){mean, sqrt(fmax(var, 0.0) / (double)N)};
        out[i].phi_err = l1;
        if (!isfinite(mean) || !isfinite(out[i].sigma.err) || !isfinite(out[i].mean)) {
            ljgap_warn(w, "montecarlo: non-finite result");
            st = LJGAP_EFAIL;
            goto end;
        }
    }
    st = LJGAP_OK;
end:
    gsl_rng_free(m.r);
    gsl_rng_free(master);
    free(ks);
    free(G);
    return st;
}

/* The histogram b at the points of a (piecewise constant around b's points). */
static double hist_at(const ljgap_pdf *b, double g)
{
    if (b->n < 2) return 0.0;
    double dg = (b->g[b->n - 1] - b->g[0]) / (double)(b->n - 1);
    double x = (g - b->g[0]) / dg + 0.5;
    return x >= 0.0 && x < (double)b->n ? b->phi[(size_t)x] : 0.0;
}

/* As for the traction, the step control leaves a bias of order c^2 (for the Fig. 2 spectrum
 * at g_ave = 0.98 the PDF's sigma is off by 0.7 %: seven standard errors of 10^6 paths). A
 * second run at 2c with the same path seeds (a quarter of the cost) measures it:
 * b = (r(2c) - r(c))/3. sigma becomes r(c) - b with |b| added to its standard error; the
 * histogram is left as sampled (a corrected one could go negative) and its L1 estimate gains
 * the L1 distance of the two histograms / 3 (on the same grid when one is asked for; without
 * one the two runs bin on slightly different ranges, which only adds to the estimate). */
int ljgap__pdf_mc(const ljgap_psd *psd, const ljgap_opts *o, double g_ave, const double *k2,
                  size_t nk2, const double *grid, ljgap_pdf *out, ljgap_warnings *w)
{
    ljgap_opts o1 = *o, o2 = *o;
    o1.max_seconds = 0.75 * o->max_seconds;
    o2.max_seconds = 0.25 * o->max_seconds;
    o1.max_work = (long)(0.75 * (double)o->max_work);
    o2.max_work = (long)(0.25 * (double)o->max_work);
    if (nk2 == 0) return LJGAP_OK;
    ljgap_pdf *p2 = calloc(nk2, sizeof *p2);
    if (!p2) return LJGAP_ENOMEM;
    int st = ljgap__mc_pdf(psd, &o1, LJGAP__MC_C, g_ave, k2, nk2, grid, out, w);
    if (st == LJGAP_OK)
        st = ljgap__mc_pdf(psd, &o2, 2.0 * LJGAP__MC_C, g_ave, k2, nk2, grid, p2, w);
    if (st == LJGAP_OK) {
        for (size_t i = 0; i < nk2; i++) {
            double b = (p2[i].sigma.value - out[i].sigma.value) / 3.0, d = 0.0;
            out[i].sigma.value -= b;
            out[i].sigma.err += fabs(b);
            const ljgap_pdf *a = &out[i];
            double dg = a->n > 1 ? (a->g[a->n - 1] - a->g[0]) / (double)(a->n - 1) : 0.0;
            for (size_t j = 0; j < a->n; j++)
                d += fabs(a->phi[j] - hist_at(&p2[i], a->g[j])) * dg;
            out[i].phi_err += d / 3.0;
        }
    }
    ljgap_pdf_release(p2, nk2);
    free(p2);
    return st;
}
