/* ljgapd.c -- the ljgap HTTP daemon: libmicrohttpd 0.9.75 in front of ljgap_handle().
 *
 * The daemon is a thin shell. Everything that knows physics or JSON fields lives in the request
 * handler (handler.h); this file only moves bytes between sockets and that pure function, and
 * adds what a shared lab server needs around it:
 *
 *   - routing: one flat table, first match wins, the last row answers 404. A row names its path
 *     (exact, or a prefix ending in '/' with a predicate saying whether the rest exists), the
 *     methods it allows (anything else is 405 with Allow) and the function that answers.
 *   - bodies: compute requests must say Content-Type: application/json (else 415) and carry at
 *     most 1 MiB (413, decided from Content-Length before reading, or while reading a chunked
 *     body, when the buffer would grow past the limit).
 *   - threads: libmicrohttpd runs one thread per connection, so a long computation blocks only
 *     its own connection; /healthz, /version, /openapi.json and static files are never queued
 *     behind it. The number of connections (hence threads) is capped by --threads; idle
 *     connections are closed after a timeout.
 *   - compute slots: a counter caps concurrent computations at --compute-slots (default: the
 *     number of cores). A compute request that finds every slot busy is answered at once with
 *     503 and Retry-After rather than queued: the client knows best whether to wait.
 *   - cache: identical requests (same endpoint, same body bytes) that were answered 2xx are
 *     answered from a bounded LRU cache (http_cache.h) with meta.cached set to true, without
 *     taking a slot.
 *   - problems: every 4xx/5xx is RFC 9457 application/problem+json; the handler writes its own
 *     (400, 404, 422), this file writes the HTTP-level ones through respond_problem().
 *   - logging: one line per request on stderr (method, path, status, milliseconds, request id),
 *     written when libmicrohttpd reports the request complete. X-Request-Id is echoed when the
 *     client sends a sane one, otherwise made up, and is returned on every answer.
 *   - simulations: POST /v1/simulations validates at once (400/422 like every endpoint) and
 *     queues a numerical-model run in the job store (jobs.h: --job-workers threads, a queue of
 *     --job-queue, 503 with Retry-After when full); 202 gives the job's id and its Location.
 *     GET /v1/simulations/ID polls it (status, progress, then result or problem), DELETE
 *     cancels it (200 once it has ended, 202 while it is still stopping). Job workers do not
 *     take compute slots: they are threads of their own, so size --compute-slots and
 *     --job-workers together to the cores.
 *   - shutdown: SIGINT/SIGTERM are taken by sigwait() in main. The daemon stops accepting
 *     (MHD_quiesce_daemon), lets in-flight requests finish for a grace period, then raises the
 *     handler's cancel flag so long computations return early, and stops the daemon, all within
 *     10 s; then it frees everything and exits 0.
 *
 * No route builds a response by hand: respond_json, respond_problem and respond_file are the
 * only callers of respond(), which adds the common headers and queues the answer.
 */
#include "handler.h"
#include "http_cache.h"
#include "jobs.h"
#include "ljgap.h"

#include <arpa/inet.h>
#include <cjson/cJSON.h>
#include <errno.h>
#include <fcntl.h>
#include <fftw3.h>
#include <getopt.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_version.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* The OpenAPI document, server/openapi.json embedded by the Makefile ($(BUILD)/gen/openapi.c). */
extern const char ljgapd_openapi[];
extern const size_t ljgapd_openapi_len;

/* ---- configuration ---- */

typedef struct {
    unsigned port;          /* TCP port; 0 lets the kernel pick one (default 8080) */
    const char *bind;       /* numeric IPv4 or IPv6 address to listen on (default 127.0.0.1) */
    const char *web;        /* directory of static files, NULL serves none (default NULL) */
    unsigned threads;       /* connection limit = connection threads (default max(64, slots+16)) */
    unsigned slots;         /* concurrent computations (default: online cores) */
    unsigned timeout_s;     /* idle connection timeout in seconds (default 30) */
    size_t max_body;        /* largest accepted request body in bytes (default 1 MiB) */
    size_t cache_entries;   /* cache bound in entries (default 1024) */
    size_t cache_bytes;     /* cache bound in bytes (default 64 MiB) */
    unsigned retry_after;   /* Retry-After seconds on 503 (default 1) */
    double grace_s;         /* shutdown: seconds in-flight work may run before cancel (default 7) */
    double stop_s;          /* shutdown: seconds after the signal at which we stop (default 9.5) */
    ljgap_jobs_config jobs; /* simulation jobs: workers, queue, finished jobs kept (jobs.h) */
    unsigned job_seconds;   /* wall-time cap of one simulation (default 600) */
    unsigned job_retry;     /* Retry-After seconds when the job queue is full (default 10) */
    double cancel_wait_s;   /* DELETE waits this long for a running job to stop (default 2) */
} ljgapd_config;

/* ---- server state shared by all connection threads ---- */

