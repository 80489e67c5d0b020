/* handler.c -- the request handler: endpoint name + JSON body + Accept -> status + body.
 *
 * The CLI, the HTTP daemon and the fuzzer are thin shells over ljgap_handle_call. It parses the
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
 * Simulations (the discrete model, ljgap_sim.h, and its hybrid with the theory when the request
 * has k_split) are not an endpoint of ljgap_handle: a run takes minutes.
 * ljgap_sim_request_parse validates like every endpoint (same problems) and builds the PSD;
 * ljgap_sim_request_run runs it under the caller's cancel flag, progress callback and time cap,
 * its realizations on limits.sim_threads threads, and serialises the result. The daemon runs them
 * as background jobs (jobs.c), the CLI in the foreground; ljgap_sim_status_answer answers a poll
 * of a job, with a finished job's result as CSV when Accept asks for it.
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
#include "accept.h"
#include "answer.h"
#include "csv.h"
#include "ljgap_sim.h"
#include "ljgap_topo.h"
#include "problems.h"
#include "request.h"

#include <math.h>
#include <pthread.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define CT_JSON "application/json"
#define CT_PROBLEM "application/problem+json"
#define DETAIL_LEN (LJGAP_MAX_WARN * LJGAP_WARN_LEN + 400)

/* Problem types (problems.c has the status, title and page of each). */
#define P_MALFORMED "malformed-json"
#define P_NOT_FOUND "not-found"
#define P_NOT_ACCEPTABLE "not-acceptable"
#define P_VALIDATION "validation"
#define P_OUTSIDE "outside-model"
#define P_CAP "cap-exceeded"
#define P_NO_ANSWER "no-answer"
#define P_UNAVAILABLE "unavailable"
#define P_OOM "out-of-memory"

/* Sent when not even a problem can be allocated; never freed (see ljgap_reply_free). */
static char oom_body[] = "{\"type\":\"" LJGAP_PROBLEM_BASE "out-of-memory\","
                         "\"title\":\"Out of memory\",\"status\":500,"
                         "\"detail\":\"the server ran out of memory\",\"errors\":[]}";

static ljgap_limits limits = LJGAP_LIMITS_INIT; /* written only by ljgap_handler_set_limits */

void ljgap_handler_set_limits(const ljgap_limits *l)
{
    limits = *l;
}

/* ---- replies ---- */

static void reply_oom(ljgap_reply *out)
{
    out->status = 500;
    out->body = oom_body;
    out->len = strlen(oom_body);
    out->content_type = CT_PROBLEM;
}

/* Serialises doc into out; doc stays the caller's. */
static void reply_json(ljgap_reply *out, int status, const char *ctype, const cJSON *doc)
{
    char *s = cJSON_PrintUnformatted(doc);
    if (!s) {
        reply_oom(out);
        return;
    }
    out->status = status;
    out->body = s;
    out->len = strlen(s);
    out->content_type = ctype;
}

/* A problem answer of type /problems/slug (status and title from problems.c); takes errors
 * (an array, or NULL for an empty one). */
static void reply_problem(ljgap_reply *out, const char *slug, const char *detail, cJSON *errors)
{
    const ljgap_problem_doc *k = ljgap_problem_find(slug);
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
        reply_oom(out);
        goto end;
    }
    reply_json(out, k->status, CT_PROBLEM, p);
end:
    cJSON_Delete(p);
}

void ljgap_reply_problem(ljgap_reply *out, const char *slug, const char *detail)
{
    memset(out, 0, sizeof *out);
    reply_problem(out, slug, detail, NULL);
}

void ljgap_reply_free(ljgap_reply *r)
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
static void put_summary(job *j, cJSON *obj, cJSON *err_parent, const char *err_key,
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

static void put_meta(job *j, double t0)
{
    cJSON *meta = put(j, j->ans, "meta", cJSON_CreateObject());
    cJSON *w;
    put(j, meta, "method", cJSON_CreateString(j->rq.method));
    put(j, meta, "elapsed_ms", cJSON_CreateNumber((ljgap_now() - t0) * 1e3));
    put(j, meta, "version", cJSON_CreateString(LJGAP_VERSION));
    w = put(j, meta, "warnings", cJSON_CreateArray());
    for (int i = 0; w && i < j->rq.warn.n; i++)
        put(j, w, NULL, cJSON_CreateString(j->rq.warn.msg[i]));
    put(j, meta, "cached", cJSON_CreateFalse());
}

/* Core options for one call: the request's, capped by what is left of the time budget. */
static int opts_now(job *j, ljgap_opts *o)
{
    *o = j->rq.opts;
    o->max_seconds = j->deadline - ljgap_now();
    o->cancel = j->cancel;
    if (o->max_seconds > 0) return LJGAP_OK;
    snprintf(j->fail, sizeof j->fail, " (the request's time budget ran out before this step)");
    return LJGAP_ECAP;
}

/* ---- endpoints ---- */

/* Core options and the PSD for one core call (free psd after, on success). */
static int prepare(job *j, const ljgap_psd_spec *spec, ljgap_psd *psd, ljgap_opts *o,
                   ljgap_warnings *w)
{
    int st = opts_now(j, o);
    if (st) return st;
    st = ljgap_psd_from_spec(psd, spec);
    if (st == LJGAP_EINVAL)
        ljgap_warn(w, "the PSD could not be formed: its variance is not a finite positive "
                      "number");
    return st;
}

/* Summary of the PSD in spec: one ljgap_traction call with no points. */
static int summarise(job *j, const ljgap_psd_spec *spec, ljgap_summary *sum, ljgap_warnings *w)
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
    put_summary(j, j->ans, j->ans, "error", &sum);
    put_si(j, j->ans, &sum);
    return LJGAP_OK;
}

