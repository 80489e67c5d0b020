/* handler.c -- the request handler: endpoint name + JSON body + Accept -> status + body.
 *
 * The CLI, the HTTP daemon and the fuzzer are thin shells over ljgap__handle_call. It parses the
 * body with cJSON, validates it (request.c: every bad field reported with a JSON pointer),
 * builds the PSD, calls the core (include/ljgap.h) and serialises the answer exactly as
 * docs/api.md fixes it: as JSON, or for traction, pdf and sweep as CSV when the Accept header
 * prefers it (accept.c decides, csv.c writes the JSON answer out as a table). It is a pure
 * function of its arguments and of the limits set at start-up, so it is thread-safe: nothing
 * else here is mutable and shared.
 *
 * Two rules hold for every answer:
 *   - no NaN or Inf goes out: put_num writes null instead and says why in meta.warnings;
 *   - every 2xx answer has meta {method, elapsed_ms (measured here), version, warnings,
 *     cached}, and the core's warnings are copied into meta.warnings.
 *
 * With a "material" block every answer adds "si": the scales χ (m) and σ0 (Pa) and the
 * returned quantities in SI (gaps in m, tractions in Pa, Δγeff in J/m², core/units.c), with
 * their errors in an "error" object placed as the dimensionless answer places its own: si.error
 * beside si's values, a sweep's in each of si.results.
 * "contact" (theory.md §6, core/contact.c) adds the sphere's pull-off forces. A sweep computes
 * its values on up to limits.sweep_threads threads; each value is independent, so the answer
 * is the sequential one.
 *
 * Endpoints whose runner lives in its own file reach the builders here through answer.h: psd
 * (psd.c), psd/combine (combine.c); simulations, which are not an endpoint of ljgap__handle (a run
 * takes minutes), are parsed, run and answered in simreq.c.
 *
 * Problem types: the "type" member of every application/problem+json answer is /problems/SLUG,
 * a page the daemon serves; problems.c holds the status, title and text of each (openapi.json
 * lists the same set; a unit test keeps them in step). The handler answers these:
 *   malformed-json  400  the body is not one valid JSON value
 *   not-found       404  no such endpoint
 *   not-acceptable  406  the Accept header allows no form this answer has
 *   validation      422  valid JSON, bad values: errors[] has one {pointer, detail} per bad field
 *   outside-model   422  the core found the input outside the model's domain (LJGAP_EINVAL),
 *                        pointer "/psd"
 *   cap-exceeded    422  the computation needs more than the server's caps (LJGAP_ECAP)
 *   no-answer       422  no finite answer could be formed (LJGAP_EFAIL)
 *   unavailable     503  the computation was cancelled (server shutting down, a simulation
 *                        cancelled; LJGAP_ECANCEL)
 *   out-of-memory   500  an allocation failed (LJGAP_ENOMEM)
 * Every problem has "type", "title", "status", "detail" and "errors" (possibly empty).
 */
#include "handler.h"
#include "clock.h" /* ljgap__clock_now */
#include "accept.h"
#include "answer.h"
#include "csv.h"
#include "input_error.h" /* the measurement's uncertainty: ljgap__ie_* */
#include "ljgap_sim.h"
#include "ljgap_topo.h"
#include "problems.h"
#include "request.h"
#include "textbuf.h"   /* ljgap__utf8_span */
#include "topo_text.h" /* the text upload of psd */
#include "validity/validity.h" /* the answers' "model" */

#include <math.h>
#include <pthread.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Sent when not even a problem can be allocated; never freed (see ljgap__reply_free). */
static char oom_body[] = "{\"type\":\"" LJGAP_PROBLEM_BASE "out-of-memory\","
                         "\"title\":\"Out of memory\",\"status\":500,"
                         "\"detail\":\"the server ran out of memory\",\"errors\":[]}";

static ljgap__limits limits = LJGAP_LIMITS_INIT; /* written only by ljgap__handler_set_limits */

void ljgap__handler_set_limits(const ljgap__limits *l)
{
    limits = *l;
}

/* ---- replies ---- */

void ljgap__ans_oom(ljgap__reply *out)
{
    out->status = 500;
    out->body = oom_body;
    out->len = strlen(oom_body);
    out->content_type = CT_PROBLEM;
}

/* Serialises doc into out; doc stays the caller's. */
void ljgap__ans_reply_json(ljgap__reply *out, int status, const char *ctype, const cJSON *doc)
{
    char *s = cJSON_PrintUnformatted(doc);
    if (!s) {
        ljgap__ans_oom(out);
        return;
    }
    out->status = status;
    out->body = s;
    out->len = strlen(s);
    out->content_type = ctype;
}

/* A problem answer of type /problems/slug (status and title from problems.c); takes errors
 * (an array, or NULL for an empty one). */
void ljgap__ans_problem(ljgap__reply *out, const char *slug, const char *detail, cJSON *errors)
{
    const ljgap__problem_doc *k = ljgap__problem_find(slug);
    cJSON *p = cJSON_CreateObject();
    char type[80];
    snprintf(type, sizeof type, LJGAP_PROBLEM_BASE "%s", slug);
    if (!errors) errors = cJSON_CreateArray();
    if (!k || !p || !errors || !cJSON_AddStringToObject(p, "type", type) ||
        !cJSON_AddStringToObject(p, "title", k->title) ||
        !cJSON_AddNumberToObject(p, "status", k->status) ||
        !cJSON_AddStringToObject(p, "detail", detail) ||
        !cJSON_AddItemToObject(p, "errors", errors)) {
        cJSON_Delete(errors);
        ljgap__ans_oom(out);
        goto end;
    }
    ljgap__ans_reply_json(out, k->status, CT_PROBLEM, p);
end:
    cJSON_Delete(p);
}