static ljgapd_config cfg;
static http_cache *cache;        /* answers of earlier identical requests */
static ljgap_jobs *jobs;         /* simulation jobs */
static int web_fd = -1;          /* open directory cfg.web, or -1 */
static atomic_uint busy_slots;   /* computations running now */
static atomic_uint inflight;     /* requests begun and not yet reported complete */
static atomic_int stopping;      /* set once a signal asked us to stop */
static volatile int cancel_flag; /* the handler's ljgap_limits.cancel */
static unsigned id_seed;         /* random per process: made-up request ids differ per run */
static atomic_ulong id_counter;  /* made-up request ids are seed + counter */

#define REQUEST_ID_MAX 64 /* longest X-Request-Id echoed */
#define LOG_PATH_MAX 200  /* longest path written to the log */
#define FILE_NAME_MAX 128 /* longest static file name */
#define DISCARD_FACTOR 16 /* close a connection sending more than this times the body limit */
#define PROBLEM_BASE "https://ljgap.example/problems/" /* as in handler.c */

/* ---- one request ---- */

struct route;

typedef struct {
    struct timespec t0;          /* when the request line arrived */
    const struct route *route;   /* the row that answers, set on the first call */
    char method[16];             /* request method, for the log */
    char path[LOG_PATH_MAX + 1]; /* path with control characters replaced, for the log */
    const char *url;             /* the path as libmicrohttpd gave it (valid during the request) */
    char id[REQUEST_ID_MAX + 1]; /* request id: echoed or made up */
    int status;                  /* status queued, 0 until then */
    char *body;                  /* request body received so far (compute routes) */
    size_t len;                  /* bytes in body */
    size_t cap;                  /* bytes allocated for body */
    int too_large;               /* the body outgrew cfg.max_body: answer 413 */
    size_t discarded;            /* body bytes dropped since (or after an early answer) */
} request;

typedef enum MHD_Result (*route_fn)(struct MHD_Connection *c, request *r);

struct route {
    const char *path;                /* exact path, or a prefix if it ends in '/' */
    int (*exists)(const char *rest); /* for a prefix: does the rest name something? */
    const char *allow;               /* allowed methods, the Allow header of a 405 */
    int takes_body;                  /* read a JSON body before answering */
    route_fn answer;                 /* writes the response */
};

static double seconds_since(const struct timespec *t0)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)(t.tv_sec - t0->tv_sec) + 1e-9 * (double)(t.tv_nsec - t0->tv_nsec);
}

/* ---- reply helpers: the only code that creates responses ---- */

/* Adds the common headers, queues resp and records the status. Takes ownership of resp. */
static enum MHD_Result respond(struct MHD_Connection *c, request *r, int status,
                               struct MHD_Response *resp, const char *ctype)
{
    enum MHD_Result ret;

    if (!resp) return MHD_NO; /* out of memory: drop the connection, nothing else can be sent */
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, ctype);
    MHD_add_response_header(resp, "X-Request-Id", r->id);
    MHD_add_response_header(resp, "X-Content-Type-Options", "nosniff");
    /* The page loads nothing from elsewhere and runs no inline code (issue 5). */
    MHD_add_response_header(resp, "Content-Security-Policy", "default-src 'self'");
    if (atomic_load(&stopping)) MHD_add_response_header(resp, MHD_HTTP_HEADER_CONNECTION, "close");
    ret = MHD_queue_response(c, (unsigned)status, resp);
    MHD_destroy_response(resp);
    if (ret == MHD_YES) r->status = status;
    return ret;
}

/* Answer status with a copy of body (JSON or problem+json, as ctype says) and, when header is
 * not NULL, one extra header (Location). */
static enum MHD_Result respond_json_hdr(struct MHD_Connection *c, request *r, int status,
                                        const char *ctype, const char *body, size_t len,
                                        const char *header, const char *value)
{
    struct MHD_Response *resp =
        MHD_create_response_from_buffer(len, (void *)body, MHD_RESPMEM_MUST_COPY);
    if (resp && header) MHD_add_response_header(resp, header, value);
    return respond(c, r, status, resp, ctype);
}

static enum MHD_Result respond_json(struct MHD_Connection *c, request *r, int status,
                                    const char *ctype, const char *body, size_t len)
{
    return respond_json_hdr(c, r, status, ctype, body, len, NULL, NULL);
}

/* Problem types of the answers written here (the handler writes its own, same base URI;
 * openapi.json lists them all). */
static const char *problem_type(int status)
{
    switch (status) {
    case MHD_HTTP_NOT_FOUND:
        return PROBLEM_BASE "not-found";
    case MHD_HTTP_METHOD_NOT_ALLOWED:
        return PROBLEM_BASE "method-not-allowed";
    case MHD_HTTP_CONTENT_TOO_LARGE:
        return PROBLEM_BASE "content-too-large";
    case MHD_HTTP_UNSUPPORTED_MEDIA_TYPE:
        return PROBLEM_BASE "unsupported-media-type";
    case MHD_HTTP_SERVICE_UNAVAILABLE:
        return PROBLEM_BASE "busy";
    default:
        return PROBLEM_BASE "out-of-memory";
    }
}

/* Answer an RFC 9457 problem. header/value, if not NULL, is one extra header (Allow,
 * Retry-After). */