static int run_traction(job *j)
{
    const ljgap_request *rq = &j->rq;
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
    put_summary(j, sum_obj, err, "summary", &sum);
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
end:
    free(sigma);
    return st;
}

static int run_pdf(job *j)
{
    const ljgap_request *rq = &j->rq;
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
    const ljgap_request *rq = &sw->j->rq;
    for (;;) {
        ljgap_psd_spec spec;
        size_t i;
        pthread_mutex_lock(&sw->lock);
        i = sw->stop ? rq->nx : sw->next++;
        pthread_mutex_unlock(&sw->lock);
        if (i >= rq->nx) return NULL;
        ljgap_request_sweep_spec(rq, i, &spec);
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
    ljgap_request *rq = &j->rq;
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
        put_summary(j, r, r, "error", sw.st[i] ? NULL : &sw.sum[i]);
        if (sir && !sw.st[i]) {
            cJSON *sr = put(j, sir, NULL, cJSON_CreateObject());
            put_si_summary(j, sr, sr, "error", &sw.sum[i]);
        } else if (sir)
            put(j, sir, NULL, cJSON_CreateNull());
    }
    if (failed == rq->nx) {
        snprintf(j->fail, sizeof j->fail, " for any of the %zu values", rq->nx);
        st = LJGAP_EFAIL;
    }
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
    put_summary(j, j->ans, j->ans, "error", &sum);
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
    return LJGAP_OK;
}

/* ---- psd: a height map's PSD (issue 15, core/topo.c) ---- */

#define K1_MARGIN 1.1 /* the proposed k1 keeps this factor above k0/χ, off the pole of (14) */
#define SLOPE_WARN 3  /* an rms slope above this asks whether the units are right */

/* Does the fit stand for the spectrum up to the table's end, soundly, with an exponent below
 * -2? Then the tail continues it. Up to the end: every reliable bin above the fit's band lies
 * within TAIL_BINS_SIGMA errors (and TAIL_BINS_REL) of the fitted law, so that a cutoff, a noise
 * floor or the tip's trace above the band stops the tail while a band that merely stops a bin
 * or two short of the end does not. */
#define TAIL_BINS_SIGMA 3
#define TAIL_BINS_REL 0.1
static int fit_gives_tail(const ljgap_topo_result *r)
{
    if (!r->has_fit || !r->fit.sound || !(2 * r->fit.D.value - 8 < -2)) return 0;
    for (size_t i = r->rel_first; i <= r->rel_last && i < r->n; i++) {
        if (r->k[i] <= r->fit.kmax * (1 + 1e-9)) continue;
        double law = r->fit.C.value * pow(r->k[i], 2 * r->fit.D.value - 8);
        if (!(fabs(log(r->P[i] / law)) <= TAIL_BINS_SIGMA * r->P_err[i] / r->P[i] + TAIL_BINS_REL))
            return 0;
    }
    return 1;
}

/* The psd object of a table (k, P, P_err: n knots, log-log interpolated) with the tail P ∝ k^q
 * when q is finite: /v1/psd's (put_psd_object) and /v1/psd/combine's. Its variance (with the
 * tail) into *m0 (NAN when it cannot be formed). */
void ljgap_ans_table_psd(job *j, const double *k, const double *P, const double *P_err, size_t n,
                         double q, double q_err, double *m0)
{
    cJSON *o = put(j, j->ans, "psd", cJSON_CreateObject());
    int tail = isfinite(q);
    ljgap_psd psd;
    *m0 = NAN;
    put(j, o, "kind", cJSON_CreateString("table"));
    put_nums(j, o, "k", k, n, sizeof *k, "psd.k");
    put_nums(j, o, "P", P, n, sizeof *P, "psd.P");
    put_nums(j, o, "P_err", P_err, n, sizeof *P_err, "psd.P_err");
    if (tail) {
        cJSON *to = put(j, o, "tail", cJSON_CreateObject());
        put_num(j, to, "exponent", q, "psd.tail", -1);
        put_num(j, to, "exponent_err", q_err, "psd.tail.exponent_err", -1);
    }
    if (ljgap_psd_table(&psd, k, P, n, tail, tail ? q : 0) == LJGAP_OK) *m0 = psd.m0;
    ljgap_psd_free(&psd);
}

/* The psd object for /v1/adhesion with "units":"SI": the reliable bins from k_from on as a
 * table that keeps their variance (ljgap_topo_table), with P_err and the fitted power law as
 * the tail when fit_gives_tail; the fitted power law itself from k_from when no reliable bin
 * reaches beyond it; null (and a warning) when neither can be formed. Its variance into *m0
 * (m², NAN when null). */
