/* input_error.c -- the measurement's uncertainty of the PSD in the answers (issue 29).
 *
 * A PSD given with its errors (a table's P_err, P_corr and tail.exponent_err; a power law's
 * D_err and C_err, m0_err or h_rms_err) is a distribution of PSDs, and every answer computed
 * from it inherits a spread: the answers carry it as "input_error", 1 σ, beside the solver's
 * "error" and with the same keys. The core (ljgap_uncert.h) makes the perturbed PSDs and
 * combines their answers; here each is solved as the nominal PSD is (the same method, tol at
 * least IE_TOL: the solver's error of a perturbed answer is then far below the spread it
 * measures), on up to limits.sweep_threads threads, and the spread is written:
 *   - a table: IE_K draws of the knots in ln P with their neighbours' correlation (P_corr;
 *     absent: independent) and of the tail exponent, from the fixed seed IE_SEED (the answer is
 *     reproducible, so cacheable); input_error is the draws' standard deviation, itself known to
 *     about 1/√(2(K − 1)) (meta.input_error.relative_error);
 *   - a power law: central differences at each parameter ± 1 σ (D_err; the level's error),
 *     parameters independent: 2 solves a parameter.
 * For a table, "extrapolated" says how much of m0 and of Δγeff comes from beyond its last knot
 * (the tail: an assumption, not a measurement), with one more solve of the table cut there;
 * above EXTRAP_WARN a warning. docs/theory.md §9 has the method and its test over independent
 * maps.
 */
#include "input_error.h"
#include "clock.h" /* ljgap__clock_now */
#include "ljgap_uncert.h"
#include "ljgap_units.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* draws of a table PSD, and their seed (fixed: an answer is reproducible, so cacheable) */
#define IE_K 12
#define IE_SEED 29ul
/* the perturbed solves' tol, at least: their solver error (1e-3 relative) is then far below the
 * spread they measure (summary_sd checks it) */
#define IE_TOL 1e-3
/* the tol of the solve of the table cut at its last knot, at least: a fraction wanted to 1e-3
 * (the cut makes the band finite, which the solver resolves slowly) */
#define CUT_TOL 1e-3
/* warn when more than this of m0 or dgamma_eff comes from beyond the last knot */
#define EXTRAP_WARN 0.1
#define IE_THREADS_MAX 16
/* warn when P_corr had to be scaled below this to be sampled (a tridiagonal cut of /v1/psd's
 * knot covariance may need 0.9) */
#define CORR_SCALE_WARN 0.8

/* The perturbed PSDs of one psd spec. */
typedef struct {
    int linear;         /* 1: central differences (power law); 0: draws (table) */
    size_t K;           /* PSDs in psd (0: no uncertainty to carry) */
    size_t npar;        /* linear: parameters; psd[2p] at +h σ, psd[2p+1] at −h σ */
    double h[2];        /* linear: each parameter's step in its σ */
    const char *par[2]; /* linear: their names */
    ljgap_psd psd[LJGAP_UNCERT_KMAX]; /* owned */
    ljgap_uncert_info info;           /* draws: what the sampling did */
} pert;

static void pert_free(pert *p)
{
    for (size_t k = 0; k < p->K; k++)
        ljgap_psd_free(&p->psd[k]);
    p->K = 0;
}

/* The perturbed PSDs of s into p (p->K = 0 when the PSD has no uncertainty or the request does
 * not want it). A status only for an allocation failure; other failures warn and leave none. */
