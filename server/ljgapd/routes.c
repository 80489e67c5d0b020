/* routes.c -- the route table and the routes that are not computations or files.
 *
 * One flat table, first match wins, the last row answers 404. A row names its path (exact, or
 * a prefix ending in '/' with a predicate saying whether the rest exists), the methods it
 * allows (anything else is 405 with Allow), whether it reads a JSON body, and the function
 * that answers. /healthz, /version, /openapi.json and /v1/validity answer on the I/O thread at once: they
 * never wait for anything. The simulation job routes call the job store, which may wait (a
 * lock, a disk, a DELETE waiting for a job to stop), so they run on ljgapd_srv.ops (work.c).
 *
 * A row may take a text body besides JSON (text_max > 0): POST /v1/psd takes a height matrix as
 * text/plain or text/csv of up to LJGAP_TEXT_MAX_BYTES with its query (ljgap__handle_text);
 * every other body route keeps JSON and --max-body.
 *
 * Simulations: POST /v1/simulations validates at once (400/422 like every endpoint) and stores
 * the request as a job in the job store (jobstore.h: SQLite in --state-dir, or PostgreSQL
 * with --jobs-db, shared by several daemons; either way jobs survive a restart); 202, with the
 * job's id and its Location, only once the job is committed. Worker threads run the stored requests
 * (jobs.h: --job-workers threads, a queue of --job-queue, 503 with Retry-After when full, or with
 * the problem job-store when the store fails). GET /v1/simulations/ID polls it (status, progress,
 * then result or problem; a done job's result as CSV when Accept asks for text/csv), DELETE cancels
 * it (200 once it has ended, 202 while it is still stopping). /problems/TYPE are the pages the
 * problem types point at.
 *
 * A simulation whose working memory (its n x n grid on --job-threads threads, memest.h, and its
 * result) could never fit the memory budget is refused at submission with 413, whichever store
 * keeps the jobs; a worker reserves it before running the job, waiting while it does not fit.
 */
#include "daemon.h"
#include "jobstatus.h"
#include "ljgap.h"
#include "ljgap_sim.h"
#include "problems.h"
#include "validity/validity.h"

#include <cjson/cJSON.h>
#include <gsl/gsl_version.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>

/* The OpenAPI document, server/openapi.json embedded by the Makefile ($(BUILD)/gen/openapi.c). */
extern const char ljgapd_openapi[];
extern const size_t ljgapd_openapi_len;

/* Alive, and how busy: the compute slots and their queue, the open connections. */
static enum MHD_Result route_healthz(struct MHD_Connection *c, request *r)
{
    pool_stats ps;
    conns_stats cs;
    budget_stats ms, bs;
    char body[400];
    int n;

    pool_get_stats(ljgapd_srv.slots, &ps);
    conns_get_stats(ljgapd_srv.conns, &cs);
    budget_get(ljgapd_srv.mem, &ms);
    budget_get(ljgapd_srv.bodies, &bs);
    n = snprintf(body, sizeof body,
                 "{\"status\":\"pass\",\"compute\":{\"slots\":%u,\"running\":%u,\"waiting\":%u,"
                 "\"queue\":%u},\"connections\":{\"open\":%u,\"limit\":%u},"
                 "\"memory\":{\"limit\":%zu,\"used\":%zu,\"peak\":%zu,\"bodies\":%zu,"
                 "\"bodies_limit\":%zu,\"cache\":%zu}}",
                 ljgapd_srv.cfg.slots, ps.running, ps.waiting, ljgapd_srv.cfg.queue, cs.open,
                 ljgapd_srv.cfg.connections, ms.limit, ms.used, ms.peak, bs.used, bs.limit,
                 ljgapd_srv.pinned);
    return ljgapd_respond_json(c, r, MHD_HTTP_OK, "application/health+json", body, (size_t)n);
}

static enum MHD_Result route_version(struct MHD_Connection *c, request *r)
{
    cJSON *v = cJSON_CreateObject();
    cJSON *libs = NULL;
    char *text = NULL;
    enum MHD_Result ret;

