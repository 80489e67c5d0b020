/* daemon.h -- what the files of ljgapd share: its configuration, its state, one request, the
 * route table's row, and the reply helpers.
 *
 * ljgapd is split along its seams:
 *   main.c    start-up (limits, stores, threads, the listening daemon) and shutdown
 *   config.c  command-line flags, their defaults and --help
 *   http.c    libmicrohttpd's callbacks: a request's life cycle, bodies, connections, the log
 *   routes.c  the route table and the routes that answer from the I/O thread
 *   work.c    answering off the I/O thread: computations on compute slots (after the
 *             answer cache), job-store calls on the store's threads (pool.h)
 *   static.c  the page's files
 *   respond.c the only code that creates responses (ljgapd_respond_json, ..._problem, ...)
 *   pool.c    compute slots, the fair wait queue, cancel on hang-up (MHD-free)
 *   conns.c   connection records: slow senders, per-client counts (MHD-free)
 *   budget.c  the memory budget (--max-memory): bytes reserved before use (MHD-free)
 *   http_cache.c  the answer cache: a bounded LRU of computed answers (MHD-free)
 *   forwarded.c   the client an X-Forwarded-For header names (--trust-proxy)
 *   webfiles.c    the page's allowlist and the compiled-in table (tools/embed.c writes it)
 * Externs shared between these files are prefixed ljgapd_.
 */
#ifndef LJGAPD_DAEMON_H
#define LJGAPD_DAEMON_H

#include "budget.h"
#include "clock.h" /* ljgap__clock_since */
#include "conns.h"
#include "handler.h"
#include "http_cache.h"
#include "jobs.h"
#include "jobstore.h"
#include "memest.h"
#include "pool.h"

#include <microhttpd.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stddef.h>
#include <time.h>

/* ---- configuration (config.c) ---- */

typedef struct {
    unsigned port;               /* TCP port; 0 lets the kernel pick one (default 8080) */
    const char *bind;            /* numeric IPv4 or IPv6 address to listen on (127.0.0.1) */
    const char *web;             /* directory of static files, NULL serves none */
    unsigned connections;        /* most open connections (default 1024, within RLIMIT_NOFILE) */
    unsigned client_connections; /* most connections of one client (default 32) */
    unsigned io_threads;         /* libmicrohttpd I/O threads, epoll each (default 1) */
    unsigned slots;              /* concurrent computations (default: online cores) */
    unsigned queue;              /* computations waiting for a slot at most (default 64) */
    double queue_wait;           /* seconds a computation may wait for a slot (default 10) */
    double max_seconds;          /* wall-time cap of one computation (default 20) */
    unsigned retry_after;        /* Retry-After seconds while shutting down (default 5) */
    unsigned idle_s;             /* close a connection silent this long (default 30) */
    unsigned receive_s;          /* a whole request must arrive within this (default 60) */
    int trust_proxy;             /* the client is named by X-Forwarded-For (default off) */
    size_t max_body;             /* largest accepted request body in bytes (1 MiB) */
    size_t cache_entries;        /* answer cache bound in entries (1024) */
    size_t cache_bytes;          /* answer cache bound in bytes (64 MiB, at most max_memory/16) */
    size_t max_memory;           /* the memory budget in bytes (--max-memory; default the smaller
                                  * of 2 GiB and a quarter of physical memory) */
    double grace_s;              /* shutdown: seconds in-flight work may run (7) */
    double stop_s;               /* shutdown: seconds after the signal at which we stop (9.5) */
    ljgap__jobs_config jobs;      /* simulation jobs: workers, queue, finished jobs kept */
    unsigned job_seconds;        /* wall-time cap of one simulation (600) */
    unsigned job_threads;        /* threads of one simulation's realizations (1) */
    unsigned job_retry;          /* Retry-After seconds when the job queue is full (10) */
    double cancel_wait_s;        /* DELETE waits this long for a running job to stop (2) */
    const char *state_dir;       /* where the jobs are kept (--state-dir, or main.c's default) */
    const char *jobs_db;         /* or a postgresql:// URL (--jobs-db): a store shared by many */
} ljgapd_config;

/* Fills c from argv (defaults first); -1 after printing why (exit 2), 1 after --help (exit 0). */
int ljgapd_parse_args(ljgapd_config *c, int argc, char **argv);

/* ---- the server's state (main.c), shared by every thread ---- */