static enum MHD_Result respond_problem(struct MHD_Connection *c, request *r, int status,
                                       const char *detail, const char *header, const char *value)
{
    const char *title = MHD_get_reason_phrase_for((unsigned)status);
    cJSON *p = cJSON_CreateObject();
    char *text = NULL;
    struct MHD_Response *resp = NULL;

    if (p && cJSON_AddStringToObject(p, "type", problem_type(status)) &&
        cJSON_AddStringToObject(p, "title", title) &&
        cJSON_AddNumberToObject(p, "status", status) &&
        cJSON_AddStringToObject(p, "detail", detail) &&
        cJSON_AddStringToObject(p, "instance", r->path) && cJSON_AddArrayToObject(p, "errors"))
        text = cJSON_PrintUnformatted(p);
    cJSON_Delete(p);
    if (text) resp = MHD_create_response_from_buffer(strlen(text), text, MHD_RESPMEM_MUST_COPY);
    cJSON_free(text);
    if (resp && header) MHD_add_response_header(resp, header, value);
    return respond(c, r, status, resp, "application/problem+json");
}

/* Answer 200 with the file open on fd (size bytes); fd is closed with the response. */
static enum MHD_Result respond_file(struct MHD_Connection *c, request *r, int fd, size_t size,
                                    const char *ctype)
{
    struct MHD_Response *resp = MHD_create_response_from_fd(size, fd);
    if (!resp) close(fd);
    return respond(c, r, MHD_HTTP_OK, resp, ctype);
}

/* 413: the request body is over cfg.max_body. */
static enum MHD_Result respond_too_large(struct MHD_Connection *c, request *r)
{
    char detail[64];
    snprintf(detail, sizeof detail, "the request body is limited to %zu bytes", cfg.max_body);
    return respond_problem(c, r, MHD_HTTP_CONTENT_TOO_LARGE, detail, NULL, NULL);
}

/* ---- routes ---- */

static enum MHD_Result route_healthz(struct MHD_Connection *c, request *r)
{
    static const char ok[] = "{\"status\":\"pass\"}";
    return respond_json(c, r, MHD_HTTP_OK, "application/health+json", ok, sizeof ok - 1);
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
        return respond_problem(c, r, MHD_HTTP_INTERNAL_SERVER_ERROR, "out of memory", NULL, NULL);
    ret = respond_json(c, r, MHD_HTTP_OK, "application/json", text, strlen(text));
    cJSON_free(text);
    return ret;
}

static enum MHD_Result route_openapi(struct MHD_Connection *c, request *r)
{
    return respond_json(c, r, MHD_HTTP_OK, "application/json", ljgapd_openapi, ljgapd_openapi_len);
}

/* Atomically take a compute slot if one is free. */
static int slot_take(void)
{
    unsigned n = atomic_load(&busy_slots);
    do {
        if (n >= cfg.slots) return 0;
    } while (!atomic_compare_exchange_weak(&busy_slots, &n, n + 1));
    return 1;
}

/* Store a 2xx answer under key, with meta.cached set to true so hits can be sent as stored. */
static void cache_store(const char *key, size_t klen, const ljgap_reply *rep)
{
    cJSON *root = cJSON_ParseWithLength(rep->body, rep->len);
    cJSON *meta = cJSON_GetObjectItemCaseSensitive(root, "meta");
    cJSON *yes = NULL;
    char *text = NULL;

    if (!cJSON_IsObject(meta)) goto end;
    yes = cJSON_CreateTrue();
    if (!yes) goto end;
    if (cJSON_HasObjectItem(meta, "cached"))
        cJSON_ReplaceItemInObjectCaseSensitive(meta, "cached", yes);
    else
        cJSON_AddItemToObject(meta, "cached", yes);
    text = cJSON_PrintUnformatted(root);
    if (text) http_cache_put(cache, key, klen, rep->status, text, strlen(text));
end:
    cJSON_free(text);
    cJSON_Delete(root);
}

/* POST /v1/NAME: cache, then a compute slot, then the handler. */
static enum MHD_Result route_compute(struct MHD_Connection *c, request *r)
{
    const char *endpoint = r->url + strlen("/v1/");
    size_t elen = strlen(endpoint);
    size_t klen = elen + 1 + r->len;
    char *key = malloc(klen);
    char *hit = NULL;
    size_t hitlen = 0;
    int status = 0;
    ljgap_reply rep = {0};
    enum MHD_Result ret;

    if (!key)
        return respond_problem(c, r, MHD_HTTP_INTERNAL_SERVER_ERROR, "out of memory", NULL, NULL);
    memcpy(key, endpoint, elen + 1); /* endpoint, NUL, body bytes */
    if (r->len) memcpy(key + elen + 1, r->body, r->len);