static int pert_make(job *j, const ljgap__psd_spec *s, pert *p)
{
    memset(p, 0, sizeof *p);
    if (!j->rq.input_error) return LJGAP_OK;
    if (s->kind == LJGAP_PSD_POWER) {
        static const char *const level_names[] = {"C", "m0", "h_rms"};
        double hD = ljgap_uncert_step(s->D, s->D_err, 2, 3);
        double hL = ljgap_uncert_step(s->level_val, s->level_err, 0, INFINITY);
        p->linear = 1;
        if (hD > 0) p->h[p->npar] = hD, p->par[p->npar++] = "D";
        if (hL > 0) p->h[p->npar] = hL, p->par[p->npar++] = level_names[s->level];
        for (size_t q = 0; q < p->npar; q++)
            for (int sign = 1; sign >= -1; sign -= 2) {
                ljgap__psd_spec t = *s;
                int st;
                if (p->par[q][0] == 'D')
                    t.D += sign * p->h[q] * s->D_err;
                else
                    t.level_val += sign * p->h[q] * s->level_err;
                if ((st = ljgap__psd_from_spec(&p->psd[p->K], &t))) {
                    pert_free(p);
                    if (st == LJGAP_ENOMEM) return st;
                    ljgap_warn(&j->rq.warn,
                               "input_error: the power law at %s %c %g σ is no PSD; "
                               "the answer carries no input_error",
                               p->par[q], sign > 0 ? '+' : '-', p->h[q]);
                    return LJGAP_OK;
                }
                p->K++;
            }
        return LJGAP_OK;
    }
    if (!s->P_err && !(s->has_tail && s->tail_q_err > 0)) return LJGAP_OK;
    {
        ljgap_psd base;
        double *zero = NULL;
        int st = ljgap__psd_from_spec(&base, s);
        if (st) return st == LJGAP_ENOMEM ? st : LJGAP_OK; /* the answer itself says why */
        if (!s->P_err && !(zero = calloc(s->n, sizeof *zero))) {
            ljgap_psd_free(&base);
            return LJGAP_ENOMEM;
        }
        st = ljgap_uncert_table_draws(&base, s->P_err ? s->P_err : zero, s->P_corr,
                                      s->has_tail ? s->tail_q_err : 0, IE_K, IE_SEED, p->psd,
                                      &p->info);
        ljgap_psd_free(&base);
        free(zero);
        if (st == LJGAP_ENOMEM) return st;
        if (st) {
            ljgap_warn(&j->rq.warn, "input_error: the table's errors could not be sampled; the "
                                    "answer carries no input_error");
            return LJGAP_OK;
        }
        p->K = IE_K;
        if (p->info.corr_scale < CORR_SCALE_WARN)
            ljgap_warn(&j->rq.warn,
                       "input_error: the knots' correlations (P_corr) do not form a covariance "
                       "together; they were scaled by %.3g to sample them",
                       p->info.corr_scale);
        if (p->info.tail_clipped)
            ljgap_warn(&j->rq.warn,
                       "input_error: %d of %zu draws of the tail exponent came within half its "
                       "distance of -2 and were held there (the tail's variance would diverge)",
                       p->info.tail_clipped, p->K);
    }
    return LJGAP_OK;
}

/* The spread of a quantity from its values x[k] on the perturbed PSDs (ok[k]: it has one). */
static double pert_sd(const pert *p, const double *x, const int *ok)
{
    if (p->linear) {
        for (size_t k = 0; k < p->K; k++)
            if (!ok[k]) return NAN;
        return ljgap_uncert_sd_linear(x, p->h, p->npar);
    }
    return ljgap_uncert_sd_sample(x, ok, p->K);
}

/* ---- solving the perturbed PSDs, on up to limits.sweep_threads threads ---- */

/* What to compute on one perturbed PSD: its index k, the options, its own warnings. */
typedef int (*solve_fn)(void *ctx, size_t k, const ljgap_psd *psd, const ljgap_opts *o,
                        ljgap_warnings *w);

typedef struct {
    job *j;
    const pert *p;
    solve_fn fn;
    void *ctx;
    int st[LJGAP_UNCERT_KMAX];
    ljgap_warnings w[LJGAP_UNCERT_KMAX];
    size_t next; /* under lock */
    pthread_mutex_t lock;
} solve_work;