typedef struct {
    ljgapd_config cfg;
    http_cache *cache;       /* answers of earlier identical requests */
    ljgap__jobstore *store;   /* where the jobs are kept (jobstore.h) */
    ljgap__jobs *jobs;        /* simulation jobs */
    pool *slots;             /* compute slots and their wait queue */
    pool *ops;               /* threads for job-store calls (they may wait on the store) */
    conns *conns;            /* connection records */
    budget *mem;             /* the memory budget: bodies, computations, the cache, jobs */
    budget *bodies;          /* request bodies' share of it (half of what the cache leaves) */
    size_t pinned;           /* bytes of mem held for good (the answer cache's bound) */
    int web_fd;              /* open directory cfg.web, or -1 */
    atomic_uint inflight;    /* requests begun and not yet reported complete */
    atomic_int stopping;     /* set once a signal asked us to stop */
    unsigned id_seed;        /* random per process: made-up request ids differ per run */
    atomic_ulong id_counter; /* made-up request ids are seed + counter */
} ljgapd_server;

extern ljgapd_server ljgapd_srv;

/* ---- one request (http.c) ---- */

#define REQUEST_ID_MAX 64 /* longest X-Request-Id echoed */
#define LOG_PATH_MAX 200  /* longest path written to the log */

struct route;
typedef struct work_task work_task;

typedef struct {
    struct timespec t0;           /* when the request's headers arrived */
    const struct route *route;    /* the row that answers, set on the first call */
    struct MHD_Connection *conn;  /* its connection */
    conn_rec *rec;                /* the connection's record (conns.h), or NULL */
    char method[16];              /* request method, for the log */
    char path[LOG_PATH_MAX + 1];  /* path with control characters replaced, for the log */
    const char *url;              /* the path as libmicrohttpd gave it (valid meanwhile) */
    char id[REQUEST_ID_MAX + 1];  /* request id: echoed or made up */
    char client[POOL_CLIENT_MAX]; /* the client: remote address, or X-Forwarded-For */
    int counted;                  /* counted in conns_client_enter (--trust-proxy) */
    int status;                   /* status queued, 0 until then */
    char note[96];                /* extra words for the log line, or "" */
    const char *accept;           /* its Accept header (compute and job routes), or NULL */
    char *body;                   /* request body received so far (body routes) */
    size_t len;                   /* bytes in body */
    size_t cap;                   /* bytes allocated for body */
    size_t limit;                 /* the body's limit: cfg.max_body, or the route's text_max */
    int text;                     /* the body is text/plain or text/csv (a text route) */
    int file;                     /* the body is an instrument file (a text route; files.h) */
    ljgap__param *params;          /* a text or file body's query parameters (owned, decoded) */
    size_t nparams;               /* entries in params */
    int too_large;                /* the body outgrew its limit: answer 413 */
    int no_memory;                /* the body outgrew the memory budget: answer 503 */
    int close;                    /* close the connection after the answer (body left unread) */
    size_t held;                  /* bytes of the body reserved in ljgapd_srv.bodies */
    ljgap__token_count tokens;     /* a text body's values so far (memest.h) */
    size_t mem;                   /* its computation's estimate, reserved when it gets a slot */
    size_t discarded;             /* body bytes dropped since (or after an early answer) */
    work_task *task;              /* its work while it waits, runs, or has just ended */
} request;

/* libmicrohttpd's callbacks (http.c). */
enum MHD_Result ljgapd_on_access(void *cls, struct MHD_Connection *c, const char *url,
                                 const char *method, const char *version, const char *upload_data,
                                 size_t *upload_data_size, void **con_cls);
void ljgapd_on_completed(void *cls, struct MHD_Connection *c, void **con_cls,
                         enum MHD_RequestTerminationCode toe);
void ljgapd_on_connection(void *cls, struct MHD_Connection *c, void **socket_context,
                          enum MHD_ConnectionNotificationCode toe);
void ljgapd_mhd_log(void *cls, const char *fmt, va_list ap); /* MHD_OPTION_EXTERNAL_LOGGER */
/* The types a text route (/v1/psd) takes, its Accept-Post: JSON, text, octet-stream and the
 * instrument formats' own media types. */
const char *ljgapd_text_types(void);

/* ---- routes (routes.c) ---- */

typedef enum MHD_Result (*route_fn)(struct MHD_Connection *c, request *r);

struct route {
    const char *path;                /* exact path, or a prefix if it ends in '/' */
    int (*exists)(const char *rest); /* for a prefix: does the rest name something? */
    const char *allow;               /* allowed methods, the Allow header of a 405 */
    int takes_body;                  /* read a JSON body before answering */
    route_fn answer;                 /* writes the response (called again after a resume) */
    size_t text_max;                 /* also takes a text/plain or text/csv body, or an
                                      * instrument file (application/octet-stream or a format's
                                      * own type), of at most this many bytes, with its query
                                      * (0: JSON only) */
};

/* The kinds of job the daemon runs (one: "simulation"), for ljgap__jobs_alloc. */
extern const ljgap__job_kind ljgapd_job_kinds[];
extern const size_t ljgapd_job_nkinds;