void ljgap__reply_problem(ljgap__reply *out, const char *slug, const char *detail)
{
    memset(out, 0, sizeof *out);
    ljgap__ans_problem(out, slug, detail, NULL);
}

void ljgap__reply_free(ljgap__reply *r)
{
    if (!r) return;
    if (r->body != oom_body) free(r->body);
    r->body = NULL;
    r->len = 0;
}

/* ---- building answers ---- */

/* Adds item to parent (object member key, or array element when key is NULL). */
static cJSON *put(job *j, cJSON *parent, const char *key, cJSON *item)
{
    int ok = item && parent &&
             (key ? cJSON_AddItemToObject(parent, key, item) : cJSON_AddItemToArray(parent, item));
    if (!ok) {
        cJSON_Delete(item);
        j->oom = 1;
        return NULL;
    }
    return item;
}

/* Adds the number v, or null with a warning naming label (and [idx] when idx >= 0) when v is
 * not finite: no NaN or Inf ever goes out. */
static void put_num(job *j, cJSON *parent, const char *key, double v, const char *label, long idx)
{
    if (isfinite(v)) {
        put(j, parent, key, cJSON_CreateNumber(v));
        return;
    }
    put(j, parent, key, cJSON_CreateNull());
    if (idx >= 0)
        ljgap_warn(&j->rq.warn, "%s[%ld] is not a finite number (%g) and is given as null", label,
                   idx, v);
    else
        ljgap_warn(&j->rq.warn, "%s is not a finite number (%g) and is given as null", label, v);
}

/* An array of n numbers, each through put_num. */
static cJSON *put_nums(job *j, cJSON *parent, const char *key, const double *x, size_t n,
                       size_t stride, const char *label)
{
    cJSON *a = put(j, parent, key, cJSON_CreateArray());
    for (size_t i = 0; a && i < n; i++)
        put_num(j, a, NULL, *(const double *)((const char *)x + i * stride), label, (long)i);
    return a;
}

/* The estimated fields of ljgap_summary and of its SI form ljgap_si_summary, in contract
 * order: their names and where each is. */
static const struct {
    const char *name, *si_name;
    size_t off, si_off;
} est_fields[] = {
    {"g_eq", "g_eq_m", offsetof(ljgap_summary, g_eq), offsetof(ljgap_si_summary, g_eq_m)},
    {"sigma_max", "sigma_max_Pa", offsetof(ljgap_summary, sigma_max),
     offsetof(ljgap_si_summary, sigma_max_Pa)},
    {"g_at_max", "g_at_max_m", offsetof(ljgap_summary, g_at_max),
     offsetof(ljgap_si_summary, g_at_max_m)},
    {"dgamma_eff", "dgamma_eff_J_m2", offsetof(ljgap_summary, dgamma_eff),
     offsetof(ljgap_si_summary, dgamma_eff_J_m2)},
};
#define N_EST (sizeof est_fields / sizeof est_fields[0])

static const ljgap_est *est_of(const ljgap_summary *s, size_t i)
{
    return (const ljgap_est *)((const char *)s + est_fields[i].off);
}

static const ljgap_est *si_est_of(const ljgap_si_summary *s, size_t i)
{
    return (const ljgap_est *)((const char *)s + est_fields[i].si_off);
}

/* The adhesion fields of s into obj and their errors into a new object obj.error_key (all
 * null when s is NULL: the reason is already a warning). */
void ljgap__ans_summary(job *j, cJSON *obj, cJSON *err_parent, const char *err_key,
                       const ljgap_summary *s)
{
    cJSON *err = cJSON_CreateObject();
    for (size_t i = 0; i < N_EST; i++) {
        const char *name = est_fields[i].name;
        if (s) {
            put_num(j, obj, name, est_of(s, i)->value, name, -1);
            put_num(j, err, name, est_of(s, i)->err, name, -1);
        } else {
            put(j, obj, name, cJSON_CreateNull());
            put(j, err, name, cJSON_CreateNull());
        }
    }
    if (s)
        put_num(j, obj, "m0", s->m0, "m0", -1);
    else
        put(j, obj, "m0", cJSON_CreateNull());
    put_num(j, obj, "k0", ljgap_k0(), "k0", -1);
    put(j, err_parent, err_key, err);
}

/* The adhesion fields of s in SI (ljgap_si_summary_of: m, Pa, J/m², m²) into obj and their
 * errors into a new object err_parent.err_key, as put_summary does. */