static void *solve_worker(void *arg)
{
    solve_work *sw = arg;
    for (;;) {
        ljgap_opts o = sw->j->rq.opts;
        size_t k;
        pthread_mutex_lock(&sw->lock);
        k = sw->next++;
        pthread_mutex_unlock(&sw->lock);
        if (k >= sw->p->K) return NULL;
        if (o.tol < IE_TOL) o.tol = IE_TOL;
        o.max_seconds = sw->j->deadline - ljgap__clock_now();
        o.cancel = sw->j->cancel;
        sw->st[k] =
            o.max_seconds > 0 ? sw->fn(sw->ctx, k, &sw->p->psd[k], &o, &sw->w[k]) : LJGAP_ECAP;
    }
}

/* Solves every perturbed PSD of p with fn; ok[k] says which gave an answer. 0, or
 * LJGAP_ENOMEM (j->oom) or the status that stopped all of them (with a warning). */
static int solve_all(job *j, const pert *p, solve_fn fn, void *ctx, int *ok)
{
    const ljgap__limits *lim = ljgap__handler_limits();
    long nt = lim->sweep_threads > 0 ? lim->sweep_threads : sysconf(_SC_NPROCESSORS_ONLN);
    pthread_t th[IE_THREADS_MAX];
    size_t started = 0, good = 0;
    solve_work *sw = calloc(1, sizeof *sw);
    int worst = LJGAP_OK;
    if (!sw || pthread_mutex_init(&sw->lock, NULL)) {
        free(sw);
        j->oom = 1;
        return LJGAP_ENOMEM;
    }
    sw->j = j, sw->p = p, sw->fn = fn, sw->ctx = ctx;
    if (nt < 1) nt = 1;
    if (nt > IE_THREADS_MAX) nt = IE_THREADS_MAX;
    if ((size_t)nt > p->K) nt = (long)p->K;
    while ((long)started + 1 < nt && pthread_create(&th[started], NULL, solve_worker, sw) == 0)
        started++;
    solve_worker(sw);
    for (size_t t = 0; t < started; t++)
        pthread_join(th[t], NULL);
    pthread_mutex_destroy(&sw->lock);
    for (size_t k = 0; k < p->K; k++) {
        ok[k] = sw->st[k] == LJGAP_OK;
        good += (size_t)ok[k];
        if (sw->st[k] == LJGAP_ENOMEM) worst = LJGAP_ENOMEM;
        if (sw->st[k] && !worst) worst = sw->st[k];
    }
    if (worst == LJGAP_ENOMEM) {
        j->oom = 1;
    } else if (good < p->K) {
        char why[LJGAP_WARN_LEN] = "";
        for (size_t k = 0; k < p->K && !why[0]; k++)
            if (sw->w[k].n) snprintf(why, sizeof why, ": %s", sw->w[k].msg[0]);
        ljgap_warn(&j->rq.warn,
                   "input_error: %zu of %zu perturbed PSDs gave no answer (%s)%s; input_error is "
                   "%s",
                   p->K - good, p->K, ljgap_strerror(worst), why,
                   p->linear || good < 3 ? "null" : "from the others");
    }
    free(sw);
    return worst == LJGAP_ENOMEM ? worst : LJGAP_OK;
}

/* ---- what each answer needs of a perturbed PSD ---- */

typedef struct {
    const double *x; /* traction points (may be none) */
    size_t nx;
    ljgap_est *sigma; /* K × nx */
    ljgap_summary sum[LJGAP_UNCERT_KMAX];
} curve_ctx;

static int solve_curve(void *ctx, size_t k, const ljgap_psd *psd, const ljgap_opts *o,
                       ljgap_warnings *w)
{
    curve_ctx *c = ctx;
    return ljgap_traction(psd, o, c->x, c->nx, c->nx ? c->sigma + k * c->nx : NULL, &c->sum[k], w);
}