    if (v && cJSON_AddStringToObject(v, "program", "ljgapd") &&
        cJSON_AddStringToObject(v, "version", LJGAP_VERSION) &&
        (libs = cJSON_AddObjectToObject(v, "libraries")) &&
        cJSON_AddStringToObject(libs, "libmicrohttpd", MHD_get_version()) &&
        cJSON_AddStringToObject(libs, "cjson", cJSON_Version()) &&
        cJSON_AddStringToObject(libs, "gsl", gsl_version))
        text = cJSON_PrintUnformatted(v);
    cJSON_Delete(v);
    if (!text)
        return ljgapd_respond_problem(c, r, MHD_HTTP_INTERNAL_SERVER_ERROR, "out of memory", NULL,
                                      NULL);
    ret = ljgapd_respond_json(c, r, MHD_HTTP_OK, "application/json", text, strlen(text));
    cJSON_free(text);
    return ret;
}

/* GET /v1/validity: the validity map (server/api/validity.c), on the I/O thread: no computing. */
static enum MHD_Result route_validity(struct MHD_Connection *c, request *r)
{
    ljgap__reply rep;
    ljgap__validity_reply(&rep);
    return ljgapd_respond_reply(c, r, &rep);
}

static enum MHD_Result route_openapi(struct MHD_Connection *c, request *r)
{
    return ljgapd_respond_json(c, r, MHD_HTTP_OK, "application/json", ljgapd_openapi,
                               ljgapd_openapi_len);
}

/* ---- simulation jobs (on ljgapd_srv.ops) ---- */

#define SIM_PATH "/v1/simulations"

#define SIM_KIND "simulation" /* the job kind of a simulation in the store */

/* A simulation's working memory and its result (memest.h; the result: a few hundred bytes for
 * each of at most LJGAP_SIM_GAPS_MAX gaps). */
static size_t sim_memory(const char *body, size_t len)
{
    return ljgap__memest_sim_request(body, len, ljgapd_srv.cfg.job_threads) + len +
           (size_t)LJGAP_SIM_GAPS_MAX * 1024;
}

/* A stored simulation request, parsed again (so a restarted daemon can run it) and run, once
 * its memory is reserved in the budget (the worker waits for it, polling, while the job may
 * be cancelled; submission refused jobs that could never fit). */
static void sim_job_run(void *ctx, const char *body, size_t len, const ljgap__job_ctl *ctl,
                        ljgap__reply *out)
{
    ljgap__sim_control sc = {(double)ljgapd_srv.cfg.job_seconds, ctl->cancel, ctl->progress,
                            ctl->ctx};
    const struct timespec tick = {0, 50 * 1000 * 1000};
    size_t need = sim_memory(body, len), held = 0;
    ljgap__sim_request *sr;

    if (need <= ljgapd_compute_memory_max())
        while (!(held = budget_try(ljgapd_srv.mem, need) ? need : 0) &&
               !(ctl->cancel && *ctl->cancel))
            nanosleep(&tick, NULL);
    sr = ljgap__sim_request_parse(body, len, out);
    if (sr) ljgap__sim_request_run(sr, &sc, out); /* else the problem is in *out */
    ljgap__sim_request_free(sr);
    budget_release(ljgapd_srv.mem, held);
}

const ljgap__job_kind ljgapd_job_kinds[] = {{SIM_KIND, sim_job_run, NULL}};
const size_t ljgapd_job_nkinds = sizeof ljgapd_job_kinds / sizeof ljgapd_job_kinds[0];

/* Moves a malloc'd JSON string into out as a 2xx answer. */
static void work_json(work_reply *out, int status, char *json)
{
    out->rep.status = status;
    out->rep.body = json;
    out->rep.len = strlen(json);
    out->rep.content_type = "application/json";
}

static void work_oom(work_reply *out)
{
    out->problem = MHD_HTTP_INTERNAL_SERVER_ERROR;
    snprintf(out->detail, sizeof out->detail, "out of memory");
}