static void put_si_summary(job *j, cJSON *obj, cJSON *err_parent, const char *err_key,
                           const ljgap_summary *s)
{
    ljgap_si_summary si;
    cJSON *err = cJSON_CreateObject();
    char label[40];
    ljgap_si_summary_of(&j->rq.mat, s, &si);
    for (size_t i = 0; i < N_EST; i++) {
        const char *name = est_fields[i].si_name;
        const ljgap_est *e = si_est_of(&si, i);
        snprintf(label, sizeof label, "si.%s", name);
        put_num(j, obj, name, e->value, label, -1);
        snprintf(label, sizeof label, "si.error.%s", name);
        put_num(j, err, name, e->err, label, -1);
    }
    put_num(j, obj, "m0_m2", si.m0_m2, "si.m0_m2", -1);
    put(j, err_parent, err_key, err);
}

/* The "si" object of an answer (NULL without a material): the scales (ljgap_si_scales_of),
 * and the adhesion fields of s in SI with their errors in si.error when s is not NULL. */
static cJSON *put_si(job *j, cJSON *parent, const ljgap_summary *s)
{
    ljgap_si_scales sc;
    cJSON *si;
    if (!j->rq.has_material) return NULL;
    ljgap_si_scales_of(&j->rq.mat, &sc);
    si = put(j, parent, "si", cJSON_CreateObject());
    put_num(j, si, "chi_m", sc.chi_m, "si.chi_m", -1);
    put_num(j, si, "sigma0_Pa", sc.sigma0_Pa, "si.sigma0_Pa", -1);
    put_num(j, si, "E_star_Pa", sc.E_star_Pa, "si.E_star_Pa", -1);
    if (s) put_si_summary(j, si, si, "error", s);
    return si;
}

void ljgap__ans_meta(job *j, double t0)
{
    cJSON *meta = put(j, j->ans, "meta", cJSON_CreateObject());
    cJSON *w;
    put(j, meta, "method", cJSON_CreateString(j->rq.method));
    put(j, meta, "elapsed_ms", cJSON_CreateNumber((ljgap__clock_now() - t0) * 1e3));
    put(j, meta, "version", cJSON_CreateString(LJGAP_VERSION));
    w = put(j, meta, "warnings", cJSON_CreateArray());
    for (int i = 0; w && i < j->rq.warn.n; i++)
        put(j, w, NULL, cJSON_CreateString(j->rq.warn.msg[i]));
    if (j->ie_meta) put(j, meta, "input_error", j->ie_meta), j->ie_meta = NULL; /* taken */
    put(j, meta, "cached", cJSON_CreateFalse()); /* last: LJGAP_REPLY_UNCACHED_TAIL (reply.h) */
}

/* Core options for one call: the request's, capped by what is left of the time budget. */
static int opts_now(job *j, ljgap_opts *o)
{
    *o = j->rq.opts;
    o->max_seconds = j->deadline - ljgap__clock_now();
    o->cancel = j->cancel;
    if (o->max_seconds > 0) return LJGAP_OK;
    snprintf(j->fail, sizeof j->fail, " (the request's time budget ran out before this step)");
    return LJGAP_ECAP;
}

/* ---- endpoints ---- */

/* Core options and the PSD for one core call (free psd after, on success). */
static int prepare(job *j, const ljgap__psd_spec *spec, ljgap_psd *psd, ljgap_opts *o,
                   ljgap_warnings *w)
{
    int st = opts_now(j, o);
    if (st) return st;
    st = ljgap__psd_from_spec(psd, spec);
    if (st == LJGAP_EINVAL)
        ljgap_warn(w, "the PSD could not be formed: its variance is not a finite positive "
                      "number");
    return st;
}

/* Summary of the PSD in spec: one ljgap_traction call with no points. */
static int summarise(job *j, const ljgap__psd_spec *spec, ljgap_summary *sum, ljgap_warnings *w)
{
    ljgap_psd psd;
    ljgap_opts o;
    int st = prepare(j, spec, &psd, &o, w);
    if (st) return st;
    st = ljgap_traction(&psd, &o, NULL, 0, NULL, sum, w);
    ljgap_psd_free(&psd);
    return st;
}

static int run_adhesion(job *j)
{
    ljgap_summary sum;
    int st = summarise(j, &j->rq.psd, &sum, &j->rq.warn);
    if (st) return st;
    ljgap__ans_summary(j, j->ans, j->ans, "error", &sum);
    put_si(j, j->ans, &sum);
    ljgap__ie_adhesion(j, &sum);
    ljgap__ans_model(j, &j->rq.psd);
    return LJGAP_OK;
}