typedef struct {
    const ljgap__request *rq;
    double *sigma; /* K × nx: each PDF's mean traction (the PDFs themselves are let go at once:
                    * a perturbed solve holds no more memory than the nominal one) */
} pdf_ctx;

static int solve_pdf(void *ctx, size_t k, const ljgap_psd *psd, const ljgap_opts *o,
                     ljgap_warnings *w)
{
    pdf_ctx *c = ctx;
    const ljgap__request *rq = c->rq;
    ljgap_pdf *p = calloc(rq->nx, sizeof *p);
    int st = p ? ljgap_pdf_compute(psd, o, rq->g_ave, rq->x, rq->nx, rq->has_grid ? rq->grid : NULL,
                                   p, w)
               : LJGAP_ENOMEM;
    for (size_t i = 0; !st && i < rq->nx; i++)
        c->sigma[k * rq->nx + i] = p[i].sigma.value;
    if (p) ljgap_pdf_release(p, rq->nx);
    free(p);
    return st;
}

/* ---- writing ---- */

/* A spread v as obj.key (array element when key is NULL); null when it could not be formed (too
 * few perturbed PSDs answered: a warning says so; never NaN through put_num). */
static void put_sd(job *j, cJSON *obj, const char *key, double v, const char *label, long idx)
{
    if (isfinite(v)) {
        ljgap__ans_num(j, obj, key, v, label, idx);
        return;
    }
    ljgap__ans_put(j, obj, key, cJSON_CreateNull());
    ljgap_warn(&j->rq.warn, "input_error: a spread that too few perturbed PSDs answered is null");
}

/* n spreads as the array obj.key. */
static void put_sds(job *j, cJSON *obj, const char *key, const double *v, size_t n,
                    const char *label)
{
    cJSON *a = ljgap__ans_put(j, obj, key, cJSON_CreateArray());
    for (size_t i = 0; a && i < n; i++)
        put_sd(j, a, NULL, v[i], label, (long)i);
}

/* meta.input_error: how (once an answer). */
static void put_meta(job *j, const pert *p, const ljgap__psd_spec *s)
{
    cJSON *m, *a;
    if (j->ie_meta || !(m = j->ie_meta = cJSON_CreateObject())) {
        if (!j->ie_meta) j->oom = 1;
        return;
    }
    if (p->linear) {
        ljgap__ans_put(j, m, "method", cJSON_CreateString("linear"));
        a = ljgap__ans_put(j, m, "parameters", cJSON_CreateArray());
        for (size_t q = 0; a && q < p->npar; q++)
            ljgap__ans_put(j, a, NULL, cJSON_CreateString(p->par[q]));
        ljgap__ans_put(j, m, "samples", cJSON_CreateNumber((double)p->K));
        ljgap__ans_put(j, m, "relative_error", cJSON_CreateNull());
        ljgap__ans_put(j, m, "detail",
                      cJSON_CreateString("central differences at each parameter ± 1 σ "
                                         "(parameters independent); exact for an answer linear "
                                         "in them"));
    } else {
        char d[300];
        ljgap__ans_put(j, m, "method", cJSON_CreateString("sampling"));
        ljgap__ans_put(j, m, "samples", cJSON_CreateNumber((double)p->K));
        ljgap__ans_put(j, m, "seed", cJSON_CreateNumber((double)IE_SEED));
        ljgap__ans_num(j, m, "relative_error", ljgap_uncert_sd_relerr(p->K),
                      "meta.input_error.relative_error", -1);
        ljgap__ans_put(j, m, "knots",
                      cJSON_CreateString(s->P_corr ? "correlated with their neighbours (P_corr)"
                                                   : "independent (no P_corr)"));
        ljgap__ans_num(j, m, "corr_scale", p->info.corr_scale, "meta.input_error.corr_scale", -1);
        snprintf(d, sizeof d,
                 "the standard deviation over %zu PSDs whose knots' ln P are drawn from "
                 "N(ln P, Σ), Σ of P_err%s, and the tail exponent from its exponent_err",
                 p->K, s->P_corr ? " and P_corr" : "");
        ljgap__ans_put(j, m, "detail", cJSON_CreateString(d));
    }
    ljgap__ans_num(j, m, "solves_tol", fmax(j->rq.opts.tol, IE_TOL), "meta.input_error.solves_tol",
                  -1);
}