    if (http_cache_get(cache, key, klen, &status, &hit, &hitlen) == 1) {
        ret = respond_json(c, r, status, "application/json", hit, hitlen);
        free(hit);
        free(key);
        return ret;
    }
    if (!slot_take()) {
        char retry[16];
        free(key);
        snprintf(retry, sizeof retry, "%u", cfg.retry_after);
        return respond_problem(c, r, MHD_HTTP_SERVICE_UNAVAILABLE,
                               "every compute slot is busy; retry after the given seconds",
                               MHD_HTTP_HEADER_RETRY_AFTER, retry);
    }
    ljgap_handle(endpoint, r->body ? r->body : "", r->len, &rep);
    atomic_fetch_sub(&busy_slots, 1);
    if (rep.status >= 200 && rep.status < 300) cache_store(key, klen, &rep);
    free(key);
    ret = respond_json(c, r, rep.status, rep.content_type, rep.body, rep.len);
    ljgap_reply_free(&rep);
    return ret;
}

static int compute_exists(const char *rest)
{
    return ljgap_handler_has(rest);
}

/* ---- simulation jobs ---- */

#define SIM_PATH "/v1/simulations"

static void sim_job_run(void *arg, const ljgap_job_ctl *ctl, ljgap_reply *out)
{
    ljgap_sim_control sc = {(double)cfg.job_seconds, ctl->cancel, ctl->progress, ctl->ctx};
    ljgap_sim_request_run(arg, &sc, out);
}

static void sim_job_free(void *arg)
{
    ljgap_sim_request_free(arg);
}

/* Answers a ljgap_reply and frees it. */
static enum MHD_Result respond_reply(struct MHD_Connection *c, request *r, ljgap_reply *rep)
{
    enum MHD_Result ret = respond_json(c, r, rep->status, rep->content_type, rep->body, rep->len);
    ljgap_reply_free(rep);
    return ret;
}

/* POST /v1/simulations: validate, queue, 202 with the job's status and its Location. */
static enum MHD_Result route_sim_submit(struct MHD_Connection *c, request *r)
{
    ljgap_reply rep = {0};
    ljgap_sim_request *sr = ljgap_sim_request_parse(r->body ? r->body : "", r->len, &rep);
    char id[LJGAP_JOB_ID_LEN + 1], where[sizeof SIM_PATH + LJGAP_JOB_ID_LEN + 1], detail[120];
    char retry[16], *status = NULL;
    enum MHD_Result ret;

    if (!sr) return respond_reply(c, r, &rep);
    switch (ljgap_jobs_submit(jobs, sim_job_run, sr, sim_job_free, id)) {
    case LJGAP_JOBS_OK:
        break;
    case LJGAP_JOBS_FULL:
        snprintf(retry, sizeof retry, "%u", cfg.job_retry);
        snprintf(detail, sizeof detail,
                 "the simulation queue is full (%u jobs waiting); retry after the given seconds",
                 cfg.jobs.queue_cap);
        return respond_problem(c, r, MHD_HTTP_SERVICE_UNAVAILABLE, detail,
                               MHD_HTTP_HEADER_RETRY_AFTER, retry);
    case LJGAP_JOBS_STOPPING:
        return respond_problem(c, r, MHD_HTTP_SERVICE_UNAVAILABLE,
                               "the server is shutting down and takes no new jobs", NULL, NULL);
    default:
        return respond_problem(c, r, MHD_HTTP_INTERNAL_SERVER_ERROR, "out of memory", NULL, NULL);
    }
    /* a job just queued is not evicted (only finished ones are, and keep_done >= 1) */
    if (ljgap_jobs_status(jobs, id, &status) != LJGAP_JOBS_OK)
        return respond_problem(c, r, MHD_HTTP_INTERNAL_SERVER_ERROR, "out of memory", NULL, NULL);
    snprintf(where, sizeof where, SIM_PATH "/%s", id);
    ret = respond_json_hdr(c, r, MHD_HTTP_ACCEPTED, "application/json", status, strlen(status),
                           MHD_HTTP_HEADER_LOCATION, where);
    free(status);
    return ret;
}

/* Any one path segment may name a job; unknown ones are answered 404 by route_sim_job. */
static int sim_id_exists(const char *rest)
{
    return rest[0] && !strchr(rest, '/');
}

/* GET (or HEAD) /v1/simulations/ID: its status; DELETE: cancel it. */
static enum MHD_Result route_sim_job(struct MHD_Connection *c, request *r)
{
    const char *id = r->url + strlen(SIM_PATH "/");
    char *status = NULL, detail[200];
    int final = 1, st;
    enum MHD_Result ret;

    if (strcmp(r->method, "DELETE") == 0)
        st = ljgap_jobs_cancel(jobs, id, cfg.cancel_wait_s, &status, &final);
    else
        st = ljgap_jobs_status(jobs, id, &status);
    if (st == LJGAP_JOBS_UNKNOWN) {
        snprintf(detail, sizeof detail,
                 "no simulation job with this id: it never existed, or it finished more than "
                 "%.0f s ago or before the last %u finished jobs",
                 cfg.jobs.keep_seconds, cfg.jobs.keep_done);
        return respond_problem(c, r, MHD_HTTP_NOT_FOUND, detail, NULL, NULL);
    }
    if (st != LJGAP_JOBS_OK)
        return respond_problem(c, r, MHD_HTTP_INTERNAL_SERVER_ERROR, "out of memory", NULL, NULL);
    ret = respond_json(c, r, final ? MHD_HTTP_OK : MHD_HTTP_ACCEPTED, "application/json", status,
                       strlen(status));
    free(status);
    return ret;
}