static int run_traction(job *j)
{
    const ljgap__request *rq = &j->rq;
    ljgap_summary sum;
    ljgap_est *sigma = malloc(rq->nx * sizeof *sigma);
    ljgap_psd psd;
    ljgap_opts o;
    cJSON *err, *sum_obj, *si;
    int st = sigma ? prepare(j, &rq->psd, &psd, &o, &j->rq.warn) : LJGAP_ENOMEM;
    if (st) goto end;
    st = ljgap_traction(&psd, &o, rq->x, rq->nx, sigma, &sum, &j->rq.warn);
    ljgap_psd_free(&psd);
    if (st) goto end;
    put_nums(j, j->ans, "g_ave", rq->x, rq->nx, sizeof *rq->x, "g_ave");
    put_nums(j, j->ans, "sigma", &sigma[0].value, rq->nx, sizeof *sigma, "sigma");
    sum_obj = put(j, j->ans, "summary", cJSON_CreateObject());
    err = put(j, j->ans, "error", cJSON_CreateObject());
    put_nums(j, err, "sigma", &sigma[0].err, rq->nx, sizeof *sigma, "error.sigma");
    ljgap__ans_summary(j, sum_obj, err, "summary", &sum);
    if ((si = put_si(j, j->ans, NULL))) {
        ljgap_si_point *pt = malloc(rq->nx * sizeof *pt);
        if (!pt) {
            st = LJGAP_ENOMEM;
            goto end;
        }
        ljgap_si_points_of(&rq->mat, rq->x, sigma, rq->nx, pt);
        put_nums(j, si, "g_ave_m", &pt[0].g_ave_m, rq->nx, sizeof *pt, "si.g_ave_m");
        put_nums(j, si, "sigma_Pa", &pt[0].sigma_Pa.value, rq->nx, sizeof *pt, "si.sigma_Pa");
        sum_obj = put(j, si, "summary", cJSON_CreateObject());
        err = put(j, si, "error", cJSON_CreateObject());
        put_nums(j, err, "sigma_Pa", &pt[0].sigma_Pa.err, rq->nx, sizeof *pt, "si.error.sigma_Pa");
        put_si_summary(j, sum_obj, err, "summary", &sum);
        free(pt);
    }
    ljgap__ie_traction(j, &sum);
    ljgap__ans_model(j, &rq->psd);
end:
    free(sigma);
    return st;
}

static int run_pdf(job *j)
{
    const ljgap__request *rq = &j->rq;
    ljgap_pdf *p = calloc(rq->nx, sizeof *p);
    ljgap_psd psd;
    ljgap_opts o;
    cJSON *pdfs, *errs, *si, *sip = NULL, *sie = NULL;
    int st = p ? prepare(j, &rq->psd, &psd, &o, &j->rq.warn) : LJGAP_ENOMEM;
    if (st) goto end;
    st = ljgap_pdf_compute(&psd, &o, rq->g_ave, rq->x, rq->nx, rq->has_grid ? rq->grid : NULL, p,
                           &j->rq.warn);
    ljgap_psd_free(&psd);
    if (st) goto end;
    pdfs = put(j, j->ans, "pdfs", cJSON_CreateArray());
    errs = put(j, put(j, j->ans, "error", cJSON_CreateObject()), "pdfs", cJSON_CreateArray());
    if ((si = put_si(j, j->ans, NULL))) {
        sip = put(j, si, "pdfs", cJSON_CreateArray());
        sie = put(j, put(j, si, "error", cJSON_CreateObject()), "pdfs", cJSON_CreateArray());
    }
    for (size_t i = 0; sip && sie && i < rq->nx; i++) {
        cJSON *s = put(j, sip, NULL, cJSON_CreateObject());
        cJSON *e = put(j, sie, NULL, cJSON_CreateObject());
        ljgap_si_pdf sp = {0};
        sp.g_m = malloc((p[i].n ? p[i].n : 1) * 2 * sizeof *sp.g_m);
        if (!sp.g_m) {
            st = LJGAP_ENOMEM;
            goto end;
        }
        sp.phi_per_m = sp.g_m + p[i].n;
        ljgap_si_pdf_of(&rq->mat, &p[i], &sp);
        if (isinf(sp.k2_per_m))
            put(j, s, "k2_per_m", cJSON_CreateNull()); /* null = ∞ by contract */
        else
            put_num(j, s, "k2_per_m", sp.k2_per_m, "si.pdfs.k2_per_m", (long)i);
        put_nums(j, s, "g_m", sp.g_m, p[i].n, sizeof *sp.g_m, "si.pdfs.g_m");
        put_nums(j, s, "phi_per_m", sp.phi_per_m, p[i].n, sizeof *sp.phi_per_m,
                 "si.pdfs.phi_per_m");
        put_num(j, s, "sigma_Pa", sp.sigma_Pa.value, "si.pdfs.sigma_Pa", (long)i);
        put_num(j, e, "phi_l1", sp.phi_l1, "si.error.pdfs.phi_l1", (long)i);
        put_num(j, e, "sigma_Pa", sp.sigma_Pa.err, "si.error.pdfs.sigma_Pa", (long)i);
        free(sp.g_m);
    }
    for (size_t i = 0; pdfs && errs && i < rq->nx; i++) {
        cJSON *s = put(j, pdfs, NULL, cJSON_CreateObject());
        cJSON *e = put(j, errs, NULL, cJSON_CreateObject());
        if (isinf(p[i].k2))
            put(j, s, "k2", cJSON_CreateNull()); /* null = ∞ by contract */
        else
            put_num(j, s, "k2", p[i].k2, "pdfs.k2", (long)i);
        put_nums(j, s, "g", p[i].g, p[i].n, sizeof *p[i].g, "pdfs.g");
        put_nums(j, s, "phi", p[i].phi, p[i].n, sizeof *p[i].phi, "pdfs.phi");
        put_num(j, s, "mass", p[i].mass, "pdfs.mass", (long)i);
        put_num(j, s, "mean", p[i].mean, "pdfs.mean", (long)i);
        put_num(j, s, "sigma", p[i].sigma.value, "pdfs.sigma", (long)i);
        put_num(j, e, "phi_l1", p[i].phi_err, "error.pdfs.phi_l1", (long)i);
        put_num(j, e, "sigma", p[i].sigma.err, "error.pdfs.sigma", (long)i);
    }
    ljgap__ie_pdf(j);
    ljgap__ans_model(j, &rq->psd);
end:
    if (p) ljgap_pdf_release(p, rq->nx);
    free(p);
    return st;
}