/* The summary's four spreads, from the K summaries; one warning naming those within 3 times
 * the perturbed solves' own error (there the spread is their noise: an upper bound). */
static void summary_sd(job *j, const pert *p, const ljgap_summary *sum, const int *ok,
                       ljgap_summary *out)
{
    static const char *const names[] = {"g_eq", "sigma_max", "g_at_max", "dgamma_eff"};
    double x[LJGAP_UNCERT_KMAX];
    ljgap_est *const fields[] = {&out->g_eq, &out->sigma_max, &out->g_at_max, &out->dgamma_eff};
    char low[80] = "";
    size_t used = 0;
    for (size_t f = 0; f < 4; f++) {
        size_t off = (size_t)((char *)fields[f] - (char *)out);
        double solver = 0;
        for (size_t k = 0; k < p->K; k++) {
            const ljgap_est *e = (const ljgap_est *)((const char *)&sum[k] + off);
            x[k] = e->value;
            if (ok[k] && e->err > solver) solver = e->err;
        }
        fields[f]->err = pert_sd(p, x, ok);
        if (fields[f]->err < 3 * solver && used < sizeof low)
            used +=
                (size_t)snprintf(low + used, sizeof low - used, "%s%s", used ? ", " : "", names[f]);
    }
    if (used)
        ljgap_warn(&j->rq.warn,
                   "input_error of %s is within 3 times the perturbed solves' own error (tol %g): "
                   "the measurement's uncertainty is below what they resolve, and input_error "
                   "an upper bound",
                   low, fmax(j->rq.opts.tol, IE_TOL));
}

/* obj.key = {g_eq, sigma_max, g_at_max, dgamma_eff} from the errs of sd. */
static cJSON *put_summary_sd(job *j, cJSON *obj, const char *key, const ljgap_summary *sd,
                             const char *label)
{
    cJSON *o = ljgap__ans_put(j, obj, key, cJSON_CreateObject());
    const struct {
        const char *name;
        double v;
    } f[] = {{"g_eq", sd->g_eq.err},
             {"sigma_max", sd->sigma_max.err},
             {"g_at_max", sd->g_at_max.err},
             {"dgamma_eff", sd->dgamma_eff.err}};
    char l[80];
    for (size_t i = 0; o && i < 4; i++) {
        snprintf(l, sizeof l, "%s.%s", label, f[i].name);
        put_sd(j, o, f[i].name, f[i].v, l, -1);
    }
    return o;
}

/* The same in SI (m, Pa, J/m²). */
static cJSON *put_summary_sd_si(job *j, cJSON *obj, const char *key, const ljgap_summary *sd,
                                const char *label)
{
    ljgap_si_summary si;
    cJSON *o = ljgap__ans_put(j, obj, key, cJSON_CreateObject());
    const struct {
        const char *name;
        const ljgap_est *e;
    } f[] = {{"g_eq_m", &si.g_eq_m},
             {"sigma_max_Pa", &si.sigma_max_Pa},
             {"g_at_max_m", &si.g_at_max_m},
             {"dgamma_eff_J_m2", &si.dgamma_eff_J_m2}};
    char l[80];
    ljgap_si_summary_of(&j->rq.mat, sd, &si);
    for (size_t i = 0; o && i < 4; i++) {
        snprintf(l, sizeof l, "%s.%s", label, f[i].name);
        put_sd(j, o, f[i].name, f[i].e->err, l, -1);
    }
    return o;
}

static cJSON *si_of(job *j)
{
    return j->rq.has_material ? cJSON_GetObjectItemCaseSensitive(j->ans, "si") : NULL;
}

