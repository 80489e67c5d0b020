/* work.c -- answering off the I/O thread: computations on compute slots, job-store calls on
 * the store's threads, and the answer cache in front of the computations.
 *
 * libmicrohttpd runs every connection on its I/O thread(s) with epoll, so an access handler
 * must never block. A route whose answer takes time hands a work function to a pool (pool.h):
 *
 *   1. ljgapd_route_offload() makes a task and submits it. The pool accepts it and, still under its
 *      lock, parks it: MHD_suspend_connection(), so the connection holds no thread while it
 *      waits or runs. A full pool answers 503 with Retry-After at once.
 *   2. A pool thread runs the work function, which fills a work_reply (a body, or a problem to
 *      write); a computation reads the task's cancel flag, which the pool raises when the
 *      client hangs up (or at shutdown).
 *   3. wake: MHD_resume_connection(). libmicrohttpd calls the route's access handler again on
 *      its I/O thread, which finds the task ended and answers from it: the work's reply, 503
 *      after waiting --queue-wait seconds, 503 while shutting down, or, when the client went
 *      away, a 503 "unavailable" (cancelled) that nobody is likely to read (the log line says
 *      so).
 *
 * Responses are only ever queued from the I/O thread, inside the access handler; the pool's
 * threads only call MHD_resume_connection, which libmicrohttpd allows from any thread.
 *
 * Memory. Before a computation is submitted its working memory is estimated from the request
 * (memest.h: from the body's length, or a text matrix's count of values); the pool reserves it
 * in the budget when the task gets a slot and gives it back when the work returns, so a task
 * that does not fit waits as for a slot (503 after --queue-wait, saying memory was the reason).
 * One that could never fit, more than the budget leaves beside the cache and a full share of
 * bodies (ljgapd_compute_memory_max), is 413 at once. Cached answers need none.
 */
#include "daemon.h"
#include "files.h" /* LJGAP_FILES_MAX_POINTS */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct work_task {
    pool_task t;    /* the pool's view (first member) */
    request *r;     /* the request it answers (alive while the connection is suspended) */
    work_fn fn;     /* the work */
    work_reply out; /* what the work produced */
};

static void task_free(work_task *w)
{
    if (!w) return;
    ljgap__reply_free(&w->out.rep);
    free(w->out.key);
    free(w);
}

void ljgapd_work_release(request *r)
{
    task_free(r->task);
    r->task = NULL;
}

static void task_run(pool_task *t)
{
    work_task *w = (work_task *)t;
    w->fn(w->r, &t->cancel, &w->out);
}

static void task_park(pool_task *t)
{
    MHD_suspend_connection(((work_task *)t)->r->conn);
}

static void task_wake(pool_task *t)
{
    request *r = ((work_task *)t)->r;
    /* The note is written here, not when the answer is queued: libmicrohttpd may find the
     * connection closed once resumed and end the request without calling the route again. */
    if (t->outcome == POOL_GONE)
        snprintf(r->note, sizeof r->note, " (client went away after %.2fs%s)",
                 t->waited_s + t->ran_s, t->ran_s > 0 ? ", computation cancelled" : "");
    MHD_resume_connection(r->conn);
}

/* The access handler's second call, after the resume: answer from the ended task. */
static enum MHD_Result answer_ended(struct MHD_Connection *c, request *r, pool *p)
{
    work_task *w = r->task;
    work_reply *o = &w->out;
    enum MHD_Result ret = MHD_YES;
    char detail[240];