/* One sweep: every value is computed independently (by any thread), its result stored at
 * its index, so the answer does not depend on the number of threads. */
typedef struct {
    job *j;             /* the request (read only while workers run) */
    ljgap_summary *sum; /* nx results */
    ljgap_warnings *w;  /* nx warning lists */
    int *st;            /* nx statuses (-1: not computed) */
    size_t next;        /* next index to take, under lock */
    int stop;           /* a hard failure was seen, under lock: take no more values */
    pthread_mutex_t lock;
} sweep_work;

static void *sweep_worker(void *arg)
{
    sweep_work *sw = arg;
    job local = *sw->j; /* summarise may write local.fail; the request itself is only read */
    const ljgap__request *rq = &sw->j->rq;
    for (;;) {
        ljgap__psd_spec spec;
        size_t i;
        pthread_mutex_lock(&sw->lock);
        i = sw->stop ? rq->nx : sw->next++;
        pthread_mutex_unlock(&sw->lock);
        if (i >= rq->nx) return NULL;
        ljgap__request_sweep_spec(rq, i, &spec);
        sw->st[i] = summarise(&local, &spec, &sw->sum[i], &sw->w[i]);
        if (sw->st[i] && sw->st[i] != LJGAP_EFAIL) {
            pthread_mutex_lock(&sw->lock);
            sw->stop = 1;
            pthread_mutex_unlock(&sw->lock);
        }
    }
}

/* Runs the sweep's values on up to limits.sweep_threads threads (this one included). */
static void sweep_compute(sweep_work *sw)
{
    long nt = limits.sweep_threads > 0 ? limits.sweep_threads : sysconf(_SC_NPROCESSORS_ONLN);
    pthread_t th[64];
    size_t started = 0;
    if (nt < 1) nt = 1;
    if (nt > 64) nt = 64;
    if ((size_t)nt > sw->j->rq.nx) nt = (long)sw->j->rq.nx;
    /* a thread that cannot be started leaves its share to the others */
    while ((long)started + 1 < nt && pthread_create(&th[started], NULL, sweep_worker, sw) == 0)
        started++;
    sweep_worker(sw);
    for (size_t t = 0; t < started; t++)
        pthread_join(th[t], NULL);
}

/* One value of a sweep failed without a finite answer: its fields are null, and a warning
 * says why; the sweep goes on. Any other failure ends the sweep (the first such value is
 * reported). */
static int run_sweep(job *j)
{
    ljgap__request *rq = &j->rq;
    sweep_work sw = {.j = j};
    cJSON *results, *si, *sir = NULL;
    size_t failed = 0;
    int st = LJGAP_OK;
    sw.sum = calloc(rq->nx, sizeof *sw.sum);
    sw.w = calloc(rq->nx, sizeof *sw.w);
    sw.st = malloc(rq->nx * sizeof *sw.st);
    if (!sw.sum || !sw.w || !sw.st || pthread_mutex_init(&sw.lock, NULL)) {
        st = LJGAP_ENOMEM;
        goto end;
    }
    for (size_t i = 0; i < rq->nx; i++)
        sw.st[i] = -1;
    sweep_compute(&sw);
    pthread_mutex_destroy(&sw.lock);
    for (size_t i = 0; i < rq->nx; i++) {
        for (int k = 0; k < sw.w[i].n; k++)
            ljgap_warn(&rq->warn, "values[%zu]: %s", i, sw.w[i].msg[k]);
        if (sw.st[i] > 0 && sw.st[i] != LJGAP_EFAIL) {
            snprintf(j->fail, sizeof j->fail, " (at values[%zu] = %g)", i, rq->x[i]);
            st = sw.st[i];
            goto end;
        }
    }
    put(j, j->ans, "vary", cJSON_CreateString(rq->vary_name));
    put_nums(j, j->ans, "values", rq->x, rq->nx, sizeof *rq->x, "values");
    results = put(j, j->ans, "results", cJSON_CreateArray());
    if ((si = put_si(j, j->ans, NULL))) sir = put(j, si, "results", cJSON_CreateArray());
    for (size_t i = 0; results && i < rq->nx; i++) {
        cJSON *r = put(j, results, NULL, cJSON_CreateObject());
        if (sw.st[i]) failed++;
        ljgap__ans_summary(j, r, r, "error", sw.st[i] ? NULL : &sw.sum[i]);
        if (sir && !sw.st[i]) {
            cJSON *sr = put(j, sir, NULL, cJSON_CreateObject());
            put_si_summary(j, sr, sr, "error", &sw.sum[i]);
        } else if (sir)
            put(j, sir, NULL, cJSON_CreateNull());
    }
    ljgap__ans_model_sweep(j);
    if (failed == rq->nx) {
        snprintf(j->fail, sizeof j->fail, " for any of the %zu values", rq->nx);
        st = LJGAP_EFAIL;
    }
    ljgap__ie_sweep(j, sw.sum, sw.st); /* the values computed; nothing when the sweep failed */
end:
    free(sw.sum);
    free(sw.w);
    free(sw.st);
    return st;
}

/* The hybrid JKR model (theory.md §6): the adhesion summary of the rough surface, then the
 * sphere's pull-off forces from core/contact.c. */