static void put_psd_object(job *j, const ljgap_topo_result *r, double k_from, double *m0)
{
    double q = 2 * r->fit.D.value - 8;
    int tail = fit_gives_tail(r);
    ljgap_topo_tab t;
    int st = ljgap_topo_table(r, k_from, tail ? q : NAN, &t);
    cJSON *o;
    ljgap_psd psd;
    *m0 = NAN;
    if (st == LJGAP_ENOMEM) {
        j->oom = 1;
        return;
    }
    if (st == LJGAP_OK) {
        ljgap_ans_table_psd(j, t.k, t.P, t.P_err, t.n, tail ? q : NAN, 2 * r->fit.D.err, m0);
        if (!tail)
            ljgap_warn(
                &j->rq.warn, "the psd object has no tail: %s, so the table ends at k = %g 1/m",
                !r->has_fit     ? "there is no power-law fit"
                : !r->fit.sound ? "the fit is no sound power law with 2 < D < 3"
                                : "the bins above the fit band are no power law (a cutoff, a noise "
                                  "floor or the tip's trace?) and are kept as measured",
                t.k[t.n - 1]);
    } else if (r->has_fit && r->fit.sound && q < -2) {
        o = put(j, j->ans, "psd", cJSON_CreateObject());
        put(j, o, "kind", cJSON_CreateString("power"));
        put_num(j, o, "D", r->fit.D.value, "psd.D", -1);
        put_num(j, o, "k1", k_from, "psd.k1", -1);
        put_num(j, o, "C", r->fit.C.value, "psd.C", -1);
        ljgap_warn(&j->rq.warn,
                   "the theory's band starts at k1 = %g 1/m, beyond the reliable bins: the psd "
                   "object is the fitted power law, extrapolated",
                   k_from);
        if (ljgap_psd_power(&psd, r->fit.D.value, k_from, INFINITY, LJGAP_LEVEL_C,
                            r->fit.C.value) == LJGAP_OK)
            *m0 = psd.m0;
    } else {
        put(j, j->ans, "psd", cJSON_CreateNull());
        ljgap_warn(&j->rq.warn,
                   "no psd object: no reliable bin lies above k = %g 1/m and the "
                   "fit gives no sound power law with 2 < D < 3 to extrapolate",
                   k_from);
    }
    ljgap_topo_tab_free(&t);
}

/* With a material: where the band [kf, kl] (its name: "reliable band", ...) lies against the
 * theory's k > k0/χ and the k1 it proposes (kf, or K1_MARGIN k0/χ when that is higher) into
 * d and the answer's "domain"; the caller then writes the psd object from d->k1 and ends with
 * ljgap_ans_domain_end and the object's variance. /v1/psd's and /v1/psd/combine's. */
void ljgap_ans_domain_begin(job *j, double kf, double kl, const char *band, ljgap_domain *d)
{
    const ljgap_material *m = &j->rq.mat;
    double chi = ljgap_units_chi(m);
    d->kd = ljgap_k0() / chi;
    d->kf = kf;
    d->kl = kl;
    d->band = band;
    d->k1 = fmax(kf, K1_MARGIN * d->kd);
    d->inside = kl <= d->kd ? 0 : kf > d->kd ? 1 : log(kl / d->kd) / log(kl / kf);
    d->obj = put(j, j->ans, "domain", cJSON_CreateObject());
    put_num(j, d->obj, "k0", d->kd, "domain.k0", -1);
    put(j, d->obj, "inside",
        cJSON_CreateString(d->inside == 1   ? "all"
                           : d->inside == 0 ? "none"
                                            : "part"));
    put_num(j, d->obj, "fraction", d->inside, "domain.fraction", -1);
    put_num(j, d->obj, "k1", d->k1, "domain.k1", -1);
    put_num(j, d->obj, "k1_dimensionless", d->k1 * chi, "domain.k1_dimensionless", -1);
}

void ljgap_ans_domain_end(job *j, const ljgap_domain *d, double m0)
{
    if (isfinite(m0)) {
        put_num(j, d->obj, "h_rms", sqrt(m0), "domain.h_rms", -1);
        put_num(j, d->obj, "m0_dimensionless", ljgap_units_var_to_dimless(&j->rq.mat, m0),
                "domain.m0_dimensionless", -1);
    } else {
        put(j, d->obj, "h_rms", cJSON_CreateNull());
        put(j, d->obj, "m0_dimensionless", cJSON_CreateNull());
    }
    if (d->inside < 1)
        ljgap_warn(&j->rq.warn,
                   "%s of the %s (k = %g to %g 1/m) lies below k0/χ = %g 1/m, "
                   "outside the theory's domain: the psd object starts at k1 = %g 1/m",
                   d->inside == 0 ? "all" : "part", d->band, d->kf, d->kl, d->kd, d->k1);
}

void ljgap_ans_si(job *j)
{
    put_si(j, j->ans, NULL);
}