    if (w->t.waited_s >= 0.05 && w->t.outcome != POOL_GONE)
        snprintf(r->note, sizeof r->note, " waited=%.2fs", w->t.waited_s);
    switch (w->t.outcome) {
    case POOL_DONE:
        if (o->problem)
            ret = ljgapd_respond_problem(c, r, o->problem, o->detail, o->header, o->value);
        else if (!o->rep.body)
            ret = ljgapd_respond_problem(c, r, MHD_HTTP_INTERNAL_SERVER_ERROR, "out of memory",
                                         NULL, NULL);
        else
            ret = ljgapd_respond_json_hdr(c, r, o->rep.status, o->rep.content_type, o->rep.body,
                                          o->rep.len, o->header, o->value);
        break;
    case POOL_EXPIRED:
        if (w->t.starved) {
            char m[32];
            snprintf(r->note, sizeof r->note, " waited=%.2fs for memory", w->t.waited_s);
            budget_format(ljgapd_srv.cfg.max_memory, m, sizeof m);
            snprintf(detail, sizeof detail,
                     "waited %.0f s (the --queue-wait limit) for a compute slot and the memory "
                     "of its computation: the memory budget (--max-memory %s) was in use; "
                     "retry after the given seconds",
                     w->t.waited_s, m);
            ret = ljgapd_respond_busy(c, r, detail, pool_retry_after(p));
            break;
        }
        snprintf(detail, sizeof detail,
                 "waited %.0f s for a free compute slot (the --queue-wait limit); every slot "
                 "was busy: retry after the given seconds",
                 w->t.waited_s);
        ret = ljgapd_respond_busy(c, r, detail, pool_retry_after(p));
        break;
    case POOL_STOPPED:
        ret =
            ljgapd_respond_busy(c, r, "the server is shutting down; retry after the given seconds",
                                ljgapd_srv.cfg.retry_after);
        break;
    case POOL_GONE:
        /* Nobody is likely to read this (the socket hung up), but a client that only shut down
         * its sending side still learns what happened; a write to a closed socket just fails. */
        ret = ljgapd_respond_cancelled(c, r,
                                       "the connection was closed (or shut down for sending) while "
                                       "the request waited or ran, so it was cancelled");
        break;
    }
    ljgapd_work_release(r);
    return ret;
}

enum MHD_Result ljgapd_route_offload(struct MHD_Connection *c, request *r, pool *p, work_fn fn,
                                     char *key, size_t klen)
{
    const union MHD_ConnectionInfo *ci;
    work_task *w;
    char detail[200];

    if (r->task) return answer_ended(c, r, p);
    if (!(w = calloc(1, sizeof *w))) {
        free(key);
        return ljgapd_respond_problem(c, r, MHD_HTTP_INTERNAL_SERVER_ERROR, "out of memory", NULL,
                                      NULL);
    }
    w->r = r;
    w->fn = fn;
    w->out.key = key;
    w->out.klen = klen;
    w->t.run = task_run;
    w->t.park = task_park;
    w->t.wake = task_wake;
    snprintf(w->t.client, sizeof w->t.client, "%s", r->client);
    ci = MHD_get_connection_info(c, MHD_CONNECTION_INFO_CONNECTION_FD);
    w->t.fd = ci ? ci->connect_fd : -1;
    w->t.mem = p == ljgapd_srv.slots ? r->mem : 0; /* reserved when it gets a slot */
    r->task = w;
    switch (pool_submit(p, &w->t)) {
    case POOL_OK:
        return MHD_YES; /* suspended; answered when resumed */
    case POOL_FULL:
        ljgapd_work_release(r);
        snprintf(detail, sizeof detail,
                 "every compute slot is busy and the wait queue is full (%u waiting at most); "
                 "retry after the given seconds",
                 pool_queue_cap(p));
        return ljgapd_respond_busy(c, r, detail, pool_retry_after(p));
    default:
        ljgapd_work_release(r);
        return ljgapd_respond_busy(c, r,
                                   "the server is shutting down; retry after the given seconds",
                                   ljgapd_srv.cfg.retry_after);
    }
}

/* ---- memory (budget.h, memest.h) ---- */

size_t ljgapd_compute_memory_max(void)
{
    size_t lim = budget_limit(ljgapd_srv.mem),
           rest = lim - ljgapd_srv.pinned - budget_limit(ljgapd_srv.bodies);
    return ljgapd_srv.pinned + budget_limit(ljgapd_srv.bodies) < lim ? rest : 0;
}

/* Sets r->mem to the computation's estimate; answers 413 (returns 1, *ret set) when it could
 * never fit (its body is in the bodies' share, already reserved). */
static int over_budget(struct MHD_Connection *c, request *r, size_t est, enum MHD_Result *ret)
{
    size_t most = ljgapd_compute_memory_max();
    r->mem = est;
    if (est <= most) return 0;
    *ret = ljgapd_respond_over_budget(c, r, est, "the part one computation may hold", most);
    return 1;
}

/* ---- POST /v1/NAME: the cache, then a compute slot ---- */

/* Stores an answer the handler marked cacheable (reply.h) under key, with meta.cached true, so
 * that hits can be sent as stored: the answer up to its LJGAP_REPLY_UNCACHED_TAIL, then
 * LJGAP_REPLY_CACHED_TAIL (parsing and printing the answer again would cost about 2 % of a whole
 * adhesion request). */
static void cache_store(const char *key, size_t klen, const ljgap__reply *rep)
{
    static const char yes[] = LJGAP_REPLY_CACHED_TAIL;
    const size_t n = sizeof LJGAP_REPLY_UNCACHED_TAIL - 1;

    if (!rep->cacheable || rep->len < n) return; /* CSV, a problem: not cached */
    http_cache_put2(ljgapd_srv.cache, key, klen, rep->status, rep->body, rep->len - n, yes,
                    sizeof yes - 1);
}