/* "extrapolated" of a table PSD: the share of m0 beyond its last knot and of Δγeff (one solve
 * of the table cut there). */
static void put_extrapolated(job *j, const ljgap__psd_spec *s, const ljgap_summary *sum)
{
    ljgap_psd base, cut;
    ljgap_summary t;
    ljgap_opts o = j->rq.opts;
    double mf, df = 0;
    cJSON *e;
    int st;
    if (!j->rq.input_error || s->kind != LJGAP_PSD_TABLE) return;
    if ((st = ljgap__psd_from_spec(&base, s))) {
        if (st == LJGAP_ENOMEM) j->oom = 1;
        return;
    }
    mf = ljgap_uncert_beyond(&base, base.k[base.n - 1]);
    if (mf > 0) {
        if (o.tol < CUT_TOL) o.tol = CUT_TOL; /* a fraction, wanted to 1e-3 of dgamma_eff */
        o.max_seconds = j->deadline - ljgap__clock_now();
        o.cancel = j->cancel;
        st = o.max_seconds > 0 ? ljgap_psd_truncate(&cut, &base, base.k[base.n - 1]) : LJGAP_ECAP;
        if (!st) {
            ljgap_warnings w = {0};
            st = ljgap_traction(&cut, &o, NULL, 0, NULL, &t, &w);
            ljgap_psd_free(&cut);
        }
        if (st == LJGAP_ENOMEM) j->oom = 1;
        df = st ? NAN : fabs(sum->dgamma_eff.value - t.dgamma_eff.value) / sum->dgamma_eff.value;
        if (st && st != LJGAP_ENOMEM)
            ljgap_warn(&j->rq.warn,
                       "extrapolated: the table cut at its last knot gave no answer "
                       "(%s); dgamma_eff_fraction is null",
                       ljgap_strerror(st));
    }
    e = ljgap__ans_put(j, j->ans, "extrapolated", cJSON_CreateObject());
    ljgap__ans_num(j, e, "k_last", base.k[base.n - 1], "extrapolated.k_last", -1);
    ljgap__ans_num(j, e, "m0_fraction", mf, "extrapolated.m0_fraction", -1);
    if (isfinite(df)) /* else null: the warning above says why */
        ljgap__ans_num(j, e, "dgamma_eff_fraction", df, "extrapolated.dgamma_eff_fraction", -1);
    else
        ljgap__ans_put(j, e, "dgamma_eff_fraction", cJSON_CreateNull());
    if (mf > EXTRAP_WARN || df > EXTRAP_WARN)
        ljgap_warn(&j->rq.warn,
                   "%.0f %% of m0 and %.0f %% of dgamma_eff come from beyond the table's last "
                   "point (k = %g), from its tail: an assumption, not a measurement",
                   100 * mf, 100 * df, base.k[base.n - 1]);
    ljgap_psd_free(&base);
}

/* The K summaries (and curves at x) of s's perturbed PSDs; 1 when input_error is to be
 * written (p->K > 0), with sd's errs the summary's spreads. */
static int curve_spread(job *j, const ljgap__psd_spec *s, pert *p, curve_ctx *c, int *ok,
                        ljgap_summary *sd)
{
    if (pert_make(j, s, p)) {
        j->oom = 1;
        return 0;
    }
    if (!p->K) return 0;
    put_meta(j, p, s);
    if (c->nx && !(c->sigma = malloc(p->K * c->nx * sizeof *c->sigma))) {
        j->oom = 1;
        pert_free(p);
        return 0;
    }
    if (solve_all(j, p, solve_curve, c, ok)) {
        free(c->sigma);
        c->sigma = NULL;
        pert_free(p);
        return 0;
    }
    memset(sd, 0, sizeof *sd);
    summary_sd(j, p, c->sum, ok, sd);
    return 1;
}