/* With a material: the domain of the reliable band and the psd object from its k1. */
static void put_domain(job *j, const ljgap_topo_result *r)
{
    ljgap_domain d;
    double m0;
    ljgap_ans_domain_begin(j, r->rel_kmin, r->k[r->rel_last], "reliable band", &d);
    put_psd_object(j, r, d.k1, &m0);
    ljgap_ans_domain_end(j, &d, m0);
}

static int run_psd(job *j)
{
    ljgap_topo_spec *t = &j->rq.topo;
    ljgap_topo_grid g = {t->nx, t->ny, t->dx, t->dy, t->periodic};
    ljgap_topo_opts o;
    ljgap_topo_result r;
    cJSON *err, *grid, *fit, *efit, *pr, *rel;
    double m0;
    int st;
    ljgap_topo_opts_default(&o);
    o.cancel = j->cancel;
    o.fit_kmin = t->fit_kmin;
    o.fit_kmax = t->fit_kmax;
    o.detrend = (ljgap_topo_detrend)t->detrend;
    o.tip_radius = t->tip_radius;
    o.resolution = t->resolution;
    st = ljgap_topo_compute(t->h, &g, &o, &r, &j->rq.warn);
    free(t->h); /* a large map: the answer needs the bins only */
    t->h = NULL;
    if (st == LJGAP_EINVAL || st == LJGAP_EFAIL) {
        j->bad_ptr = "/topography/heights";
        j->bad_head = "the height map cannot be analysed";
        return LJGAP_EINVAL;
    }
    if (st) return st;
    put_nums(j, j->ans, "k", r.k, r.n, sizeof *r.k, "k");
    put_nums(j, j->ans, "P", r.P, r.n, sizeof *r.P, "P");
    put_nums(j, j->ans, "modes", r.modes, r.n, sizeof *r.modes, "modes");
    put_num(j, j->ans, "h_rms", r.h_rms.value, "h_rms", -1);
    put_num(j, j->ans, "rms_slope", r.rms_slope.value, "rms_slope", -1);
    grid = put(j, j->ans, "grid", cJSON_CreateObject());
    put(j, grid, "nx", cJSON_CreateNumber((double)t->nx));
    put(j, grid, "ny", cJSON_CreateNumber((double)t->ny));
    put_num(j, grid, "dx", t->dx, "grid.dx", -1);
    put_num(j, grid, "dy", t->dy, "grid.dy", -1);
    put(j, grid, "periodic", cJSON_CreateBool(t->periodic));
    put(j, grid, "profile", cJSON_CreateBool(r.profile));
    put(j, grid, "detrend",
        cJSON_CreateString(r.profile && r.detrend == LJGAP_DETREND_PLANE
                               ? "line"
                               : ljgap_topo_detrend_name(r.detrend)));
    put(j, grid, "window", cJSON_CreateString(t->periodic ? "none" : "hann"));
    put_num(j, grid, "k_min", r.k_fund, "grid.k_min", -1);
    put_num(j, grid, "k_max", r.k_nyq, "grid.k_max", -1);
    rel = put(j, j->ans, "reliable", cJSON_CreateObject());
    put_num(j, rel, "k_min", r.rel_kmin, "reliable.k_min", -1);
    put_num(j, rel, "k_max", r.rel_kmax, "reliable.k_max", -1);
    put(j, rel, "by",
        cJSON_CreateString(r.rel_by == LJGAP_RELIABLE_TIP          ? "tip"
                           : r.rel_by == LJGAP_RELIABLE_RESOLUTION ? "resolution"
                           : r.rel_by == LJGAP_RELIABLE_NOISE      ? "noise"
                                                                   : "nyquist"));
    err = put(j, j->ans, "error", cJSON_CreateObject());
    put_nums(j, err, "P", r.P_err, r.n, sizeof *r.P_err, "error.P");
    put_num(j, err, "h_rms", r.h_rms.err, "error.h_rms", -1);
    put_num(j, err, "rms_slope", r.rms_slope.err, "error.rms_slope", -1);
    if (r.has_fit) {
        fit = put(j, j->ans, "fit", cJSON_CreateObject());
        efit = put(j, err, "fit", cJSON_CreateObject());
        put_num(j, fit, "D", r.fit.D.value, "fit.D", -1);
        put_num(j, fit, "H", 3 - r.fit.D.value, "fit.H", -1);
        put_num(j, fit, "C", r.fit.C.value, "fit.C", -1);
        put_num(j, fit, "k_min", r.fit.kmin, "fit.k_min", -1);
        put_num(j, fit, "k_max", r.fit.kmax, "fit.k_max", -1);
        put(j, fit, "bins", cJSON_CreateNumber((double)r.fit.bins));
        put_num(j, fit, "chi2_red", r.fit.chi2_red, "fit.chi2_red", -1);
        put_num(j, fit, "corr_lnC_D", r.fit.corr, "fit.corr_lnC_D", -1);
        put(j, fit, "band", cJSON_CreateString(r.fit.given ? "given" : "detected"));
        put(j, fit, "sound", cJSON_CreateBool(r.fit.sound));
        put_num(j, efit, "D", r.fit.D.err, "error.fit.D", -1);
        put_num(j, efit, "H", r.fit.D.err, "error.fit.H", -1);
        put_num(j, efit, "C", r.fit.C.err, "error.fit.C", -1);
        if (r.fit.noise_floor > 0) { /* a white floor fitted with the law (m⁴) */
            put_num(j, fit, "noise_floor", r.fit.noise_floor, "fit.noise_floor", -1);
            put_num(j, efit, "noise_floor", r.fit.noise_floor_err, "error.fit.noise_floor", -1);
        } else {
            put(j, fit, "noise_floor", cJSON_CreateNull());
            put(j, efit, "noise_floor", cJSON_CreateNull());
        }
    } else {
        put(j, j->ans, "fit", cJSON_CreateNull());
        put(j, err, "fit", cJSON_CreateNull());
    }
    if (r.profile) {
        pr = put(j, j->ans, "profile", cJSON_CreateObject());
        put_nums(j, pr, "PP", r.PP, r.n, sizeof *r.PP, "profile.PP");
        put_num(j, pr, "alpha", r.alpha.value, "profile.alpha", -1);
        pr = put(j, err, "profile", cJSON_CreateObject());
        put_nums(j, pr, "PP", r.PP_err, r.n, sizeof *r.PP_err, "error.profile.PP");
        put_num(j, pr, "alpha", r.alpha.err, "error.profile.alpha", -1);
        ljgap_warn(&j->rq.warn,
                   "one profile: its 1-D PSD PP ∝ k^-%.3g was turned into the isotropic PSD P = "
                   "F(α) PP/k, which assumes an isotropic surface",
                   r.alpha.value);
    }
    if (r.rms_slope.value > SLOPE_WARN)
        ljgap_warn(&j->rq.warn,
                   "the rms slope is %.3g: are the heights and dx, dy in metres (the same unit)?",
                   r.rms_slope.value);
    if (j->rq.has_material)
        put_domain(j, &r);
    else
        put_psd_object(j, &r, 0, &m0);
    put_si(j, j->ans, NULL);
    ljgap_topo_result_free(&r);
    return LJGAP_OK;
}