/* The Content-Type of an allowlisted static file name (relative to web/), or NULL.
 * Allowed: index.html, and NAME.{js,css,png,svg,json} at the top or in vendor/, where NAME is
 * letters, digits, '.', '_' and '-' not starting with '.'. So nothing can climb out of web/. */
static const char *static_type(const char *rel)
{
    static const struct {
        const char *ext;
        const char *type;
    } types[] = {
        {".js", "text/javascript; charset=utf-8"},
        {".css", "text/css; charset=utf-8"},
        {".png", "image/png"},
        {".svg", "image/svg+xml"},
        {".json", "application/json"},
    };
    const char *name = rel;
    size_t n;

    if (strcmp(rel, "index.html") == 0) return "text/html; charset=utf-8";
    if (strncmp(name, "vendor/", 7) == 0) name += 7;
    n = strlen(name);
    if (n == 0 || n > FILE_NAME_MAX || name[0] == '.') return NULL;
    if (strspn(name, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-") != n)
        return NULL;
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++) {
        size_t e = strlen(types[i].ext);
        if (n > e && strcmp(name + n - e, types[i].ext) == 0) return types[i].type;
    }
    return NULL;
}

static const char *static_rel(const char *rest)
{
    return rest[0] ? rest : "index.html";
}

static int static_exists(const char *rest)
{
    return static_type(static_rel(rest)) != NULL;
}

/* GET an allowlisted file from web/. */
static enum MHD_Result route_static(struct MHD_Connection *c, request *r)
{
    const char *rel = static_rel(r->url + 1);
    const char *ctype = static_type(rel);
    struct stat st;
    int fd = -1;

    if (web_fd >= 0) fd = openat(web_fd, rel, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return respond_problem(c, r, MHD_HTTP_NOT_FOUND, "no such page", NULL, NULL);
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return respond_problem(c, r, MHD_HTTP_NOT_FOUND, "no such page", NULL, NULL);
    }
    return respond_file(c, r, fd, (size_t)st.st_size, ctype);
}

static enum MHD_Result route_not_found(struct MHD_Connection *c, request *r)
{
    return respond_problem(c, r, MHD_HTTP_NOT_FOUND, "no such endpoint; see /openapi.json", NULL,
                           NULL);
}

/* First match wins; the last row matches everything. */
static const struct route routes[] = {
    {"/healthz", NULL, "GET, HEAD", 0, route_healthz},
    {"/version", NULL, "GET, HEAD", 0, route_version},
    {"/openapi.json", NULL, "GET, HEAD", 0, route_openapi},
    {SIM_PATH, NULL, "POST", 1, route_sim_submit},
    {SIM_PATH "/", sim_id_exists, "GET, HEAD, DELETE", 0, route_sim_job},
    {"/v1/", compute_exists, "POST", 1, route_compute},
    {"/", static_exists, "GET, HEAD", 0, route_static},
    {NULL, NULL, NULL, 0, route_not_found},
};

static const struct route *route_find(const char *url)
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

/* Is method one of the comma-separated tokens in allow? */
static int method_allowed(const char *allow, const char *method)
{
    size_t n = strlen(method);
    for (const char *p = allow; *p;) {
        size_t t = strcspn(p, ",");
        if (t == n && strncmp(p, method, n) == 0) return 1;
        p += t;
        p += strspn(p, ", ");
    }
    return 0;
}

/* Is the Content-Type application/json or application/...+json (parameters allowed)? */
static int is_json_type(const char *ct)
{
    size_t n;
    if (!ct) return 0;
    ct += strspn(ct, " \t");
    n = strcspn(ct, "; \t");
    if (n == 16 && strncasecmp(ct, "application/json", 16) == 0) return 1;
    return n > 17 && strncasecmp(ct, "application/", 12) == 0 &&
           strncasecmp(ct + n - 5, "+json", 5) == 0;
}

/* ---- request life cycle ---- */

/* Copy s into dst (size dstsz), replacing bytes outside printable ASCII with '?'. */
static void copy_printable(char *dst, size_t dstsz, const char *s)
{
    size_t i = 0;
    for (; s[i] && i + 1 < dstsz; i++)
        dst[i] = (s[i] > ' ' && s[i] < 0x7f) ? s[i] : '?';
    dst[i] = '\0';
}

static request *request_new(struct MHD_Connection *c, const char *url, const char *method)
{
    const char *rid = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "X-Request-Id");
    request *r = calloc(1, sizeof *r);

    if (!r) return NULL;
    clock_gettime(CLOCK_MONOTONIC, &r->t0);
    r->url = url;
    copy_printable(r->method, sizeof r->method, method);
    copy_printable(r->path, sizeof r->path, url);
    if (rid && rid[0] && strlen(rid) <= REQUEST_ID_MAX &&
        strspn(rid, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._:-") ==
            strlen(rid))
        strcpy(r->id, rid);
    else
        snprintf(r->id, sizeof r->id, "%08x%08lx", id_seed,
                 (unsigned long)atomic_fetch_add(&id_counter, 1) + 1);
    return r;
}

/* The first call of a request: route it and refuse what can be refused before any body. */
static enum MHD_Result request_begin(struct MHD_Connection *c, request *r, const char *method)
{
    const char *clen, *ctype;
    unsigned long long want = 0;
    char detail[64];

    r->route = route_find(r->url);
    if (!r->route->path) return r->route->answer(c, r);
    if (!method_allowed(r->route->allow, method)) {
        snprintf(detail, sizeof detail, "use %s", r->route->allow);
        return respond_problem(c, r, MHD_HTTP_METHOD_NOT_ALLOWED, detail, MHD_HTTP_HEADER_ALLOW,
                               r->route->allow);
    }
    if (!r->route->takes_body) return r->route->answer(c, r);

    clen = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH);
    if (clen) want = strtoull(clen, NULL, 10);
    if (want > cfg.max_body) return respond_too_large(c, r);
    ctype = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE);
    if (!is_json_type(ctype))
        return respond_problem(c, r, MHD_HTTP_UNSUPPORTED_MEDIA_TYPE,
                               "send the request as Content-Type: application/json", NULL, NULL);
    if (want) {
        r->body = malloc(want + 1);
        if (!r->body) return MHD_NO;
        r->cap = want + 1;
    }
    return MHD_YES;
}