/* The row for url: first match wins; the last row (path NULL) answers 404. */
const struct route *ljgapd_route_find(const char *url);

/* ---- work off the I/O thread (work.c) ---- */

/* What a work function produces: an answer body, or a problem for the I/O thread to write. */
typedef struct {
    ljgap__reply rep;    /* the answer (status, body, content type), when problem is 0 */
    int problem;        /* nonzero: answer a problem with this status and detail instead */
    char detail[256];   /* the problem's detail */
    const char *header; /* one extra header of either answer (Location, Retry-After), or NULL */
    char value[400];    /* its value */
    char *key;          /* compute: the answer cache's key (owned), or NULL */
    size_t klen;        /* its length */
} work_reply;

/* Runs on a pool thread: reads the request (its body, url, method), honours *cancel. */
typedef void (*work_fn)(request *r, const volatile int *cancel, work_reply *out);

/* Suspends the connection and runs fn on p; answers when it is resumed (the route calls
 * this again on its second call: r->task is set then). Takes key (may be NULL). */
enum MHD_Result ljgapd_route_offload(struct MHD_Connection *c, request *r, pool *p, work_fn fn,
                                     char *key, size_t klen);
/* Frees the request's task, if any (the request's end). */
void ljgapd_work_release(request *r);

/* POST /v1/NAME: the cache, else a compute slot. */
enum MHD_Result ljgapd_route_compute(struct MHD_Connection *c, request *r);
int ljgapd_compute_exists(const char *rest);
/* POST /v1/psd: JSON as ljgapd_route_compute; a text body (a height matrix) or an instrument
 * file (ljgap__handle_file) with its query on a
 * compute slot, not cached. */
enum MHD_Result ljgapd_route_psd(struct MHD_Connection *c, request *r);

/* static.c: GET / and the page's files: compiled in, or from --web DIR. */
enum MHD_Result ljgapd_route_static(struct MHD_Connection *c, request *r);
int ljgapd_static_exists(const char *rest);

/* ---- replies (respond.c): the only code that creates responses ---- */

/* Answer status with a copy of body (ctype as given) and, if header is not NULL, one extra
 * header. */
enum MHD_Result ljgapd_respond_json_hdr(struct MHD_Connection *c, request *r, int status,
                                        const char *ctype, const char *body, size_t len,
                                        const char *header, const char *value);
enum MHD_Result ljgapd_respond_json(struct MHD_Connection *c, request *r, int status,
                                    const char *ctype, const char *body, size_t len);
/* Answers a ljgap__reply and frees it. */
enum MHD_Result ljgapd_respond_reply(struct MHD_Connection *c, request *r, ljgap__reply *rep);
/* An RFC 9457 problem; header/value, if not NULL, is one extra header (Allow, Retry-After). */
enum MHD_Result ljgapd_respond_problem(struct MHD_Connection *c, request *r, int status,
                                       const char *detail, const char *header, const char *value);
/* 503 with Retry-After: seconds. */
enum MHD_Result ljgapd_respond_busy(struct MHD_Connection *c, request *r, const char *detail,
                                    unsigned seconds);
/* 503 of type unavailable (the computation was cancelled: its client went away), with
 * Retry-After: 1. */
enum MHD_Result ljgapd_respond_cancelled(struct MHD_Connection *c, request *r, const char *detail);
/* 200 with the file open on fd (size bytes); fd is closed with the response. */
enum MHD_Result ljgapd_respond_file(struct MHD_Connection *c, request *r, int fd, size_t size,
                                    const char *ctype);
/* 200 with static bytes (not copied) and their ETag, or 304 when if_none_match matches it. */
enum MHD_Result ljgapd_respond_static(struct MHD_Connection *c, request *r, const void *data,
                                      size_t len, const char *ctype, const char *etag,
                                      const char *if_none_match);
/* 413: the request body is over cfg.max_body. */
enum MHD_Result ljgapd_respond_too_large(struct MHD_Connection *c, request *r);
/* 413 for memory: what the request needs (need bytes) can never fit the budget, whose part
 * (what bytes) is named in the detail. */
enum MHD_Result ljgapd_respond_over_budget(struct MHD_Connection *c, request *r, size_t need,
                                           const char *what, size_t bytes);
/* 503 + Retry-After: the memory budget is in use now (what: "the request body", ...). */
enum MHD_Result ljgapd_respond_no_memory(struct MHD_Connection *c, request *r, const char *what,
                                         size_t need);

/* Bytes of the budget one computation or simulation may reserve at most: what is left beside
 * the pinned cache and a full share of bodies (its own body is in that share). */
size_t ljgapd_compute_memory_max(void);

#endif