/* ---- routing ---- */

typedef struct {
    const char *name;
    ljgap_endpoint ep;
    int (*run)(job *j);
} route;

static const route routes[] = {
    {"adhesion", LJGAP_EP_ADHESION, run_adhesion},
    {"traction", LJGAP_EP_TRACTION, run_traction},
    {"pdf", LJGAP_EP_PDF, run_pdf},
    {"sweep", LJGAP_EP_SWEEP, run_sweep},
    {"contact", LJGAP_EP_CONTACT, run_contact},
    {"psd", LJGAP_EP_PSD, run_psd},
    {"psd/combine", LJGAP_EP_COMBINE, ljgap_run_combine},
};

static const route *route_find(const char *name)
{
    for (size_t i = 0; name && i < sizeof routes / sizeof routes[0]; i++)
        if (strcmp(name, routes[i].name) == 0) return &routes[i];
    return NULL;
}

int ljgap_handler_has(const char *endpoint)
{
    return route_find(endpoint) != NULL;
}

/* "; "-joined warnings after prefix into buf. */
static void join_warnings(char *buf, size_t size, const char *prefix, const ljgap_warnings *w)
{
    size_t used = (size_t)snprintf(buf, size, "%s", prefix);
    for (int i = 0; i < w->n && used < size; i++)
        used += (size_t)snprintf(buf + used, size - used, "%s%s", i ? "; " : ": ", w->msg[i]);
}

/* The problem for a failed core status. */
static void reply_status(ljgap_reply *out, int st, const job *j)
{
    char detail[DETAIL_LEN], head[DETAIL_LEN + 200];
    cJSON *errors = NULL, *e = NULL;
    switch (st) {
    case LJGAP_EINVAL:
        join_warnings(detail, sizeof detail,
                      j->bad_head ? j->bad_head : "the PSD is outside the model's domain",
                      &j->rq.warn);
        errors = cJSON_CreateArray();
        e = cJSON_CreateObject();
        if (!errors || !e ||
            !cJSON_AddStringToObject(e, "pointer", j->bad_ptr ? j->bad_ptr : "/psd") ||
            !cJSON_AddStringToObject(e, "detail", detail) || !cJSON_AddItemToArray(errors, e)) {
            cJSON_Delete(e);
            cJSON_Delete(errors);
            reply_oom(out);
            return;
        }
        reply_problem(out, P_OUTSIDE, detail, errors);
        return;
    case LJGAP_ECAP:
        snprintf(head, sizeof head,
                 "the computation needs more than the server's caps allow "
                 "(max_seconds = %g s of wall time per request, max_work = %ld grid "
                 "point-steps); ask for a larger tol or fewer points%s",
                 limits.max_seconds, j->rq.opts.max_work, j->fail);
        join_warnings(detail, sizeof detail, head, &j->rq.warn);
        reply_problem(out, P_CAP, detail, NULL);
        return;
    case LJGAP_EFAIL:
        snprintf(head, sizeof head, "no finite answer could be formed%s", j->fail);
        join_warnings(detail, sizeof detail, head, &j->rq.warn);
        reply_problem(out, P_NO_ANSWER, detail, NULL);
        return;
    case LJGAP_ECANCEL:
        reply_problem(out, P_UNAVAILABLE,
                      "the computation was cancelled (the server is "
                      "shutting down); try again",
                      NULL);
        return;
    default:
        reply_oom(out);
        return;
    }
}