/* Append a chunk of body. A body that outgrows cfg.max_body is freed and the rest counted
 * and dropped (libmicrohttpd 0.9.75 cannot queue an answer while a body is arriving, so the
 * 413 goes out when the body ends); -1 (close the connection) if memory runs out or the client
 * goes on sending past DISCARD_FACTOR times the limit. */
static int request_take(request *r, const char *data, size_t n)
{
    if (!r->too_large && !r->status && r->len + n > cfg.max_body) {
        r->too_large = 1;
        free(r->body);
        r->body = NULL;
        r->discarded = r->len;
        r->len = r->cap = 0;
    }
    if (r->too_large || r->status) {
        r->discarded += n;
        return r->discarded > DISCARD_FACTOR * cfg.max_body ? -1 : 0;
    }
    if (r->len + n + 1 > r->cap) {
        size_t cap = r->cap ? r->cap : 4096;
        char *b;
        while (cap < r->len + n + 1)
            cap *= 2;
        if (cap > cfg.max_body + 1) cap = cfg.max_body + 1;
        b = realloc(r->body, cap);
        if (!b) return -1;
        r->body = b;
        r->cap = cap;
    }
    memcpy(r->body + r->len, data, n);
    r->len += n;
    r->body[r->len] = '\0';
    return 0;
}

static enum MHD_Result on_access(void *cls, struct MHD_Connection *c, const char *url,
                                 const char *method, const char *version, const char *upload_data,
                                 size_t *upload_data_size, void **con_cls)
{
    request *r = *con_cls;

    if (!r) {
        r = request_new(c, url, method);
        if (!r) return MHD_NO;
        *con_cls = r;
        atomic_fetch_add(&inflight, 1);
        return request_begin(c, r, method);
    }
    r->url = url; /* the same string on every call; kept current to be safe */
    if (*upload_data_size) {
        size_t n = *upload_data_size;
        *upload_data_size = 0;
        return request_take(r, upload_data, n) == 0 ? MHD_YES : MHD_NO;
    }
    if (r->status) return MHD_YES;
    if (r->too_large) return respond_too_large(c, r);
    return r->route->answer(c, r);
}

static void on_completed(void *cls, struct MHD_Connection *c, void **con_cls,
                         enum MHD_RequestTerminationCode toe)
{
    request *r = *con_cls;

    if (!r) return;
    fprintf(stderr, "%s %s %d %.1fms id=%s%s\n", r->method, r->path, r->status,
            1e3 * seconds_since(&r->t0), r->id,
            toe == MHD_REQUEST_TERMINATED_COMPLETED_OK ? "" : " (connection closed early)");
    free(r->body);
    free(r);
    *con_cls = NULL;
    atomic_fetch_sub(&inflight, 1);
}

/* ---- start-up and shutdown ---- */

static void usage(FILE *f)
{
    fprintf(
        f, "usage: ljgapd [--port N] [--bind ADDR] [--web DIR] [--threads N] "
           "[--compute-slots N]\n"
           "Serves the ljgap calculations over HTTP (see /openapi.json).\n"
           "  --port N           TCP port; 0 picks a free one (default 8080)\n"
           "  --bind ADDR        numeric IPv4/IPv6 address to listen on (default 127.0.0.1)\n"
           "  --web DIR          serve the page and its assets from DIR (default: none)\n"
           "  --threads N        most simultaneous connections; each connection has its own\n"
           "                     thread, so this also bounds the threads (default max(64,\n"
           "                     slots+16); must exceed --compute-slots so /healthz and static\n"
           "                     files always find a thread)\n"
           "  --compute-slots N  most computations at once; more get 503 + Retry-After\n"
           "                     (default: number of cores)\n"
           "  --job-workers N    simulation jobs running at once, each on its own thread\n"
           "                     (default 1)\n"
           "  --job-queue N      simulation jobs waiting; more get 503 + Retry-After (default 8)\n"
           "  --job-keep N       finished jobs kept for polling, for at most an hour (default 64)\n"
           "  --job-seconds N    wall-time cap of one simulation (default 600)\n"
           "The first line on stdout is 'listening on http://HOST:PORT/'; one log line per\n"
           "request goes to stderr. SIGINT/SIGTERM stop it within 10 s.\n");
}