static int run_contact(job *j)
{
    ljgap_summary sum;
    ljgap_contact c;
    cJSON *po, *tab, *err, *epo;
    int st = summarise(j, &j->rq.psd, &sum, &j->rq.warn);
    if (st) return st;
    if ((st = ljgap_contact_compute(&j->rq.mat, j->rq.R, &sum, &c))) {
        snprintf(j->fail, sizeof j->fail,
                 " (the contact model needs a positive sigma_max and dgamma_eff)");
        return st == LJGAP_EINVAL ? LJGAP_EFAIL : st;
    }
    ljgap__ans_summary(j, j->ans, j->ans, "error", &sum);
    err = cJSON_GetObjectItemCaseSensitive(j->ans, "error");
    po = put(j, j->ans, "pull_off_N", cJSON_CreateObject());
    epo = put(j, err, "pull_off_N", cJSON_CreateObject());
    put_num(j, po, "jkr_smooth", c.jkr_smooth.value, "pull_off_N.jkr_smooth", -1);
    put_num(j, po, "jkr", c.jkr.value, "pull_off_N.jkr", -1);
    put_num(j, po, "dmt", c.dmt.value, "pull_off_N.dmt", -1);
    put_num(j, po, "maugis_dugdale", c.md.value, "pull_off_N.maugis_dugdale", -1);
    put_num(j, epo, "jkr_smooth", c.jkr_smooth.err, "error.pull_off_N.jkr_smooth", -1);
    put_num(j, epo, "jkr", c.jkr.err, "error.pull_off_N.jkr", -1);
    put_num(j, epo, "dmt", c.dmt.err, "error.pull_off_N.dmt", -1);
    put_num(j, epo, "maugis_dugdale", c.md.err, "error.pull_off_N.maugis_dugdale", -1);
    tab = put(j, j->ans, "tabor", cJSON_CreateObject());
    put_num(j, tab, "smooth", c.tabor_smooth, "tabor.smooth", -1);
    put_num(j, tab, "effective", c.tabor_eff.value, "tabor.effective", -1);
    put_num(j, put(j, err, "tabor", cJSON_CreateObject()), "effective", c.tabor_eff.err,
            "error.tabor.effective", -1);
    put_num(j, j->ans, "maugis_lambda", c.lambda.value, "maugis_lambda", -1);
    put_num(j, err, "maugis_lambda", c.lambda.err, "error.maugis_lambda", -1);
    put(j, j->ans, "regime", cJSON_CreateString(ljgap_regime_name(c.regime)));
    put_num(j, j->ans, "R", j->rq.R, "R", -1);
    put_si(j, j->ans, &sum);
    ljgap__ie_contact(j, &sum);
    ljgap__ans_model(j, &j->rq.psd);
    return LJGAP_OK;
}

/* ---- for psd.c and combine.c ---- */

void ljgap__ans_si(job *j)
{
    put_si(j, j->ans, NULL);
}

/* ---- the endpoints: a name to its runner (the URL routes are the daemon's, ljgapd/routes.c,
 * whose POST /v1/NAME rows hand NAME here) ---- */

typedef struct {
    const char *name;   /* the endpoint's name, POST /v1/NAME */
    ljgap__endpoint ep;  /* what request.c validates it as */
    int (*run)(job *j); /* builds the answer in j->ans */
} endpoint_row;

static const endpoint_row endpoints[] = {
    {"adhesion", LJGAP_EP_ADHESION, run_adhesion},
    {"traction", LJGAP_EP_TRACTION, run_traction},
    {"pdf", LJGAP_EP_PDF, run_pdf},
    {"sweep", LJGAP_EP_SWEEP, run_sweep},
    {"contact", LJGAP_EP_CONTACT, run_contact},
    {"psd", LJGAP_EP_PSD, ljgap__run_psd},
    {"psd/combine", LJGAP_EP_COMBINE, ljgap__run_combine},
};

static const endpoint_row *endpoint_find(const char *name)
{
    for (size_t i = 0; name && i < sizeof endpoints / sizeof endpoints[0]; i++)
        if (strcmp(name, endpoints[i].name) == 0) return &endpoints[i];
    return NULL;
}

int ljgap__handler_has(const char *endpoint)
{
    return endpoint_find(endpoint) != NULL;
}