/* Parses exactly one JSON value filling body[0..len), which must be UTF-8 (RFC 8259 §8.1: the
 * answer quotes names from it); NULL with *where set when it is not. */
static cJSON *parse_body(const char *body, size_t len, size_t *where)
{
    const char *end = body;
    cJSON *root = NULL;
    if (body && (*where = ljgap_utf8_span(body, len)) < len) return NULL;
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
static void reply_invalid(ljgap_reply *out, ljgap_verr *ve)
{
    char detail[DETAIL_LEN];
    if (ve->oom) {
        reply_oom(out);
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
    reply_problem(out, P_VALIDATION, detail, ve->errors);
    ve->errors = NULL; /* reply_problem took it */
}

/* Parses body and validates it as a request to ep into j->rq. Returns 1 when it is valid;
 * else 0 with the problem (400, 422 or 500) in *out. j->rq is left for ljgap_request_free. */
static int validate(ljgap_endpoint ep, const char *body, size_t len, job *j, ljgap_reply *out)
{
    cJSON *root = NULL;
    ljgap_verr ve = {0};
    char detail[DETAIL_LEN];
    size_t where = 0;
    int ok = 0;
    if (!(root = parse_body(body, len, &where))) {
        snprintf(detail, sizeof detail,
                 "the body is not one valid JSON value in UTF-8 (error at byte "
                 "%zu of %zu)",
                 where, len);
        reply_problem(out, P_MALFORMED, detail, NULL);
        goto end;
    }
    if (!(ve.errors = cJSON_CreateArray())) {
        reply_oom(out);
        goto end;
    }
    if (ljgap_request_parse(ep, root, &limits, &j->rq, &ve) || ve.oom) {
        reply_invalid(out, &ve);
        goto end;
    }
    ok = 1;
end:
    cJSON_Delete(root);
    cJSON_Delete(ve.errors);
    return ok;
}

/* The media types an answer can take: JSON always, CSV where csv.h has a form for it. */
static const char *const forms[] = {CT_JSON, "text/csv"};

/* Which form the Accept header asks for: 0 JSON, 1 CSV (only when csv is nonzero), or -1 with
 * the 406 problem in *out. */
static int negotiate(const char *accept, int csv, ljgap_reply *out)
{
    int k = ljgap_accept_pick(accept, forms, csv ? 2 : 1);
    if (k < 0)
        reply_problem(out, P_NOT_ACCEPTABLE,
                      csv ? "the Accept header allows neither application/json nor text/csv, "
                            "the forms this answer has; ask for one of them or send no Accept"
                          : "the Accept header does not allow application/json, the one form "
                            "this answer has; ask for it or send no Accept",
                      NULL);
    return k;
}

/* The form of endpoint's answer that call's Accept header asks for (negotiate). */
static int form_of(const char *endpoint, const ljgap_call *call, ljgap_reply *out)
{
    return negotiate(call ? call->accept : NULL, ljgap_csv_offers(endpoint), out);
}

/* Runs a validated request and answers it in form (0 JSON, 1 the CSV of endpoint; j->rq is
 * the caller's to free). */
static void run_job(job *j, int (*run)(job *), const char *endpoint, int form,
                    const ljgap_call *call, double t0, ljgap_reply *out)
{
    int st;
    j->deadline = t0 + limits.max_seconds;
    j->cancel = call && call->cancel ? call->cancel : limits.cancel;
    if (!(j->ans = cJSON_CreateObject())) {
        reply_oom(out);
        return;
    }
    st = run(j);
    if (!st) put_meta(j, t0);
    if (!st && j->oom) st = LJGAP_ENOMEM;
    if (st)
        reply_status(out, st, j);
    else if (form == 0)
        reply_json(out, 200, CT_JSON, j->ans);
    else if (ljgap_csv_render(endpoint, j->ans, j->rq.si_psd, out) != 0)
        reply_oom(out);
    cJSON_Delete(j->ans);
    j->ans = NULL;
}

void ljgap_handle(const char *endpoint, const char *body, size_t len, ljgap_reply *out)
{
    ljgap_handle_call(endpoint, body, len, NULL, out);
}

void ljgap_handle_call(const char *endpoint, const char *body, size_t len, const ljgap_call *call,
                       ljgap_reply *out)
{
    double t0 = ljgap_now();
    const route *r = route_find(endpoint);
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
                 endpoint ? (int)ljgap_utf8_span(endpoint, strnlen(endpoint, 60)) : 0,
                 endpoint ? endpoint : "");
        reply_problem(out, P_NOT_FOUND, detail, NULL);
        goto end;
    }
    if ((form = form_of(r->name, call, out)) < 0) goto end;
    if (validate(r->ep, body, len, &j, out)) run_job(&j, r->run, r->name, form, call, t0, out);
end:
    ljgap_request_free(&j.rq);
}

int ljgap_handler_has_text(const char *endpoint)
{
    return endpoint && strcmp(endpoint, "psd") == 0;
}