void ljgap__ie_adhesion(job *j, const ljgap_summary *sum)
{
    pert p;
    curve_ctx c = {0};
    int ok[LJGAP_UNCERT_KMAX];
    ljgap_summary sd;
    cJSON *si = si_of(j);
    if (curve_spread(j, &j->rq.psd, &p, &c, ok, &sd)) {
        put_summary_sd(j, j->ans, "input_error", &sd, "input_error");
        if (si) put_summary_sd_si(j, si, "input_error", &sd, "si.input_error");
        pert_free(&p);
    }
    put_extrapolated(j, &j->rq.psd, sum);
}

void ljgap__ie_traction(job *j, const ljgap_summary *sum)
{
    const ljgap__request *rq = &j->rq;
    pert p;
    curve_ctx c = {.x = rq->x, .nx = rq->nx};
    int ok[LJGAP_UNCERT_KMAX];
    ljgap_summary sd;
    cJSON *si = si_of(j), *ie, *sie;
    double *pt = NULL, x[LJGAP_UNCERT_KMAX];
    if (curve_spread(j, &rq->psd, &p, &c, ok, &sd)) {
        if (!(pt = malloc((rq->nx ? rq->nx : 1) * 2 * sizeof *pt))) {
            j->oom = 1;
        } else {
            for (size_t i = 0; i < rq->nx; i++) {
                for (size_t k = 0; k < p.K; k++)
                    x[k] = c.sigma[k * rq->nx + i].value;
                pt[i] = pert_sd(&p, x, ok);
                pt[rq->nx + i] = pt[i] * (rq->has_material ? ljgap_units_sigma0(&rq->mat) : 1);
            }
            ie = ljgap__ans_put(j, j->ans, "input_error", cJSON_CreateObject());
            put_sds(j, ie, "sigma", pt, rq->nx, "input_error.sigma");
            put_summary_sd(j, ie, "summary", &sd, "input_error.summary");
            if (si && (sie = ljgap__ans_put(j, si, "input_error", cJSON_CreateObject()))) {
                put_sds(j, sie, "sigma_Pa", pt + rq->nx, rq->nx, "si.input_error.sigma_Pa");
                put_summary_sd_si(j, sie, "summary", &sd, "si.input_error.summary");
            }
        }
        free(pt);
        free(c.sigma);
        pert_free(&p);
    }
    put_extrapolated(j, &rq->psd, sum);
}

void ljgap__ie_pdf(job *j)
{
    const ljgap__request *rq = &j->rq;
    pert p;
    pdf_ctx c = {.rq = rq};
    int ok[LJGAP_UNCERT_KMAX];
    double x[LJGAP_UNCERT_KMAX];
    cJSON *si = si_of(j), *arr, *sarr = NULL;
    if (pert_make(j, &rq->psd, &p)) {
        j->oom = 1;
        return;
    }
    if (!p.K) return;
    put_meta(j, &p, &rq->psd);
    if (!(c.sigma = calloc(p.K * rq->nx, sizeof *c.sigma))) {
        j->oom = 1;
        pert_free(&p);
        return;
    }
    if (!solve_all(j, &p, solve_pdf, &c, ok)) {
        arr = ljgap__ans_put(j, ljgap__ans_put(j, j->ans, "input_error", cJSON_CreateObject()),
                            "pdfs", cJSON_CreateArray());
        if (si)
            sarr = ljgap__ans_put(j, ljgap__ans_put(j, si, "input_error", cJSON_CreateObject()),
                                 "pdfs", cJSON_CreateArray());
        for (size_t i = 0; arr && i < rq->nx; i++) {
            double sd;
            for (size_t k = 0; k < p.K; k++)
                x[k] = c.sigma[k * rq->nx + i];
            sd = pert_sd(&p, x, ok);
            put_sd(j, ljgap__ans_put(j, arr, NULL, cJSON_CreateObject()), "sigma", sd,
                   "input_error.pdfs.sigma", (long)i);
            if (sarr)
                put_sd(j, ljgap__ans_put(j, sarr, NULL, cJSON_CreateObject()), "sigma_Pa",
                       sd * ljgap_units_sigma0(&rq->mat), "si.input_error.pdfs.sigma_Pa", (long)i);
        }
    }
    free(c.sigma);
    pert_free(&p);
}

