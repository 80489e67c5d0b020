/* paper.c -- the paper's iteration (16)-(18) as printed: the faithful baseline.
 *
 * Dimensionless (theory.md §1). Starting from a flat gap, Φ(g, k1) = δ(g - g_ave), wave
 * packets [ka, kb] are added one after another:
 *
 *   V(g0; ka, kb) = 2π ∫_ka^kb s P(s) f(g0, s)^2 ds                                 (17)
 *   Φ(g, kb) = ∫ Φ(g0, ka) exp(-(g - g0)^2 / 2V(g0)) / √(2πV(g0)) dg0              (16),(18)
 *   sigma_bar(g_ave) = ∫ Φ(g, k2) sigma(g) dg                                        (21)
 *
 * Discretisation (the paper's Section 3.1.1):
 *  - a uniform gap grid g_i = g_lo + i h, h = min(0.005, √Vmax/10) so that h^2 << Vmax;
 *  - bands chosen so that V(g*, band) = Vmax exactly, g* = (15/2)^(1/6) being where f is
 *    largest for every k (so V <= Vmax at every grid point); snapshot wavenumbers are band
 *    edges; for k2 = ∞ the bands stop at kmax, where f(g_lo, kmax) = 0.999, and the rest of
 *    the variance m0 - cumvar(kmax) is one exact heat-kernel step (f = 1);
 *  - each band moves the mass p_j of grid point j to the points within 8√V_j with weights
 *    ∝ exp(-(g_i - g_j)^2 / 2V_j) normalized to sum 1 (mass is conserved exactly; the mean
 *    too, except for what the lower end cuts off: that "leak" is measured and reported).
 *    A packet narrower than the grid (V_j < h^2) goes to five points with the Gaussian's
 *    exact mass, mean and variance instead (a three-point kernel applied twice): the
 *    sampled Gaussian would keep its mass in place and lose V_j. The start δ(g - g_ave) is
 *    split linearly between the two neighbouring points (mass and mean exact).
 *  - the traction curve comes from the transposed iteration u <- T^T u, u = sigma(g_i) at
 *    the end, which gives sigma_bar at every grid point in one pass with the same arithmetic
 *    as a forward run from each point; between points it is interpolated linearly, which
 *    equals the split start.
 *
 * Grid ends: g_lo = 0.5 min(1, lowest gap asked for) to begin with; the leak (probability
 * renormalized at the ends) is computed alongside, and while leak * |sigma(g_lo)| exceeds
 * tol/10 the lower end is moved down (theory.md §3: for D near 3 the finest waves carry
 * paths close to the wall). g_hi = max(8, g_end + 10√m0), g_end being the largest gap whose
 * sigma_bar is needed (for the summary max(8, 12√m0 + 1), beyond which the analytic tail of
 * ljgap__curve_summary takes over).
 *
 * Error: the iteration is first order in Vmax, so each level is compared with one at Vmax/2
 * (h follows the rule); err = |r(V) - r(V/2)|, or the larger of the last two such differences
 * once there are two (convergence is irregular), and the V/2 value is reported. Vmax is halved
 * until err <= tol max(1, |value|) or the work cap (grid points x window, summed over bands
 * and levels: o->max_work) or o->max_seconds is reached, with a warning at the cap. Each
 * halving costs about 2√2 times the previous level (5.7 times below Vmax = 1/400, where h
 * halves too): the method is the baseline to compare with, not the fast one. With
 * o->fixed_vmax the answer is the level at o->vmax itself (as the paper's figures show it),
 * with 3 |r(V) - r(V/2)| as its error and a warning if that misses tol.
 */
#include "paper.h"
#include "core.h" /* the core's internals */

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PAPER_WIN 8.0       /* Gaussian window half-width, in standard deviations */
#define PAPER_FCLOSE 0.999  /* f(g_lo, kmax): beyond kmax one heat-kernel step */
#define PAPER_HMAX 0.005    /* largest grid spacing */
#define PAPER_GLO_MIN 0.05  /* the lower grid end is not moved below this */
#define PAPER_NCURVE_G0 0.9 /* the summary's curve starts here (g_eq >= 1 for any roughness) */

double ljgap__paper_h(double vmax)
{
    double h = sqrt(vmax) / 10.0;
    return h < PAPER_HMAX ? h : PAPER_HMAX;
}

static int push_band(ljgap__paper_ws *ws, double ka, double kb, double vfix)
{
    if (ws->nb == ws->cap) {
        size_t cap = ws->cap ? 2 * ws->cap : 256;
        double *a = realloc(ws->ka, cap * sizeof *a);
        if (!a) return LJGAP_ENOMEM;
        ws->ka = a;
        a = realloc(ws->kb, cap * sizeof *a);
        if (!a) return LJGAP_ENOMEM;
        ws->kb = a;
        a = realloc(ws->vfix, cap * sizeof *a);
        if (!a) return LJGAP_ENOMEM;
        ws->vfix = a;
        ws->cap = cap;
    }
    ws->ka[ws->nb] = ka;
    ws->kb[ws->nb] = kb;
    ws->vfix[ws->nb] = vfix;
    ws->nb++;
    return LJGAP_OK;
}