void ljgap_handle_text(const char *endpoint, const ljgap_param *params, size_t nparams,
                       const char *body, size_t len, const ljgap_call *call, ljgap_reply *out)
{
    double t0 = ljgap_now();
    ljgap_topo_spec heights = {0};
    ljgap_verr ve = {0};
    cJSON *query = NULL;
    char detail[DETAIL_LEN];
    job j;
    int form;
    memset(&j, 0, sizeof j);
    memset(out, 0, sizeof *out);
    if (!ljgap_handler_has_text(endpoint)) {
        snprintf(detail, sizeof detail,
                 "no text upload to \"%.*s\": only psd takes a height matrix as text/plain or "
                 "text/csv; the other endpoints take JSON",
                 endpoint ? (int)ljgap_utf8_span(endpoint, strnlen(endpoint, 60)) : 0,
                 endpoint ? endpoint : "");
        reply_problem(out, P_NOT_FOUND, detail, NULL);
        return;
    }
    if ((form = form_of(endpoint, call, out)) < 0) return;
    if (!(ve.errors = cJSON_CreateArray())) {
        reply_oom(out);
        return;
    }
    ljgap_topo_text_parse(body ? body : "", body ? len : 0, ljgap_limits_topo_cap(&limits), &heights, &ve);
    if (!(query = ljgap_topo_params_json(params, nparams, &ve))) ve.oom = 1;
    if (!ve.oom) ljgap_request_parse_text(query, &heights, &limits, &j.rq, &ve);
    if (ve.n || ve.oom)
        reply_invalid(out, &ve);
    else
        run_job(&j, run_psd, endpoint, form, call, t0, out);
    cJSON_Delete(query);
    cJSON_Delete(ve.errors);
    free(heights.h);
    ljgap_request_free(&j.rq);
}

/* ---- simulations (ljgap_sim.h) ---- */

struct ljgap_sim_request {
    job j;         /* the validated request (j.rq) and, while it runs, the answer */
    ljgap_psd psd; /* built from j.rq.psd at parse time */
};

ljgap_sim_request *ljgap_sim_request_parse(const char *body, size_t len, ljgap_reply *out)
{
    ljgap_sim_request *sr = calloc(1, sizeof *sr);
    ljgap_verr ve = {0};
    int st;
    memset(out, 0, sizeof *out);
    if (!sr) {
        reply_oom(out);
        return NULL;
    }
    if (!validate(LJGAP_EP_SIMULATION, body, len, &sr->j, out)) goto fail;
    st = ljgap_psd_from_spec(&sr->psd, &sr->j.rq.psd);
    if (st == LJGAP_OK && sr->psd.m0 > 0 && sr->psd.m0 <= LJGAP_M0_MAX) return sr;
    if (st == LJGAP_ENOMEM || !(ve.errors = cJSON_CreateArray())) {
        reply_oom(out);
        goto fail;
    }
    ljgap_verr_add(&ve, "/psd", "the PSD's variance m0 = %g is outside (0, %g]",
                   st == LJGAP_OK ? sr->psd.m0 : NAN, LJGAP_M0_MAX);
    if (ve.oom)
        reply_oom(out);
    else
        reply_problem(out, P_VALIDATION, "1 problem in the request: see errors", ve.errors);
    ve.errors = NULL;
fail:
    cJSON_Delete(ve.errors);
    ljgap_sim_request_free(sr);
    return NULL;
}

/* The result object of a run (api.md "simulations"). */
static void put_sim_result(job *j, const ljgap_sim_result *r, double t0)
{
    cJSON *jump, *err;
    size_t n = r->n_gap;
    put_nums(j, j->ans, "g_ave", r->g_ave, n, sizeof *r->g_ave, "g_ave");
    put_nums(j, j->ans, "sigma", r->sigma, n, sizeof *r->sigma, "sigma");
    put_nums(j, j->ans, "sigma_std", r->sigma_std, n, sizeof *r->sigma_std, "sigma_std");
    put_nums(j, j->ans, "sigma_out", r->sigma_out, n, sizeof *r->sigma_out, "sigma_out");
    put_nums(j, j->ans, "residual", r->residual, n, sizeof *r->residual, "residual");
    jump = put(j, j->ans, "jump", cJSON_CreateArray());
    for (size_t i = 0; jump && i < n; i++)
        put(j, jump, NULL, cJSON_CreateBool(r->jump[i]));
    put_nums(j, j->ans, "m0_realized", r->m0_realized, (size_t)r->realizations,
             sizeof *r->m0_realized, "m0_realized");
    put_num(j, j->ans, "m0", r->m0_target, "m0", -1);
    put_num(j, j->ans, "m0_grid", r->m0_grid, "m0_grid", -1);
    put_num(j, j->ans, "L", r->L, "L", -1);
    put(j, j->ans, "n", cJSON_CreateNumber(r->n));
    put(j, j->ans, "realizations", cJSON_CreateNumber(r->realizations));
    put(j, j->ans, "seed", cJSON_CreateNumber((double)j->rq.sim.seed));
    put(j, j->ans, "tol", cJSON_CreateNumber(j->rq.sim.tol));
    put(j, j->ans, "elapsed_ms", cJSON_CreateNumber((ljgap_now() - t0) * 1e3));
    err = put(j, j->ans, "error", cJSON_CreateObject());
    put_nums(j, err, "sigma", r->sigma_err, n, sizeof *r->sigma_err, "error.sigma");
    if (r->k_split > 0) { /* the hybrid: the fine band and its modified law */
        cJSON *fine;
        put_num(j, j->ans, "k_split", r->k_split, "k_split", -1);
        fine = put(j, j->ans, "fine", cJSON_CreateObject());
        put_summary(j, fine, fine, "error", &r->fine);
        put_num(j, fine, "law_error", r->law_err, "fine.law_error", -1);
    }
}