/* 503 job-store with Retry-After: the store failed (its reason is logged, not sent). */
static void work_store_failed(work_reply *out)
{
    char *p = ljgap__job_problem(MHD_HTTP_SERVICE_UNAVAILABLE, "job-store", "Job store unavailable",
                                "the job store cannot be read or written just now; retry after "
                                "the given seconds");
    fprintf(stderr, "ljgapd: job store: %s\n", ljgap__jobstore_errmsg());
    if (!p) {
        work_oom(out);
        return;
    }
    out->rep.status = MHD_HTTP_SERVICE_UNAVAILABLE;
    out->rep.body = p;
    out->rep.len = strlen(p);
    out->rep.content_type = "application/problem+json";
    out->header = MHD_HTTP_HEADER_RETRY_AFTER;
    snprintf(out->value, sizeof out->value, "%u", ljgapd_srv.cfg.job_retry);
}

/* POST /v1/simulations: validate, store, 202 with the job's status and its Location. */
static void sim_submit_work(request *r, const volatile int *cancel, work_reply *out)
{
    const char *body = r->body ? r->body : "";
    ljgap__sim_request *sr = ljgap__sim_request_parse(body, r->len, &out->rep);
    char id[LJGAP_JOB_ID_LEN + 1], *status = NULL;

    if (!sr) return;            /* out->rep holds the problem */
    ljgap__sim_request_free(sr); /* valid: the job is its body, parsed again when it runs */
    /* refused now, not when a worker takes it: its working memory (and its result, a few
     * hundred bytes a gap) must fit the budget, whichever store keeps it */
    size_t need = sim_memory(body, r->len), most = ljgapd_compute_memory_max();
    if (need > most) {
        char a[32], b[32], m[32];
        budget_format(need, a, sizeof a);
        budget_format(most, b, sizeof b);
        budget_format(ljgapd_srv.cfg.max_memory, m, sizeof m);
        out->problem = MHD_HTTP_CONTENT_TOO_LARGE;
        snprintf(out->detail, sizeof out->detail,
                 "the simulation needs about %s of memory (its n x n grid on %u thread%s), more "
                 "than the %s a job may hold of this server's memory budget (--max-memory %s): "
                 "use a smaller n",
                 a, ljgapd_srv.cfg.job_threads, ljgapd_srv.cfg.job_threads == 1 ? "" : "s", b, m);
        return;
    }
    switch (ljgap__jobs_submit(ljgapd_srv.jobs, SIM_KIND, body, r->len, id)) {
    case LJGAP_JOBS_OK:
        break;
    case LJGAP_JOBS_FULL:
        out->problem = MHD_HTTP_SERVICE_UNAVAILABLE;
        snprintf(out->detail, sizeof out->detail,
                 "the simulation queue is full (%u jobs waiting); retry after the given seconds",
                 ljgapd_srv.cfg.jobs.queue_cap);
        out->header = MHD_HTTP_HEADER_RETRY_AFTER;
        snprintf(out->value, sizeof out->value, "%u", ljgapd_srv.cfg.job_retry);
        return;
    case LJGAP_JOBS_STOPPING:
        out->problem = MHD_HTTP_SERVICE_UNAVAILABLE;
        snprintf(out->detail, sizeof out->detail,
                 "the server is shutting down and takes no new jobs");
        out->header = MHD_HTTP_HEADER_RETRY_AFTER;
        snprintf(out->value, sizeof out->value, "%u", ljgapd_srv.cfg.retry_after);
        return;
    case LJGAP_JOBS_STORE:
        work_store_failed(out);
        return;
    default:
        work_oom(out);
        return;
    }
    /* a job just stored is not evicted (only finished ones are) */
    switch (ljgap__jobs_status(ljgapd_srv.jobs, id, &status)) {
    case LJGAP_JOBS_OK:
        break;
    case LJGAP_JOBS_NOMEM:
        work_oom(out);
        return;
    default:
        work_store_failed(out);
        return;
    }
    work_json(out, MHD_HTTP_ACCEPTED, status);
    out->header = MHD_HTTP_HEADER_LOCATION;
    snprintf(out->value, sizeof out->value, SIM_PATH "/%s", id);
}

static enum MHD_Result route_sim_submit(struct MHD_Connection *c, request *r)
{
    return ljgapd_route_offload(c, r, ljgapd_srv.ops, sim_submit_work, NULL, 0);
}

/* Any one path segment may name a job; unknown ones are answered 404. */
static int sim_id_exists(const char *rest)
{
    return rest[0] && !strchr(rest, '/');
}