void ljgap__ie_contact(job *j, const ljgap_summary *sum)
{
    const ljgap__request *rq = &j->rq;
    pert p;
    curve_ctx c = {0};
    int ok[LJGAP_UNCERT_KMAX], okc[LJGAP_UNCERT_KMAX];
    ljgap_summary sd;
    ljgap_contact ct[LJGAP_UNCERT_KMAX];
    cJSON *si = si_of(j), *ie, *po;
    if (curve_spread(j, &rq->psd, &p, &c, ok, &sd)) {
        static const char *const names[] = {"jkr_smooth", "jkr", "dmt", "maugis_dugdale"};
        double x[6][LJGAP_UNCERT_KMAX];
        for (size_t k = 0; k < p.K; k++) {
            okc[k] = ok[k] && ljgap_contact_compute(&rq->mat, rq->R, &c.sum[k], &ct[k]) == 0;
            if (!okc[k]) continue;
            x[0][k] = ct[k].jkr_smooth.value, x[1][k] = ct[k].jkr.value;
            x[2][k] = ct[k].dmt.value, x[3][k] = ct[k].md.value;
            x[4][k] = ct[k].tabor_eff.value, x[5][k] = ct[k].lambda.value;
        }
        ie = put_summary_sd(j, j->ans, "input_error", &sd, "input_error");
        po = ljgap__ans_put(j, ie, "pull_off_N", cJSON_CreateObject());
        for (size_t f = 0; po && f < 4; f++)
            put_sd(j, po, names[f], pert_sd(&p, x[f], okc), "input_error.pull_off_N", (long)f);
        put_sd(j, ljgap__ans_put(j, ie, "tabor", cJSON_CreateObject()), "effective",
               pert_sd(&p, x[4], okc), "input_error.tabor.effective", -1);
        put_sd(j, ie, "maugis_lambda", pert_sd(&p, x[5], okc), "input_error.maugis_lambda", -1);
        if (si) put_summary_sd_si(j, si, "input_error", &sd, "si.input_error");
        pert_free(&p);
    }
    put_extrapolated(j, &rq->psd, sum);
}

void ljgap__ie_sweep(job *j, const ljgap_summary *sum, const int *st)
{
    const ljgap__request *rq = &j->rq;
    cJSON *results = cJSON_GetObjectItemCaseSensitive(j->ans, "results"), *si = si_of(j);
    cJSON *sir = si ? cJSON_GetObjectItemCaseSensitive(si, "results") : NULL;
    for (size_t i = 0; results && i < rq->nx && !j->oom; i++) {
        ljgap__psd_spec s;
        pert p;
        curve_ctx c = {0};
        int ok[LJGAP_UNCERT_KMAX];
        ljgap_summary sd;
        if (st[i]) continue;
        ljgap__request_sweep_spec(rq, i, &s);
        /* the varied field's value is exact: its error does not apply */
        if (rq->vary == LJGAP_VARY_M0 || rq->vary == LJGAP_VARY_C) s.level_err = 0;
        if (rq->vary == LJGAP_VARY_D) s.D_err = 0;
        if (!curve_spread(j, &s, &p, &c, ok, &sd)) continue;
        put_summary_sd(j, cJSON_GetArrayItem(results, (int)i), "input_error", &sd,
                       "results.input_error");
        if (sir && cJSON_IsObject(cJSON_GetArrayItem(sir, (int)i)))
            put_summary_sd_si(j, cJSON_GetArrayItem(sir, (int)i), "input_error", &sd,
                              "si.results.input_error");
        pert_free(&p);
    }
    (void)sum;
}