void ljgap_sim_request_run(ljgap_sim_request *sr, const ljgap_sim_control *ctl, ljgap_reply *out)
{
    double t0 = ljgap_now();
    job *j = &sr->j;
    ljgap_sim_opts o = j->rq.sim;
    ljgap_sim_result res;
    char head[DETAIL_LEN + 200], detail[DETAIL_LEN];
    int st;
    memset(out, 0, sizeof *out);
    memset(&res, 0, sizeof res);
    long th = limits.sim_threads > 0 ? limits.sim_threads : sysconf(_SC_NPROCESSORS_ONLN);
    o.threads = th < 1 ? 1 : th > LJGAP_SIM_THREADS_MAX ? LJGAP_SIM_THREADS_MAX : (int)th;
    if (ctl) {
        if (ctl->max_seconds > 0) o.max_seconds = ctl->max_seconds;
        o.cancel = ctl->cancel;
        o.progress = ctl->progress;
        o.progress_ctx = ctl->progress_ctx;
    }
    st = ljgap_sim_run(&sr->psd, &o, j->rq.x, j->rq.nx, &res, &j->rq.warn);
    if (!st && !(j->ans = cJSON_CreateObject())) st = LJGAP_ENOMEM;
    if (!st) {
        put_sim_result(j, &res, t0);
        put_meta(j, t0);
        if (j->oom) st = LJGAP_ENOMEM;
    }
    if (!st) {
        reply_json(out, 200, CT_JSON, j->ans);
    } else if (st == LJGAP_ECAP) {
        snprintf(head, sizeof head,
                 "the simulation needs more than the cap of %g s of wall time for one run; "
                 "ask for a smaller n, fewer realizations or fewer mean gaps",
                 o.max_seconds);
        join_warnings(detail, sizeof detail, head, &j->rq.warn);
        reply_problem(out, P_CAP, detail, NULL);
    } else if (st == LJGAP_ECANCEL) {
        reply_problem(out, P_UNAVAILABLE,
                      "the simulation was cancelled before it finished (DELETE, Ctrl-C, or the "
                      "server shutting down)",
                      NULL);
    } else {
        reply_status(out, st, j);
    }
    cJSON_Delete(j->ans);
    j->ans = NULL;
    ljgap_sim_result_free(&res);
}

void ljgap_sim_request_free(ljgap_sim_request *sr)
{
    if (!sr) return;
    ljgap_psd_free(&sr->psd);
    ljgap_request_free(&sr->j.rq);
    free(sr);
}

void ljgap_sim_status_answer(const char *status_json, int http_status, const char *accept,
                             ljgap_reply *out)
{
    cJSON *doc = NULL;
    const char *state;
    char detail[200];
    int form;
    memset(out, 0, sizeof *out);
    if ((form = negotiate(accept, 1, out)) < 0) return;
    if (form == 1) {
        doc = cJSON_Parse(status_json);
        if (!doc) {
            reply_oom(out);
            return;
        }
        state = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(doc, "status"));
        if (state && strcmp(state, "done") == 0) {
            if (ljgap_csv_render("simulations", cJSON_GetObjectItemCaseSensitive(doc, "result"), 0,
                                 out) != 0)
                reply_oom(out);
            goto end;
        }
        if (ljgap_accept_pick(accept, forms, 1) < 0) { /* only CSV will do */
            snprintf(detail, sizeof detail,
                     "the job is %.20s: its result is there as text/csv once it is done; until "
                     "then ask for application/json too (Accept: text/csv, "
                     "application/json;q=0.5)",
                     state ? state : "not done");
            reply_problem(out, P_NOT_ACCEPTABLE, detail, NULL);
            goto end;
        }
    }
    if (!(out->body = strdup(status_json))) {
        reply_oom(out);
        goto end;
    }
    out->status = http_status;
    out->len = strlen(out->body);
    out->content_type = CT_JSON;
end:
    cJSON_Delete(doc);
}

/* ---- for endpoints run in their own files (answer.h) ---- */

cJSON *ljgap_ans_put(job *j, cJSON *parent, const char *key, cJSON *item)
{
    return put(j, parent, key, item);
}

void ljgap_ans_num(job *j, cJSON *parent, const char *key, double v, const char *label, long idx)
{
    put_num(j, parent, key, v, label, idx);
}

cJSON *ljgap_ans_nums(job *j, cJSON *parent, const char *key, const double *x, size_t n,
                      size_t stride, const char *label)
{
    return put_nums(j, parent, key, x, n, stride, label);
}