/* GET (or HEAD) /v1/simulations/ID: its status; DELETE: cancel it. */
static void sim_job_work(request *r, const volatile int *cancel, work_reply *out)
{
    const char *id = r->url + strlen(SIM_PATH "/");
    char *status = NULL;
    int final = 1, st;

    if (strcmp(r->method, "DELETE") == 0)
        st = ljgap__jobs_cancel(ljgapd_srv.jobs, id, ljgapd_srv.cfg.cancel_wait_s, &status, &final);
    else
        st = ljgap__jobs_status(ljgapd_srv.jobs, id, &status);
    if (st == LJGAP_JOBS_UNKNOWN) {
        out->problem = MHD_HTTP_NOT_FOUND;
        snprintf(out->detail, sizeof out->detail,
                 "no simulation job with this id: it never existed, or it finished more than "
                 "%.0f s ago or before the last %u finished jobs",
                 ljgapd_srv.cfg.jobs.keep_seconds, ljgapd_srv.cfg.jobs.keep_done);
        return;
    }
    if (st == LJGAP_JOBS_STORE) {
        work_store_failed(out);
        return;
    }
    if (st != LJGAP_JOBS_OK) {
        work_oom(out);
        return;
    }
    if (strcmp(r->method, "DELETE") == 0) {
        work_json(out, final ? MHD_HTTP_OK : MHD_HTTP_ACCEPTED, status);
        return;
    }
    /* JSON, or a done job's result as CSV, as Accept asks (406 when neither will do) */
    ljgap__sim_status_answer(status, MHD_HTTP_OK, r->accept, &out->rep);
    free(status);
}

static enum MHD_Result route_sim_job(struct MHD_Connection *c, request *r)
{
    if (!r->task)
        r->accept = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_ACCEPT);
    return ljgapd_route_offload(c, r, ljgapd_srv.ops, sim_job_work, NULL, 0);
}

/* GET /problems/TYPE: what a problem type means and how to fix the request; /problems/: all. */
static int problems_exists(const char *rest)
{
    return !strchr(rest, '/');
}

static enum MHD_Result route_problems(struct MHD_Connection *c, request *r)
{
    ljgap__reply rep;
    ljgap__problem_page(r->url + strlen(LJGAP_PROBLEM_BASE), &rep);
    return ljgapd_respond_reply(c, r, &rep);
}

static enum MHD_Result route_not_found(struct MHD_Connection *c, request *r)
{
    return ljgapd_respond_problem(c, r, MHD_HTTP_NOT_FOUND, "no such endpoint; see /openapi.json",
                                  NULL, NULL);
}

/* First match wins; the last row matches everything. */
static const struct route routes[] = {
    {"/healthz", NULL, "GET, HEAD", 0, route_healthz, 0},
    {"/version", NULL, "GET, HEAD", 0, route_version, 0},
    {"/openapi.json", NULL, "GET, HEAD", 0, route_openapi, 0},
    {SIM_PATH, NULL, "POST", 1, route_sim_submit, 0},
    {SIM_PATH "/", sim_id_exists, "GET, HEAD, DELETE", 0, route_sim_job, 0},
    {"/v1/psd", NULL, "POST", 1, ljgapd_route_psd, LJGAP_TEXT_MAX_BYTES},
    {"/v1/validity", NULL, "GET, HEAD", 0, route_validity, 0},
    {"/v1/", ljgapd_compute_exists, "POST", 1, ljgapd_route_compute, 0},
    {LJGAP_PROBLEM_BASE, problems_exists, "GET, HEAD", 0, route_problems, 0},
    {"/", ljgapd_static_exists, "GET, HEAD", 0, ljgapd_route_static, 0},
    {NULL, NULL, NULL, 0, route_not_found, 0},
};

const struct route *ljgapd_route_find(const char *url)
{
    const struct route *rt = routes;
    for (; rt->path; rt++) {
        size_t n = strlen(rt->path);
        if (rt->path[n - 1] == '/') {
            if (strncmp(url, rt->path, n) == 0 && rt->exists(url + n)) return rt;
        } else if (strcmp(url, rt->path) == 0) {
            return rt;
        }
    }
    return rt;
}