/* The kb in (ka, kend] with V(g*; ka, kb) = vmax, or kend when the rest is smaller. */
static double band_end(const ljgap_psd *psd, double gs, double vmax, double ka, double kend)
{
    if (ljgap_packet_var(psd, gs, ka, kend) <= vmax) return kend;
    /* f(g*, k) decreases with k, so f(g*, ka) gives a first guess with V <= vmax */
    double fa = ljgap_f(gs, ka);
    double tau = ljgap_psd_cumvar(psd, ka) + vmax / (fa * fa);
    double lo = ka, hi = tau < psd->m0 ? ljgap_psd_k_of_cumvar(psd, tau) : kend;
    if (!(hi > ka) || !(hi < kend)) hi = kend;
    while (hi < kend && ljgap_packet_var(psd, gs, ka, hi) < vmax) {
        lo = hi;
        hi = ka + 2.0 * (hi - ka);
        if (hi > kend) hi = kend;
    }
    for (int it = 0; it < 200 && hi - lo > 1e-14 * hi; it++) {
        double mid = 0.5 * (lo + hi);
        if (ljgap_packet_var(psd, gs, ka, mid) <= vmax)
            lo = mid;
        else
            hi = mid;
    }
    return lo > ka ? lo : hi;
}

void ljgap__paper_free(ljgap__paper_ws *ws)
{
    if (!ws) return;
    free(ws->ka);
    free(ws->kb);
    free(ws->vfix);
    free(ws->snap);
    free(ws->tmp);
    free(ws->tmp2);
    free(ws->e);
    free(ws);
}

ljgap__paper_ws *ljgap__paper_alloc(const ljgap_psd *psd, double vmax, double h, double g_lo,
                                    double g_hi, const double *ks, size_t nks)
{
    if (!psd || !(vmax > 0) || !(h > 0) || !(g_lo > 0) || !(g_hi > g_lo + 2 * h) || !isfinite(g_hi))
        return NULL;
    ljgap__paper_ws *ws = calloc(1, sizeof *ws);
    if (!ws) return NULL;
    ws->g_lo = g_lo;
    ws->h = h;
    ws->n = (size_t)floor((g_hi - g_lo) / h) + 1;
    ws->vmax = vmax;
    ws->nsnap = nks ? nks : 1;
    ws->snap = calloc(ws->nsnap, sizeof *ws->snap);
    ws->tmp = malloc(ws->n * sizeof *ws->tmp);
    ws->tmp2 = malloc(ws->n * sizeof *ws->tmp2);
    if (!ws->snap || !ws->tmp || !ws->tmp2) goto fail;

    const double gs = ljgap_gstar(), k0 = ljgap_k0();
    const double kfull = psd->k2;
    double kmax = kfull;
    if (isinf(kfull)) {
        double g4 = pow(g_lo, 4.0), g10 = pow(g_lo, 10.0);
        kmax = PAPER_FCLOSE / (1.0 - PAPER_FCLOSE) * (9.0 / g10 - 3.0 / g4);
        if (kmax < 1000.0 * k0) kmax = 1000.0 * k0;
        if (kmax < psd->k1) kmax = psd->k1;
    }
    double vbig = vmax, k = psd->k1;
    for (size_t s = 0; s < ws->nsnap; s++) {
        double t = nks ? ks[s] : kfull;
        if (t > kfull) t = kfull;
        while (k < t) {
            int st;
            if (k < kmax) {
                double kb = band_end(psd, gs, vmax, k, t < kmax ? t : kmax);
                if (!(kb > k)) goto fail;
                st = push_band(ws, k, kb, -1.0);
                k = kb;
            } else {
                double v =
                    (isinf(t) ? psd->m0 : ljgap_psd_cumvar(psd, t)) - ljgap_psd_cumvar(psd, k);
                if (v < 0) v = 0;
                if (v > vbig) vbig = v;
                st = push_band(ws, k, t, v);
                k = t;
            }
            if (st) goto fail;
        }
        ws->snap[s] = ws->nb;
    }
    double half = PAPER_WIN * sqrt(vbig * (1.0 + 1e-9)) / h;
    ws->emax = half < (double)ws->n ? (size_t)half + 1 : ws->n;
    ws->e = malloc((ws->emax + 1) * sizeof *ws->e);
    if (!ws->e) goto fail;
    return ws;
fail:
    ljgap__paper_free(ws);
    return NULL;
}