/* On a compute slot: the handler, then the cache. */
static void compute_work(request *r, const volatile int *cancel, work_reply *out)
{
    ljgap__call call = {cancel, r->accept};
    const char *endpoint = r->url + strlen("/v1/");
    ljgap__handle_call(endpoint, r->body ? r->body : "", r->len, &call, &out->rep);
    if (out->rep.status >= 200 && out->rep.status < 300 && out->key)
        cache_store(out->key, out->klen, &out->rep);
}

enum MHD_Result ljgapd_route_compute(struct MHD_Connection *c, request *r)
{
    const char *endpoint = r->url + strlen("/v1/");
    size_t elen = strlen(endpoint), alen, klen;
    char *key, *hit = NULL;
    size_t hitlen = 0;
    int status = 0;
    enum MHD_Result ret;

    if (r->task) return ljgapd_route_offload(c, r, ljgapd_srv.slots, compute_work, NULL, 0);
    /* the cache key: Accept, NUL, endpoint, NUL, body bytes (only JSON answers are stored) */
    r->accept = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_ACCEPT);
    alen = r->accept ? strlen(r->accept) : 0;
    klen = alen + 1 + elen + 1 + r->len;
    if (!(key = malloc(klen)))
        return ljgapd_respond_problem(c, r, MHD_HTTP_INTERNAL_SERVER_ERROR, "out of memory", NULL,
                                      NULL);
    memcpy(key, r->accept ? r->accept : "", alen + 1);
    memcpy(key + alen + 1, endpoint, elen + 1);
    if (r->len) memcpy(key + alen + 1 + elen + 1, r->body, r->len);
    if (http_cache_get(ljgapd_srv.cache, key, klen, &status, &hit, &hitlen) == 1) {
        ret = ljgapd_respond_json(c, r, status, "application/json", hit, hitlen);
        free(hit);
        free(key);
        return ret;
    }
    if (over_budget(
            c, r,
            ljgap__memest_json(r->len, ljgap__json_values(r->body, r->len), ljgapd_srv.cfg.slots),
            &ret)) {
        free(key);
        return ret;
    }
    return ljgapd_route_offload(c, r, ljgapd_srv.slots, compute_work, key, klen);
}

int ljgapd_compute_exists(const char *rest)
{
    return ljgap__handler_has(rest);
}

/* On a compute slot: a text upload (its body can be 64 MiB: no cache). */
static void psd_text_work(request *r, const volatile int *cancel, work_reply *out)
{
    ljgap__call call = {cancel, r->accept};
    ljgap__handle_text("psd", r->params, r->nparams, r->body ? r->body : "", r->len, &call,
                      &out->rep);
}

/* On a compute slot: an instrument file (files.h), not cached. */
static void psd_file_work(request *r, const volatile int *cancel, work_reply *out)
{
    ljgap__call call = {cancel, r->accept};
    ljgap__handle_file("psd", r->params, r->nparams, (const unsigned char *)r->body, r->len, &call,
                      &out->rep);
    if (out->rep.status == 415) { /* no format read here: what the route takes */
        out->header = "Accept-Post";
        snprintf(out->value, sizeof out->value, "%s", ljgapd_text_types());
    }
}

enum MHD_Result ljgapd_route_psd(struct MHD_Connection *c, request *r)
{
    enum MHD_Result ret;
    if (r->file) {
        if (!r->task) {
            /* a file holds at most a point per 2 bytes (16-bit samples); the map and its
             * cropped copy (psd.c) come on top of the text path's estimate */
            size_t points = r->len / 2 + 1, cap = LJGAP_FILES_MAX_POINTS;
            if (points > cap) points = cap;
            r->accept = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_ACCEPT);
            if (over_budget(c, r, ljgap__memest_psd_text(points) + 16 * points, &ret)) return ret;
        }
        return ljgapd_route_offload(c, r, ljgapd_srv.slots, psd_file_work, NULL, 0);
    }
    if (!r->text) return ljgapd_route_compute(c, r);
    if (!r->task) {
        size_t values = r->tokens.tokens, cap = LJGAP_TOPO_POINTS_DEFAULT;
        r->accept = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_ACCEPT);
        /* the parser stops after its cap of heights */
        if (over_budget(c, r, ljgap__memest_psd_text(values < cap ? values + 1 : cap + 1), &ret))
            return ret;
    }
    return ljgapd_route_offload(c, r, ljgapd_srv.slots, psd_text_work, NULL, 0);
}