static int parse_uint(const char *s, unsigned lo, unsigned hi, unsigned *out)
{
    char *end = NULL;
    unsigned long v;
    errno = 0;
    v = strtoul(s, &end, 10);
    if (errno || end == s || *end || s[0] == '-' || v < lo || v > hi) return -1;
    *out = (unsigned)v;
    return 0;
}

static int parse_args(int argc, char **argv)
{
    static const struct option opts[] = {
        {"port", required_argument, NULL, 'p'},
        {"bind", required_argument, NULL, 'b'},
        {"web", required_argument, NULL, 'w'},
        {"threads", required_argument, NULL, 't'},
        {"compute-slots", required_argument, NULL, 's'},
        {"job-workers", required_argument, NULL, 'W'},
        {"job-queue", required_argument, NULL, 'Q'},
        {"job-keep", required_argument, NULL, 'K'},
        {"job-seconds", required_argument, NULL, 'S'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    unsigned threads = 0;
    int o;

    cfg.port = 8080;
    cfg.bind = "127.0.0.1";
    cfg.slots = cores > 0 ? (unsigned)cores : 1;
    cfg.timeout_s = 30;
    cfg.max_body = (size_t)1 << 20;
    cfg.cache_entries = 1024;
    cfg.cache_bytes = (size_t)64 << 20;
    cfg.retry_after = 1;
    cfg.grace_s = 7.0;
    cfg.stop_s = 9.5;
    ljgap_jobs_config_default(&cfg.jobs);
    cfg.job_seconds = 600;
    cfg.job_retry = 10;
    cfg.cancel_wait_s = 2.0;
    while ((o = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
        int bad = 0;
        switch (o) {
        case 'p':
            bad = parse_uint(optarg, 0, 65535, &cfg.port);
            break;
        case 'b':
            cfg.bind = optarg;
            break;
        case 'w':
            cfg.web = optarg;
            break;
        case 't':
            bad = parse_uint(optarg, 2, 100000, &threads);
            break;
        case 's':
            bad = parse_uint(optarg, 1, 10000, &cfg.slots);
            break;
        case 'W':
            bad = parse_uint(optarg, 1, 64, &cfg.jobs.workers);
            break;
        case 'Q':
            bad = parse_uint(optarg, 1, 10000, &cfg.jobs.queue_cap);
            break;
        case 'K':
            bad = parse_uint(optarg, 1, 100000, &cfg.jobs.keep_done);
            break;
        case 'S':
            bad = parse_uint(optarg, 1, 86400, &cfg.job_seconds);
            break;
        case 'h':
            usage(stdout);
            exit(0);
        default:
            usage(stderr);
            return -1;
        }
        if (bad) {
            const struct option *opt = opts;
            while (opt->val != o)
                opt++;
            fprintf(stderr, "ljgapd: bad value '%s' for --%s\n", optarg, opt->name);
            return -1;
        }
    }
    if (optind < argc) {
        usage(stderr);
        return -1;
    }
    cfg.threads = threads ? threads : (cfg.slots + 16 > 64 ? cfg.slots + 16 : 64);
    if (cfg.threads <= cfg.slots) {
        fprintf(stderr, "ljgapd: --threads (%u) must exceed --compute-slots (%u)\n", cfg.threads,
                cfg.slots);
        return -1;
    }
    return 0;
}

static struct MHD_Daemon *daemon_start(char *host, size_t hostsz)
{
    struct sockaddr_in in4 = {0};
    struct sockaddr_in6 in6 = {0};
    struct sockaddr *sa = NULL;
    unsigned flags = MHD_USE_THREAD_PER_CONNECTION | MHD_USE_INTERNAL_POLLING_THREAD |
                     MHD_USE_AUTO | MHD_USE_ITC | MHD_USE_ERROR_LOG;
    struct MHD_Daemon *d;
    const union MHD_DaemonInfo *info;

    if (inet_pton(AF_INET, cfg.bind, &in4.sin_addr) == 1) {
        in4.sin_family = AF_INET;
        in4.sin_port = htons((uint16_t)cfg.port);
        sa = (struct sockaddr *)&in4;
        snprintf(host, hostsz, "%s",
                 in4.sin_addr.s_addr == htonl(INADDR_ANY) ? "127.0.0.1" : cfg.bind);
    } else if (inet_pton(AF_INET6, cfg.bind, &in6.sin6_addr) == 1) {
        in6.sin6_family = AF_INET6;
        in6.sin6_port = htons((uint16_t)cfg.port);
        sa = (struct sockaddr *)&in6;
        flags |= MHD_USE_IPv6;
        if (IN6_IS_ADDR_UNSPECIFIED(&in6.sin6_addr))
            snprintf(host, hostsz, "[::1]");
        else
            snprintf(host, hostsz, "[%s]", cfg.bind);
    } else {
        fprintf(stderr, "ljgapd: --bind wants a numeric IPv4 or IPv6 address, not '%s'\n",
                cfg.bind);
        return NULL;
    }
    d = MHD_start_daemon(flags, (uint16_t)cfg.port, NULL, NULL, on_access, NULL,
                         MHD_OPTION_SOCK_ADDR, sa, MHD_OPTION_CONNECTION_LIMIT,
                         (unsigned int)cfg.threads, MHD_OPTION_CONNECTION_TIMEOUT,
                         (unsigned int)cfg.timeout_s, MHD_OPTION_NOTIFY_COMPLETED, on_completed,
                         NULL, MHD_OPTION_END);
    if (!d) {
        fprintf(stderr, "ljgapd: cannot listen on %s port %u\n", cfg.bind, cfg.port);
        return NULL;
    }
    info = MHD_get_daemon_info(d, MHD_DAEMON_INFO_BIND_PORT);
    if (info) cfg.port = info->port;
    return d;
}

/* Wait until no request is in flight or `until` seconds have passed since t0. */
static void wait_inflight(const struct timespec *t0, double until)
{
    const struct timespec tick = {0, 20 * 1000 * 1000};
    while (atomic_load(&inflight) > 0 && seconds_since(t0) < until)
        nanosleep(&tick, NULL);
}

int main(int argc, char **argv)
{
    struct MHD_Daemon *d = NULL;
    ljgap_limits limits;
    sigset_t sigs;
    char host[INET6_ADDRSTRLEN + 3];
    struct timespec t_sig;
    MHD_socket lfd;
    int sig = 0;
    int rc = 1;

    gsl_set_error_handler_off();
    if (parse_args(argc, argv) != 0) return 2;

    /* Signals go to main's sigwait only: block them before any thread starts. */
    sigemptyset(&sigs);
    sigaddset(&sigs, SIGINT);
    sigaddset(&sigs, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &sigs, NULL);
    signal(SIGPIPE, SIG_IGN);

    ljgap_limits_default(&limits);
    limits.cancel = &cancel_flag;
    ljgap_handler_set_limits(&limits);
    if (getrandom(&id_seed, sizeof id_seed, 0) != sizeof id_seed)
        id_seed = (unsigned)getpid() ^ (unsigned)time(NULL);

    cache = http_cache_alloc(cfg.cache_entries, cfg.cache_bytes);
    jobs = ljgap_jobs_alloc(&cfg.jobs);
    if (!cache || !jobs) {
        fprintf(stderr, "ljgapd: out of memory\n");
        goto end;
    }
    if (cfg.web) {
        web_fd = open(cfg.web, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
        if (web_fd < 0) {
            fprintf(stderr, "ljgapd: cannot open --web %s: %s\n", cfg.web, strerror(errno));
            goto end;
        }
    }
    d = daemon_start(host, sizeof host);
    if (!d) goto end;
    printf("listening on http://%s:%u/\n", host, cfg.port);
    fflush(stdout);
    fprintf(stderr, "ljgapd %s: %u compute slots, %u connections, %u job workers, web %s\n",
            LJGAP_VERSION, cfg.slots, cfg.threads, cfg.jobs.workers, cfg.web ? cfg.web : "(none)");

    while (sigwait(&sigs, &sig) != 0)
        ;
    clock_gettime(CLOCK_MONOTONIC, &t_sig);
    atomic_store(&stopping, 1);
    fprintf(stderr, "ljgapd: %s, stopping (%u requests in flight)\n", strsignal(sig),
            atomic_load(&inflight));
    lfd = MHD_quiesce_daemon(d);
    ljgap_jobs_shutdown(jobs); /* background jobs have no client waiting: cancel them now */
    wait_inflight(&t_sig, cfg.grace_s);
    if (atomic_load(&inflight) > 0) {
        fprintf(stderr, "ljgapd: cancelling %u computations\n", atomic_load(&busy_slots));
        cancel_flag = 1;
        wait_inflight(&t_sig, cfg.stop_s);
    }
    if (atomic_load(&inflight) > 0) {
        /* A computation ignored the cancel flag: stopping the daemon would wait for it. */
        fprintf(stderr, "ljgapd: %u requests did not finish; exiting without them\n",
                atomic_load(&inflight));
        _exit(0);
    }
    if (!ljgap_jobs_wait_idle(jobs, cfg.stop_s - seconds_since(&t_sig))) {
        fprintf(stderr, "ljgapd: a simulation ignored its cancel flag; exiting without it\n");
        _exit(0);
    }
    MHD_stop_daemon(d);
    if (lfd != MHD_INVALID_SOCKET) close(lfd);
    fprintf(stderr, "ljgapd: stopped after %.1f s\n", seconds_since(&t_sig));
    rc = 0;
end:
    if (web_fd >= 0) close(web_fd);
    ljgap_jobs_free(jobs);
    fftw_cleanup(); /* the simulations' FFTW planner state is global: freed once no job runs */
    http_cache_free(cache);
    return rc;
}