/* One band. Forward (back = 0): out = T in, ws->leak += mass cut at the lower end. Transposed
 * (back = 1): out = T^T in, and lout = c + T^T lin when lout != NULL, c_j being the weight
 * of row j cut at the lower end. */
static void band_apply(ljgap__paper_ws *ws, const ljgap_psd *psd, size_t b, const double *in,
                       double *out, int back, const double *lin, double *lout)
{
    const size_t n = ws->n;
    const double h = ws->h;
    double *e = ws->e;
    if (!back) memset(out, 0, n * sizeof *out);
    for (size_t j = 0; j < n; j++) {
        if (!back && in[j] == 0.0) continue;
        double V = ws->vfix[b] >= 0
                       ? ws->vfix[b]
                       : ljgap_packet_var(psd, ws->g_lo + (double)j * h, ws->ka[b], ws->kb[b]);
        size_t M;
        if (V < h * h) {
            /* Narrower than the grid: the sampled Gaussian would keep (almost) all the mass
             * in place and lose the variance V, at every band, wherever f is small (near
             * the wall, and everywhere but g* at a stiff start), so the iteration would
             * converge to a wrong limit as Vmax and h shrink together. Instead five points
             * carry the Gaussian's mass, mean and variance exactly: the three-point kernel
             * (b, 1 - 2b, b), b = V/4h^2 <= 1/4, applied twice. (Once, with b = V/2h^2, it
             * would tend to (1/2, 0, 1/2) as V -> h^2 and, applied where V is just below h^2,
             * leave a checkerboard in the PDF: peaks 10 % off at Vmax = 1/160 and 1/250 for
             * Fig. 2. The twice-applied kernel's symbol is a square, so it damps every grid
             * mode, and at V = h^2 it is the binomial (1, 4, 6, 4, 1)/16, close to the
             * sampled Gaussian that takes over there.) */
            double b4 = V / (4.0 * h * h);
            e[0] = (1.0 - 2.0 * b4) * (1.0 - 2.0 * b4) + 2.0 * b4 * b4;
            e[1] = 2.0 * b4 * (1.0 - 2.0 * b4);
            e[2] = b4 * b4;
            M = ws->emax < 2 ? ws->emax : 2;
        } else {
            double half = PAPER_WIN * sqrt(V) / h;
            M = half < (double)ws->emax ? (size_t)half : ws->emax;
            /* e_m = exp(-m^2 h^2/2V) = Π_{i<=m} r^(2i-1), r = exp(-h^2/2V); for V >= h^2 the
             * sampled Gaussian's variance is V to ~exp(-2π^2) relative */
            double r = exp(-h * h / (2.0 * V)), r2 = r * r, rm = r;
            e[0] = 1.0;
            for (size_t m = 1; m <= M; m++) {
                e[m] = e[m - 1] * rm;
                rm *= r2;
            }
        }
        size_t ml = M < j ? M : j, mr = M < n - 1 - j ? M : n - 1 - j;
        double S = e[0];
        for (size_t m = 1; m <= ml; m++)
            S += e[m];
        for (size_t m = 1; m <= mr; m++)
            S += e[m];
        double c = 0.0; /* weight cut at the lower end (the upper end is 10√m0 away) */
        if (ml < M) {
            double cut = 0.0, cutr = 0.0;
            for (size_t m = ml + 1; m <= M; m++)
                cut += e[m];
            for (size_t m = mr + 1; m <= M; m++)
                cutr += e[m];
            c = cut / (S + cut + cutr);
        }
        const size_t i0 = j - ml;
        if (back) {
            double acc = 0.0, lacc = 0.0;
            for (size_t i = i0; i <= j + mr; i++) {
                double wgt = e[i < j ? j - i : i - j];
                acc += wgt * in[i];
                if (lout) lacc += wgt * lin[i];
            }
            out[j] = acc / S;
            if (lout) lout[j] = c + lacc / S;
        } else {
            double a = in[j] / S;
            for (size_t i = i0; i <= j + mr; i++)
                out[i] += a * e[i < j ? j - i : i - j];
            ws->leak += in[j] * c;
        }
        ws->work += (long)(ml + mr + 1);
    }
}

static int stop_status(const ljgap_opts *o, double deadline)
{
    if (!o || !ljgap__should_stop(o, deadline)) return LJGAP_OK;
    return (o->cancel && *o->cancel) ? LJGAP_ECANCEL : LJGAP_ECAP;
}