/* The problem for a failed core status. */
void ljgap__ans_status(ljgap__reply *out, int st, const job *j)
{
    char detail[DETAIL_LEN], head[DETAIL_LEN + 200];
    cJSON *errors = NULL, *e = NULL;
    switch (st) {
    case LJGAP_EINVAL:
        ljgap__ans_join_warnings(detail, sizeof detail,
                                j->bad_head ? j->bad_head : "the PSD is outside the model's domain",
                                &j->rq.warn);
        errors = cJSON_CreateArray();
        e = cJSON_CreateObject();
        if (!errors || !e ||
            !cJSON_AddStringToObject(e, "pointer", j->bad_ptr ? j->bad_ptr : "/psd") ||
            !cJSON_AddStringToObject(e, "detail", detail) || !cJSON_AddItemToArray(errors, e)) {
            cJSON_Delete(e);
            cJSON_Delete(errors);
            ljgap__ans_oom(out);
            return;
        }
        ljgap__ans_problem(out, P_OUTSIDE, detail, errors);
        return;
    case LJGAP_ECAP:
        snprintf(head, sizeof head,
                 "the computation needs more than the server's caps allow "
                 "(max_seconds = %g s of wall time per request, max_work = %ld grid "
                 "point-steps); ask for a larger tol or fewer points%s",
                 limits.max_seconds, j->rq.opts.max_work, j->fail);
        ljgap__ans_join_warnings(detail, sizeof detail, head, &j->rq.warn);
        ljgap__ans_problem(out, P_CAP, detail, NULL);
        return;
    case LJGAP_EFAIL:
        snprintf(head, sizeof head, "no finite answer could be formed%s", j->fail);
        ljgap__ans_join_warnings(detail, sizeof detail, head, &j->rq.warn);
        ljgap__ans_problem(out, P_NO_ANSWER, detail, NULL);
        return;
    case LJGAP_ECANCEL:
        ljgap__ans_problem(out, P_UNAVAILABLE,
                          "the computation was cancelled (the server is "
                          "shutting down); try again",
                          NULL);
        return;
    default:
        ljgap__ans_oom(out);
        return;
    }
}

/* Parses exactly one JSON value filling body[0..len), which must be UTF-8 (RFC 8259 §8.1: the
 * answer quotes names from it); NULL with *where set when it is not. */
static cJSON *parse_body(const char *body, size_t len, size_t *where)
{
    const char *end = body;
    cJSON *root = NULL;
    if (body && (*where = ljgap__utf8_span(body, len)) < len) return NULL;
    root = body && len ? cJSON_ParseWithLengthOpts(body, len, &end, 0) : NULL;
    if (!root) {
        *where = end && body ? (size_t)(end - body) : 0;
        return NULL;
    }
    while ((size_t)(end - body) < len && *end && strchr(" \t\r\n", *end))
        end++;
    if ((size_t)(end - body) < len) {
        *where = (size_t)(end - body);
        cJSON_Delete(root);
        return NULL;
    }
    return root;
}

/* The 422 validation problem of ve's problems (500 when recording them ran out of memory);
 * takes ve->errors. */
void ljgap__ans_invalid(ljgap__reply *out, ljgap__verr *ve)
{
    char detail[DETAIL_LEN];
    if (ve->oom) {
        ljgap__ans_oom(out);
        return;
    }
    if (ve->n > LJGAP_MAX_ERRORS)
        snprintf(detail, sizeof detail,
                 "%d problems in the request; the first %d are "
                 "listed in errors",
                 ve->n, LJGAP_MAX_ERRORS);
    else
        snprintf(detail, sizeof detail, "%d problem%s in the request: see errors", ve->n,
                 ve->n == 1 ? "" : "s");
    ljgap__ans_problem(out, P_VALIDATION, detail, ve->errors);
    ve->errors = NULL; /* reply_problem took it */
}

/* Parses body and validates it as a request to ep into j->rq. Returns 1 when it is valid;
 * else 0 with the problem (400, 422 or 500) in *out. j->rq is left for ljgap__request_free. */
int ljgap__ans_validate(ljgap__endpoint ep, const char *body, size_t len, job *j, ljgap__reply *out)
{
    cJSON *root = NULL;
    ljgap__verr ve = {0};
    char detail[DETAIL_LEN];
    size_t where = 0;
    int ok = 0;
    if (!(root = parse_body(body, len, &where))) {
        snprintf(detail, sizeof detail,
                 "the body is not one valid JSON value in UTF-8 (error at byte "
                 "%zu of %zu)",
                 where, len);
        ljgap__ans_problem(out, P_MALFORMED, detail, NULL);
        goto end;
    }
    if (!(ve.errors = cJSON_CreateArray())) {
        ljgap__ans_oom(out);
        goto end;
    }
    if (ljgap__request_parse(ep, root, &limits, &j->rq, &ve) || ve.oom) {
        ljgap__ans_invalid(out, &ve);
        goto end;
    }
    ok = 1;
end:
    cJSON_Delete(root);
    cJSON_Delete(ve.errors);
    return ok;
}

/* The media types an answer can take: JSON always, CSV where csv.h has a form for it. */
const char *const ljgap__ans_forms[2] = {CT_JSON, "text/csv"};

/* Which form the Accept header asks for: 0 JSON, 1 CSV (only when csv is nonzero), or -1 with
 * the 406 problem in *out. */
int ljgap__ans_negotiate(const char *accept, int csv, ljgap__reply *out)
{
    int k = ljgap__accept_pick(accept, ljgap__ans_forms, csv ? 2 : 1);
    if (k < 0)
        ljgap__ans_problem(out, P_NOT_ACCEPTABLE,
                          csv ? "the Accept header allows neither application/json nor text/csv, "
                                "the forms this answer has; ask for one of them or send no Accept"
                              : "the Accept header does not allow application/json, the one form "
                                "this answer has; ask for it or send no Accept",
                          NULL);
    return k;
}

/* The form of endpoint's answer that call's Accept header asks for (negotiate). */
static int form_of(const char *endpoint, const ljgap__call *call, ljgap__reply *out)
{
    return ljgap__ans_negotiate(call ? call->accept : NULL, ljgap__csv_offers(endpoint), out);
}

/* Runs a validated request and answers it in form (0 JSON, 1 the CSV of endpoint; j->rq is
 * the caller's to free). */