static int all_finite(const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

int ljgap__paper_forward(ljgap__paper_ws *ws, const ljgap_psd *psd, double *p, size_t b0, size_t b1,
                         const ljgap_opts *o, double deadline)
{
    for (size_t b = b0; b < b1 && b < ws->nb; b++) {
        int st = stop_status(o, deadline);
        if (st) return st;
        band_apply(ws, psd, b, p, ws->tmp, 0, NULL, NULL);
        memcpy(p, ws->tmp, ws->n * sizeof *p);
    }
    return all_finite(p, ws->n) ? LJGAP_OK : LJGAP_EFAIL;
}

int ljgap__paper_backward(ljgap__paper_ws *ws, const ljgap_psd *psd, double *u, double *leak,
                          const ljgap_opts *o, double deadline)
{
    if (leak) memset(leak, 0, ws->n * sizeof *leak);
    for (size_t b = ws->nb; b-- > 0;) {
        int st = stop_status(o, deadline);
        if (st) return st;
        band_apply(ws, psd, b, u, ws->tmp, 1, leak, leak ? ws->tmp2 : NULL);
        memcpy(u, ws->tmp, ws->n * sizeof *u);
        if (leak) memcpy(leak, ws->tmp2, ws->n * sizeof *leak);
    }
    return all_finite(u, ws->n) ? LJGAP_OK : LJGAP_EFAIL;
}

/* Linear interpolation of v on the grid (g_lo, h, n); 0 outside. */
static double grid_interp(const double *v, size_t n, double g_lo, double h, double g)
{
    double x = (g - g_lo) / h;
    if (!(x >= 0) || x > (double)(n - 1)) return 0.0;
    size_t j = (size_t)x;
    if (j >= n - 1) return v[n - 1];
    double t = x - (double)j;
    return (1.0 - t) * v[j] + t * v[j + 1];
}

/* ---- traction ---- */

#define NSUM 4 /* g_eq, sigma_max, g_at_max, dgamma_eff */

typedef struct {
    double g_lo, g_hi; /* grid ends */
    double g_c0;       /* first gap of the summary's curve */
    double g_end;      /* last gap whose sigma_bar is used */
    double g_chk;      /* leak is checked on [g_chk, g_end] */
    int want_sum;      /* compute the summary */
} trac_setup;

/* One level: val[0..n) = sigma_bar at g_ave, val[n..n+NSUM) the summary. */
static int trac_level(const ljgap_psd *psd, const ljgap_opts *o, double deadline, double vmax,
                      const trac_setup *ts, const double *g_ave, size_t n, double *val,
                      double *leak_impact, long *work, ljgap_warnings *w)
{
    double h = ljgap__paper_h(vmax);
    ljgap__paper_ws *ws = ljgap__paper_alloc(psd, vmax, h, ts->g_lo, ts->g_hi, NULL, 0);
    double *u = NULL, *leak = NULL, *g = NULL;
    int st = LJGAP_ENOMEM;
    if (!ws) goto end;
    u = malloc(ws->n * sizeof *u);
    leak = malloc(ws->n * sizeof *leak);
    g = malloc(ws->n * sizeof *g);
    if (!u || !leak || !g) goto end;
    for (size_t i = 0; i < ws->n; i++) {
        g[i] = ws->g_lo + (double)i * h;
        u[i] = ljgap_sigma(g[i]);
    }
    st = ljgap__paper_backward(ws, psd, u, leak, o, deadline);
    *work += ws->work;
    if (st) goto end;
    double lmax = 0.0;
    for (size_t i = 0; i < ws->n; i++)
        if (g[i] >= ts->g_chk - h && g[i] <= ts->g_end + h && leak[i] > lmax) lmax = leak[i];
    double sl = fabs(ljgap_sigma(ts->g_lo));
    *leak_impact = lmax * (sl > 1.0 ? sl : 1.0);
    for (size_t i = 0; i < n; i++)
        val[i] = grid_interp(u, ws->n, ws->g_lo, h, g_ave[i]);
    if (ts->want_sum) {
        size_t i0 = (size_t)ceil((ts->g_c0 - ws->g_lo) / h - 1e-9);
        size_t i1 = (size_t)floor((ts->g_end - ws->g_lo) / h + 1e-9);
        if (i1 >= ws->n) i1 = ws->n - 1;
        ljgap_summary s;
        memset(&s, 0, sizeof s);
        st = ljgap__curve_summary(g + i0, u + i0, i1 - i0 + 1, psd->m0, &s, w);
        if (st) goto end;
        val[n + 0] = s.g_eq.value;
        val[n + 1] = s.sigma_max.value;
        val[n + 2] = s.g_at_max.value;
        val[n + 3] = s.dgamma_eff.value;
    }
    st = all_finite(val, n + (ts->want_sum ? NSUM : 0)) ? LJGAP_OK : LJGAP_EFAIL;
end:
    free(u);
    free(leak);
    free(g);
    ljgap__paper_free(ws);
    return st;
}

/* The grid of the traction driver before its lower end is moved (file comment). */
static void trac_setup_make(trac_setup *ts, const ljgap_psd *psd, const double *g_ave, size_t n,
                            int want_sum)
{
    const double sm = sqrt(psd->m0);
    double gmin = INFINITY, gmax = 0.0;
    for (size_t i = 0; i < n; i++) {
        gmin = fmin(gmin, g_ave[i]);
        gmax = fmax(gmax, g_ave[i]);
    }
    ts->want_sum = want_sum;
    ts->g_c0 = PAPER_NCURVE_G0;
    ts->g_end = gmax;
    if (want_sum) ts->g_end = fmax(ts->g_end, fmax(8.0, 12.0 * sm + 1.0));
    ts->g_chk = want_sum ? fmin(gmin, ts->g_c0) : gmin;
    ts->g_lo = 0.5 * fmin(1.0, ts->g_chk);
    ts->g_hi = fmax(8.0, ts->g_end + 10.0 * sm);
}

int ljgap__paper_summary_at(const ljgap_psd *psd, const ljgap_opts *o, double vmax,
                            ljgap_summary *sum)
{
    if (!(vmax > 0) || !isfinite(vmax)) return LJGAP_EINVAL;
    trac_setup ts;
    trac_setup_make(&ts, psd, NULL, 0, 1);
    double v[NSUM], impact = 0.0;
    long work = 0;
    int st = trac_level(psd, o, ljgap__now() + o->max_seconds, vmax, &ts, NULL, 0, v, &impact,
                        &work, NULL);
    if (st) return st;
    memset(sum, 0, sizeof *sum);
    sum->g_eq.value = v[0];
    sum->sigma_max.value = v[1];
    sum->g_at_max.value = v[2];
    sum->dgamma_eff.value = v[3];
    sum->m0 = psd->m0;
    sum->k0 = ljgap_k0();
    return LJGAP_OK;
}

static int converged(const double *v, const double *err, size_t n, double tol)
{
    for (size_t i = 0; i < n; i++)
        if (err[i] > tol * fmax(1.0, fabs(v[i]))) return 0;
    return 1;
}

/* Estimated work of the level at vmax/2 from the one at vmax: twice the bands, the window
 * in points grows by (h/h')/√2 and the grid by h/h'. */
static double next_work(double work, double vmax)
{
    double q = ljgap__paper_h(vmax) / ljgap__paper_h(0.5 * vmax);
    return (double)work * 2.0 * q * q / M_SQRT2;
}

/* Whether the level at vmax/2 fits in the work cap, given the work spent and that of the
 * last level: LJGAP_OK to run it; 1 to stop with the pair already in hand (warned);
 * LJGAP_ECAP when not even the first pair fits (warned). */
static int level_fits(long work, long last, double vmax, long max_work, int have_pair,
                      ljgap_warnings *w)
{
    double est = next_work((double)last, vmax);
    if ((double)work + est <= (double)max_work) return LJGAP_OK;
    if (!have_pair) {
        ljgap_warn(w,
                   "paper: the error estimate at Vmax = %g needs about %.3g window "
                   "operations, over the cap of %ld",
                   vmax, (double)work + est, max_work);
        return LJGAP_ECAP;
    }
    ljgap_warn(w,
               "paper: work cap reached at Vmax = %g; the error estimate is the difference "
               "from Vmax = %g",
               vmax, 2.0 * vmax);
    return 1;
}

/* After the run at vmax/2 returned *st: a time cap with a pair in hand ends the refinement
 * (returns 1, *st = LJGAP_OK); without one it is an error. Warns either way. */
static int level_timed_out(int *st, int have_pair, double vmax, ljgap_warnings *w)
{
    if (*st != LJGAP_ECAP) return 0;
    if (have_pair) {
        ljgap_warn(w,
                   "paper: time cap reached at Vmax = %g; the error estimate is the difference "
                   "from Vmax = %g",
                   vmax, 2.0 * vmax);
        *st = LJGAP_OK;
        return 1;
    }
    ljgap_warn(w, "paper: time cap reached before the error estimate at Vmax = %g", 0.5 * vmax);
    return 0;
}

/* The error estimate of one quantity from its latest change d under Vmax halving. The
 * iteration converges irregularly (first order in Vmax, with grid effects on top), so once
 * there are two differences the estimate is the larger of them; *dprev keeps the last. */
static double level_err(double d, double *dprev, int have_pair)
{
    double e = have_pair ? fmax(d, *dprev) : d;
    *dprev = d;
    return e;
}

/* With fixed_vmax the answer at Vmax is kept and its error is FIXED_ERR times its change at
 * Vmax/2: 2 would be the first-order limit (Σ 2^-k), but the first halvings are irregular
 * (Fig. 2 PDF at Vmax = 1/10 .. 1/400 against the PDE: actual/estimate up to 1.27 with 2,
 * at most 0.85 with 3). */
#define FIXED_ERR 3.0

/* With fixed_vmax, the warning when the answer at Vmax misses the tolerance. */
static void fixed_warn(const ljgap_opts *o, ljgap_warnings *w)
{
    ljgap_warn(w,
               "paper: the answer at the fixed Vmax = %g is not refined; its error estimate "
               "(3 times the change at Vmax/2) is above the tolerance",
               o->vmax);
}

int ljgap__traction_paper(const ljgap_psd *psd, const ljgap_opts *o, const double *g_ave, size_t n,
                          ljgap_est *sigma, ljgap_summary *sum, ljgap_warnings *w)
{
    if (!(o->vmax > 0) || !isfinite(o->vmax) || (n && !sigma)) return LJGAP_EINVAL;
    const double deadline = ljgap__now() + o->max_seconds;
    trac_setup ts;
    if (!sum && n == 0) return LJGAP_OK;
    trac_setup_make(&ts, psd, g_ave, n, sum != NULL);

    size_t nv = n + (ts.want_sum ? NSUM : 0);
    double *v0 = calloc(nv + 1, sizeof *v0), *v1 = calloc(nv + 1, sizeof *v1);
    double *err = calloc(2 * (nv + 1), sizeof *err);
    double *dprev = err ? err + nv + 1 : NULL; /* the previous difference */
    int st = LJGAP_ENOMEM, have_pair = 0;
    if (!v0 || !v1 || !err) goto end;

    double vmax = o->vmax, impact = 0.0, tol = o->tol;
    long work = 0, last = 0;
    /* the first level also places the lower grid end: it moves down while that lowers the
     * leak's impact (coarse Vmax sends Gaussian tails through the wall, and there a lower
     * end only makes the impact grow) */
    for (;;) {
        long wk = 0;
        double imp1 = 0.0;
        trac_setup t1 = ts;
        if (impact > 0.0) t1.g_lo = fmax(PAPER_GLO_MIN, 0.6 * ts.g_lo);
        st = trac_level(psd, o, deadline, vmax, &t1, g_ave, n, impact > 0.0 ? v1 : v0, &imp1, &wk,
                        w);
        work += wk;
        last = wk;
        if (st) goto end;
        if (impact > 0.0) {
            if (imp1 >= impact) break;
            memcpy(v0, v1, nv * sizeof *v0);
            ts = t1;
        }
        impact = imp1;
        if (impact <= 0.1 * tol || ts.g_lo <= PAPER_GLO_MIN) break;
    }
    if (impact > 0.1 * tol)
        ljgap_warn(w,
                   "paper: probability reaches the lower grid end g = %g (leak x |sigma| = %.3g)",
                   ts.g_lo, impact);
    for (;;) {
        st = level_fits(work, last, vmax, o->max_work, have_pair, w);
        if (st == 1) break;
        if (st) goto end;
        long wk = 0;
        double imp1 = 0.0;
        st = trac_level(psd, o, deadline, 0.5 * vmax, &ts, g_ave, n, v1, &imp1, &wk, w);
        work += wk;
        last = wk;
        if (level_timed_out(&st, have_pair, vmax, w)) break;
        if (st) goto end;
        if (imp1 > 0.1 * tol)
            ljgap_warn(w,
                       "paper: probability reaches the lower grid end g = %g (leak x "
                       "|sigma| = %.3g)",
                       ts.g_lo, imp1);
        vmax *= 0.5;
        for (size_t i = 0; i < nv; i++) {
            double d = fabs(v1[i] - v0[i]);
            err[i] = o->fixed_vmax ? FIXED_ERR * d : level_err(d, &dprev[i], have_pair);
        }
        if (o->fixed_vmax) { /* keep v0, the answer at o->vmax */
            if (!converged(v0, err, nv, tol)) fixed_warn(o, w);
            break;
        }
        memcpy(v0, v1, nv * sizeof *v0);
        have_pair = 1;
        if (converged(v0, err, nv, tol)) break;
    }
    for (size_t i = 0; i < n; i++) {
        sigma[i].value = v0[i];
        sigma[i].err = err[i];
    }
    if (sum) {
        sum->g_eq = (ljgap_est){v0[n + 0], err[n + 0]};
        sum->sigma_max = (ljgap_est){v0[n + 1], err[n + 1]};
        sum->g_at_max = (ljgap_est){v0[n + 2], err[n + 2]};
        sum->dgamma_eff = (ljgap_est){v0[n + 3], err[n + 3]};
        sum->m0 = psd->m0;
        sum->k0 = ljgap_k0();
    }
    st = LJGAP_OK;
end:
    free(v0);
    free(v1);
    free(err);
    return st;
}

/* ---- PDF ---- */

typedef struct {
    double g_lo, h; /* grid */
    size_t n;       /* grid points */
    double *p;      /* nk x n masses, snapshot s at p + s n */
} pdf_level;

static void pdf_level_free(pdf_level *L)
{
    free(L->p);
    L->p = NULL;
}

/* Forward run from the split δ at g_ave, snapshots at ks (ascending, nk >= 1). */
static int pdf_run(const ljgap_psd *psd, const ljgap_opts *o, double deadline, double vmax,
                   double g_lo, double g_hi, double g_ave, const double *ks, size_t nk,
                   pdf_level *L, double *leak, long *work)
{
    double h = ljgap__paper_h(vmax);
    ljgap__paper_ws *ws = ljgap__paper_alloc(psd, vmax, h, g_lo, g_hi, ks, nk);
    if (!ws) return LJGAP_ENOMEM;
    L->g_lo = g_lo;
    L->h = h;
    L->n = ws->n;
    L->p = calloc(nk * ws->n, sizeof *L->p);
    int st = LJGAP_ENOMEM;
    if (!L->p) goto end;
    double *p = ws->tmp2;
    memset(p, 0, ws->n * sizeof *p);
    double x = (g_ave - g_lo) / h;
    size_t j = (size_t)x;
    if (j + 1 >= ws->n) {
        st = LJGAP_EINVAL;
        goto end;
    }
    p[j] = 1.0 - (x - (double)j);
    p[j + 1] = x - (double)j;
    size_t b = 0;
    for (size_t s = 0; s < nk; s++) {
        st = ljgap__paper_forward(ws, psd, p, b, ws->snap[s], o, deadline);
        if (st) goto end;
        b = ws->snap[s];
        memcpy(L->p + s * ws->n, p, ws->n * sizeof *p);
    }
    st = LJGAP_OK;
end:
    *leak = ws->leak;
    *work += ws->work;
    ljgap__paper_free(ws);
    if (st) pdf_level_free(L);
    return st;
}

/* sum of sigma(g_i) p_i */
static double pdf_sigma(const pdf_level *L, const double *p)
{
    double s = 0.0;
    for (size_t i = 0; i < L->n; i++)
        s += p[i] * ljgap_sigma(L->g_lo + (double)i * L->h);
    return s;
}

/* L1 distance of the densities of A (coarse) and B (fine), on A's grid. */
static double pdf_l1(const pdf_level *A, const double *pa, const pdf_level *B, const double *pb)
{
    double d = 0.0;
    for (size_t i = 0; i < A->n; i++) {
        double g = A->g_lo + (double)i * A->h;
        double fb = grid_interp(pb, B->n, B->g_lo, B->h, g) / B->h;
        d += fabs(pa[i] / A->h - fb) * A->h;
    }
    return d;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The density p/h of the masses p on level A, at its nodes or on grid {min,max,n} (linear
 * interpolation), with mass and mean, into out (g, phi, n, mass, mean). */
static int pdf_out(const pdf_level *A, const double *p, const double *grid, ljgap_pdf *out)
{
    size_t m = grid ? (size_t)grid[2] : A->n;
    double g0 = grid ? grid[0] : A->g_lo;
    double dg = grid ? (grid[1] - grid[0]) / (double)(m - 1) : A->h;
    out->n = m;
    out->g = malloc(m * sizeof *out->g);
    out->phi = malloc(m * sizeof *out->phi);
    if (!out->g || !out->phi) return LJGAP_ENOMEM;
    double mass = 0.0, mean = 0.0;
    for (size_t j = 0; j < m; j++) {
        double g = g0 + (double)j * dg;
        out->g[j] = g;
        out->phi[j] = grid ? grid_interp(p, A->n, A->g_lo, A->h, g) / A->h : p[j] / A->h;
        mass += out->phi[j] * dg;
    }
    for (size_t j = 0; j < A->n; j++)
        mean += p[j] * (A->g_lo + (double)j * A->h);
    out->mass = mass;
    out->mean = mean;
    return LJGAP_OK;
}

/* The grid ends of the PDF driver before its lower end is moved (file comment). */
static void pdf_ends(const ljgap_psd *psd, double g_ave, double *g_lo, double *g_hi)
{
    *g_lo = 0.5 * fmin(1.0, g_ave);
    *g_hi = fmax(8.0, g_ave + 10.0 * sqrt(psd->m0));
}

int ljgap__paper_pdf_at(const ljgap_psd *psd, const ljgap_opts *o, double vmax, double g_ave,
                        double k2, const double *grid, ljgap_pdf *out)
{
    if (!(vmax > 0) || !isfinite(vmax)) return LJGAP_EINVAL;
    double g_lo, g_hi, leak = 0.0, ks = fmin(k2, psd->k2);
    long work = 0;
    pdf_level A = {0};
    memset(out, 0, sizeof *out);
    pdf_ends(psd, g_ave, &g_lo, &g_hi);
    int st = pdf_run(psd, o, ljgap__now() + o->max_seconds, vmax, g_lo, g_hi, g_ave, &ks, 1, &A,
                     &leak, &work);
    if (st) return st;
    out->k2 = k2;
    out->sigma = (ljgap_est){pdf_sigma(&A, A.p), 0.0};
    st = pdf_out(&A, A.p, grid, out);
    pdf_level_free(&A);
    if (st) ljgap_pdf_release(out, 1);
    return st;
}

int ljgap__pdf_paper(const ljgap_psd *psd, const ljgap_opts *o, double g_ave, const double *k2,
                     size_t nk2, const double *grid, ljgap_pdf *out, ljgap_warnings *w)
{
    if (!(o->vmax > 0) || !isfinite(o->vmax)) return LJGAP_EINVAL;
    if (nk2 == 0) return LJGAP_OK;
    const double deadline = ljgap__now() + o->max_seconds, tol = o->tol;
    double *ks = malloc(nk2 * sizeof *ks), *serr = calloc(2 * nk2, sizeof *serr);
    double *perr = calloc(2 * nk2, sizeof *perr), *sig = calloc(nk2, sizeof *sig);
    double *sprev = serr ? serr + nk2 : NULL, *pprev = perr ? perr + nk2 : NULL;
    pdf_level A = {0}, B = {0};
    int st = LJGAP_ENOMEM, have_pair = 0;
    if (!ks || !serr || !perr || !sig) goto end;
    for (size_t i = 0; i < nk2; i++)
        ks[i] = fmin(k2[i], psd->k2);
    qsort(ks, nk2, sizeof *ks, cmp_double);

    double g_lo, g_hi;
    pdf_ends(psd, g_ave, &g_lo, &g_hi);
    double vmax = o->vmax, impact = 0.0;
    long work = 0, last = 0;
    for (;;) { /* place the lower grid end as for the traction */
        long wk = 0;
        double leak = 0.0, g1 = impact > 0.0 ? fmax(PAPER_GLO_MIN, 0.6 * g_lo) : g_lo;
        st = pdf_run(psd, o, deadline, vmax, g1, g_hi, g_ave, ks, nk2, &B, &leak, &wk);
        work += wk;
        last = wk;
        if (st) goto end;
        double imp1 = leak * fmax(1.0, fabs(ljgap_sigma(g1)));
        if (impact > 0.0 && imp1 >= impact) {
            pdf_level_free(&B);
            break;
        }
        pdf_level_free(&A);
        A = B;
        B.p = NULL;
        g_lo = g1;
        impact = imp1;
        if (impact <= 0.1 * tol || g_lo <= PAPER_GLO_MIN) break;
    }
    if (impact > 0.1 * tol)
        ljgap_warn(w,
                   "paper: probability reaches the lower grid end g = %g (leak x |sigma| = %.3g)",
                   g_lo, impact);
    for (size_t s = 0; s < nk2; s++)
        sig[s] = pdf_sigma(&A, A.p + s * A.n);
    for (;;) {
        st = level_fits(work, last, vmax, o->max_work, have_pair, w);
        if (st == 1) break;
        if (st) goto end;
        long wk = 0;
        double leak = 0.0;
        st = pdf_run(psd, o, deadline, 0.5 * vmax, g_lo, g_hi, g_ave, ks, nk2, &B, &leak, &wk);
        work += wk;
        last = wk;
        if (level_timed_out(&st, have_pair, vmax, w)) break;
        if (st) goto end;
        vmax *= 0.5;
        int ok = 1;
        for (size_t s = 0; s < nk2; s++) {
            double sb = pdf_sigma(&B, B.p + s * B.n);
            double ds = fabs(sb - sig[s]), dl = pdf_l1(&A, A.p + s * A.n, &B, B.p + s * B.n);
            if (o->fixed_vmax) { /* A and sig stay: the answer at o->vmax */
                serr[s] = FIXED_ERR * ds;
                perr[s] = FIXED_ERR * dl;
            } else {
                serr[s] = level_err(ds, &sprev[s], have_pair);
                perr[s] = level_err(dl, &pprev[s], have_pair);
                sig[s] = sb;
            }
            if (serr[s] > tol * fmax(1.0, fabs(sig[s])) || perr[s] > tol) ok = 0;
        }
        if (o->fixed_vmax) {
            if (!ok) fixed_warn(o, w);
            break;
        }
        pdf_level_free(&A);
        A = B;
        B.p = NULL;
        have_pair = 1;
        if (ok) break;
    }
    /* output, in the caller's order of k2 */
    for (size_t i = 0; i < nk2; i++) {
        double kq = fmin(k2[i], psd->k2);
        size_t s = 0;
        while (s + 1 < nk2 && ks[s] != kq)
            s++;
        out[i].k2 = k2[i];
        st = pdf_out(&A, A.p + s * A.n, grid, &out[i]);
        if (st) goto end;
        out[i].sigma = (ljgap_est){sig[s], serr[s]};
        out[i].phi_err = perr[s];
    }
    st = LJGAP_OK;
end:
    pdf_level_free(&A);
    pdf_level_free(&B);
    free(ks);
    free(serr);
    free(perr);
    free(sig);
    return st;
}