void ljgap__ans_run_job(job *j, int (*run)(job *), const char *endpoint, int form,
                    const ljgap__call *call, double t0, ljgap__reply *out)
{
    int st;
    j->deadline = t0 + limits.max_seconds;
    j->cancel = call && call->cancel ? call->cancel : limits.cancel;
    if (!(j->ans = cJSON_CreateObject())) {
        ljgap__ans_oom(out);
        return;
    }
    st = run(j);
    if (!st) ljgap__ans_meta(j, t0);
    if (!st && j->oom) st = LJGAP_ENOMEM;
    if (st)
        ljgap__ans_status(out, st, j);
    else if (form == 0) {
        /* meta is the answer's last member and cached its own last one (ljgap__ans_meta) */
        ljgap__ans_reply_json(out, 200, CT_JSON, j->ans);
        out->cacheable = out->status == 200;
    } else if (ljgap__csv_render(endpoint, j->ans, j->rq.si_psd, out) != 0)
        ljgap__ans_oom(out);
    cJSON_Delete(j->ans);
    j->ans = NULL;
    cJSON_Delete(j->ie_meta); /* a failed run's (ljgap__ans_meta took a good one's) */
}

void ljgap__handle(const char *endpoint, const char *body, size_t len, ljgap__reply *out)
{
    ljgap__handle_call(endpoint, body, len, NULL, out);
}

void ljgap__handle_call(const char *endpoint, const char *body, size_t len, const ljgap__call *call,
                       ljgap__reply *out)
{
    double t0 = ljgap__clock_now();
    const endpoint_row *r = endpoint_find(endpoint);
    job j;
    char detail[DETAIL_LEN];
    int form;
    memset(&j, 0, sizeof j);
    memset(out, 0, sizeof *out);
    if (!r) {
        /* the name may be any bytes: quote only its first whole UTF-8 characters */
        snprintf(detail, sizeof detail,
                 "no endpoint \"%.*s\": the endpoints are adhesion, "
                 "traction, pdf, sweep, contact, psd and psd/combine",
                 endpoint ? (int)ljgap__utf8_span(endpoint, strnlen(endpoint, 60)) : 0,
                 endpoint ? endpoint : "");
        ljgap__ans_problem(out, P_NOT_FOUND, detail, NULL);
        goto end;
    }
    if ((form = form_of(r->name, call, out)) < 0) goto end;
    if (ljgap__ans_validate(r->ep, body, len, &j, out))
        ljgap__ans_run_job(&j, r->run, r->name, form, call, t0, out);
end:
    ljgap__request_free(&j.rq);
}

int ljgap__handler_has_text(const char *endpoint)
{
    return endpoint && strcmp(endpoint, "psd") == 0;
}

void ljgap__handle_text(const char *endpoint, const ljgap__param *params, size_t nparams,
                       const char *body, size_t len, const ljgap__call *call, ljgap__reply *out)
{
    double t0 = ljgap__clock_now();
    ljgap__topo_spec heights = {0};
    ljgap__verr ve = {0};
    cJSON *query = NULL;
    char detail[DETAIL_LEN];
    job j;
    int form;
    memset(&j, 0, sizeof j);
    memset(out, 0, sizeof *out);
    if (!ljgap__handler_has_text(endpoint)) {
        snprintf(detail, sizeof detail,
                 "no text upload to \"%.*s\": only psd takes a height matrix as text/plain or "
                 "text/csv; the other endpoints take JSON",
                 endpoint ? (int)ljgap__utf8_span(endpoint, strnlen(endpoint, 60)) : 0,
                 endpoint ? endpoint : "");
        ljgap__ans_problem(out, P_NOT_FOUND, detail, NULL);
        return;
    }
    if ((form = form_of(endpoint, call, out)) < 0) return;
    if (!(ve.errors = cJSON_CreateArray())) {
        ljgap__ans_oom(out);
        return;
    }
    ljgap__topo_text_parse(body ? body : "", body ? len : 0, ljgap__limits_topo_cap(&limits),
                          &heights, &ve);
    if (!(query = ljgap__topo_params_json(params, nparams, &ve))) ve.oom = 1;
    if (!ve.oom) ljgap__request_parse_text(query, &heights, &limits, &j.rq, &ve);
    if (ve.n || ve.oom)
        ljgap__ans_invalid(out, &ve);
    else
        ljgap__ans_run_job(&j, ljgap__run_psd, endpoint, form, call, t0, out);
    cJSON_Delete(query);
    cJSON_Delete(ve.errors);
    free(heights.h);
    ljgap__request_free(&j.rq);
}

/* ---- for endpoints run in their own files (answer.h) ---- */

const ljgap__limits *ljgap__handler_limits(void)
{
    return &limits;
}

cJSON *ljgap__ans_put(job *j, cJSON *parent, const char *key, cJSON *item)
{
    return put(j, parent, key, item);
}

void ljgap__ans_num(job *j, cJSON *parent, const char *key, double v, const char *label, long idx)
{
    put_num(j, parent, key, v, label, idx);
}

cJSON *ljgap__ans_nums(job *j, cJSON *parent, const char *key, const double *x, size_t n,
                      size_t stride, const char *label)
{
    return put_nums(j, parent, key, x, n, stride, label);
}
