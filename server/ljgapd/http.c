/* http.c -- libmicrohttpd's callbacks: connections, a request's life cycle, bodies, the log.
 *
 * libmicrohttpd runs with epoll on --io-threads threads and calls these functions there, so
 * none of them may block: anything slow is handed to a pool (work.c) while the connection is
 * suspended.
 *
 *   - connections: on_connection records each one (conns.h: the slow-sender bound, TCP
 *     keep-alive) and drops the record when libmicrohttpd closes it.
 *   - the client: the remote address, or with --trust-proxy the last address in
 *     X-Forwarded-For (the one our proxy appended; earlier ones are the client's word). Slots
 *     are shared fairly between clients (pool.h). Without --trust-proxy, libmicrohttpd limits
 *     each address to --client-connections connections; with it, every connection comes from
 *     the proxy, so each forwarded client may have --client-connections requests in progress
 *     and the next is answered 503.
 *   - bodies: body routes must say Content-Type: application/json (else 415 with Accept-Post,
 *     decided before the size) and carry at most --max-body bytes (413, decided from
 *     Content-Length before reading, or while reading a chunked body, when the buffer would
 *     grow past the limit). A route with text_max also takes text/plain or text/csv, or an
 *     instrument file (application/octet-stream or a format's own type, files.h), up to that
 *     many bytes; its query parameters are copied then (decoded by libmicrohttpd) for the work
 *     on a compute slot, and a text's values are counted as they arrive (memest.h).
 *   - memory: a body's bytes are reserved in the budget's share for bodies (budget.h) before
 *     they are read: from Content-Length at the first call (one that does not fit is answered
 *     503 + Retry-After unread, and the connection closed, as for 413; one larger than the
 *     whole share is 413), or as a chunked body's buffer grows (past the budget: the body is
 *     dropped and 503 answered at its end). They are given back when the request ends.
 *   - the log: one line per request on stderr when libmicrohttpd reports it complete: method,
 *     path, status, milliseconds, request id, and notes (time waited for a slot, a client that
 *     went away). X-Request-Id is echoed when the client sends a sane one,
 *     otherwise made up, and is returned on every answer. libmicrohttpd's own messages (a
 *     refused connection, a client that closed mid-request) go to the same log with a prefix,
 *     at most one of a kind per second: a flood of refused connections cannot flood the log.
 */
#include "daemon.h"
#include "files.h" /* the instrument formats' media types */
#include "forwarded.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DISCARD_FACTOR 16 /* close a connection sending more than this times the body limit */

/* ---- the request line and headers ---- */

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

/* Is the Content-Type text/plain or text/csv (parameters allowed)? */
static int is_text_type(const char *ct)
{
    size_t n;
    if (!ct) return 0;
    ct += strspn(ct, " \t");
    n = strcspn(ct, "; \t");
    return (n == 10 && strncasecmp(ct, "text/plain", 10) == 0) ||
           (n == 8 && strncasecmp(ct, "text/csv", 8) == 0);
}

/* Is it an instrument file's type: application/octet-stream or a format's own (files.h)? */
static int is_file_type(const char *ct)
{
    size_t n;
    if (!ct) return 0;
    ct += strspn(ct, " \t");
    n = strcspn(ct, "; \t");
    if (n == 24 && strncasecmp(ct, "application/octet-stream", 24) == 0) return 1;
    for (const ljgap__files_format *const *f = ljgap__files_formats(); *f; f++)
        if ((*f)->media_type && strlen((*f)->media_type) == n &&
            strncasecmp(ct, (*f)->media_type, n) == 0)
            return 1;
    return 0;
}

/* What a text route's Accept-Post says: JSON, text, octet-stream and the formats' own types
 * (written once: the registry is fixed). */
static char text_types[400];

static void text_types_fill(void)
{
    size_t k = (size_t)snprintf(text_types, sizeof text_types,
                                "application/json, text/plain, text/csv, application/octet-stream");
    for (const ljgap__files_format *const *f = ljgap__files_formats(); *f; f++)
        if ((*f)->media_type && k + strlen((*f)->media_type) + 3 < sizeof text_types)
            k += (size_t)snprintf(text_types + k, sizeof text_types - k, ", %s", (*f)->media_type);
}

const char *ljgapd_text_types(void)
{
    static pthread_once_t once = PTHREAD_ONCE_INIT;
    pthread_once(&once, text_types_fill);
    return text_types;
}

/* Is it application/json or application/...+json (parameters allowed)? */
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

/* Copy s into dst (size dstsz), replacing bytes outside printable ASCII with '?'. */
static void copy_printable(char *dst, size_t dstsz, const char *s)
{
    size_t i = 0;
    for (; s[i] && i + 1 < dstsz; i++)
        dst[i] = (s[i] > ' ' && s[i] < 0x7f) ? s[i] : '?';
    dst[i] = '\0';
}

/* The numeric address of sa into out ("?" if there is none). */
static void address_of(const struct sockaddr *sa, char *out, size_t n)
{
    const void *a = NULL;
    if (sa && sa->sa_family == AF_INET) a = &((const struct sockaddr_in *)sa)->sin_addr;
    if (sa && sa->sa_family == AF_INET6) a = &((const struct sockaddr_in6 *)sa)->sin6_addr;
    if (!a || !inet_ntop(sa->sa_family, a, out, (socklen_t)n)) snprintf(out, n, "?");
}

static void client_of(struct MHD_Connection *c, char *out, size_t n)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(c, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
    if (ljgapd_srv.cfg.trust_proxy) {
        const char *xff = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "X-Forwarded-For");
        if (xff && ljgapd_forwarded_client(xff, out, n)) return;
    }
    address_of(ci ? ci->client_addr : NULL, out, n);
}

static request *request_new(struct MHD_Connection *c, const char *url, const char *method)
{
    const char *rid = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "X-Request-Id");
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(c, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    request *r = calloc(1, sizeof *r);

    if (!r) return NULL;
    clock_gettime(CLOCK_MONOTONIC, &r->t0);
    r->limit = ljgapd_srv.cfg.max_body; /* a text route raises it in request_begin */
    r->conn = c;
    r->rec = ci ? ci->socket_context : NULL;
    r->url = url;
    copy_printable(r->method, sizeof r->method, method);
    copy_printable(r->path, sizeof r->path, url);
    client_of(c, r->client, sizeof r->client);
    if (rid && rid[0] && strlen(rid) <= REQUEST_ID_MAX &&
        strspn(rid, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._:-") ==
            strlen(rid))
        strcpy(r->id, rid);
    else
        snprintf(r->id, sizeof r->id, "%08x%08lx", ljgapd_srv.id_seed,
                 (unsigned long)atomic_fetch_add(&ljgapd_srv.id_counter, 1) + 1);
    return r;
}

/* The decoded query parameters of a text body into r->params (one block: the array, then the
 * strings); -1 when out of memory. */
struct query_copy {
    request *r;
    size_t n, bytes; /* first pass: count and sizes; second: fill */
    char *next;      /* second pass: where the next string goes */
};

static enum MHD_Result query_arg(void *cls, enum MHD_ValueKind kind, const char *key,
                                 const char *value)
{
    struct query_copy *q = cls;
    const char *kv[2] = {key ? key : "", value};
    if (!q->next) {
        q->n++;
        q->bytes += strlen(kv[0]) + 1 + (value ? strlen(value) + 1 : 0);
        return MHD_YES;
    }
    ljgap__param *p = &q->r->params[q->r->nparams++];
    for (int i = 0; i < 2; i++) {
        if (!kv[i]) continue;
        size_t n = strlen(kv[i]) + 1;
        memcpy(q->next, kv[i], n);
        *(i ? &p->value : &p->name) = q->next;
        q->next += n;
    }
    return MHD_YES;
}

static int query_copy(struct MHD_Connection *c, request *r)
{
    struct query_copy q = {r, 0, 0, NULL};
    MHD_get_connection_values(c, MHD_GET_ARGUMENT_KIND, query_arg, &q);
    if (!q.n) return 0;
    if (!(r->params = calloc(1, q.n * sizeof *r->params + q.bytes))) return -1;
    q.next = (char *)(r->params + q.n);
    MHD_get_connection_values(c, MHD_GET_ARGUMENT_KIND, query_arg, &q);
    return 0;
}

/* The first call of a request: route it and refuse what can be refused before any body. */
static enum MHD_Result request_begin(struct MHD_Connection *c, request *r, const char *method)
{
    const char *clen, *ctype;
    unsigned long long want = 0;
    char detail[420];

    if (ljgapd_srv.cfg.trust_proxy) {
        if (!conns_client_enter(ljgapd_srv.conns, r->client, ljgapd_srv.cfg.client_connections)) {
            snprintf(detail, sizeof detail,
                     "this client already has %u requests in progress (--client-connections); "
                     "retry after the given seconds",
                     ljgapd_srv.cfg.client_connections);
            return ljgapd_respond_busy(c, r, detail, 1);
        }
        r->counted = 1;
    }
    r->route = ljgapd_route_find(r->url);
    if (!r->route->path) return r->route->answer(c, r);
    if (!method_allowed(r->route->allow, method)) {
        snprintf(detail, sizeof detail, "use %s", r->route->allow);
        return ljgapd_respond_problem(c, r, MHD_HTTP_METHOD_NOT_ALLOWED, detail,
                                      MHD_HTTP_HEADER_ALLOW, r->route->allow);
    }
    if (!r->route->takes_body) return r->route->answer(c, r);

    ctype = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE);
    r->text = r->route->text_max && is_text_type(ctype);
    r->file = r->route->text_max && !r->text && is_file_type(ctype);
    r->limit = r->text || r->file ? r->route->text_max : ljgapd_srv.cfg.max_body;
    clen = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH);
    if (clen) want = strtoull(clen, NULL, 10);
    if (!r->text && !r->file && !is_json_type(ctype)) {
        /* the type first: a body the route never takes is 415 whatever its size */
        const char *types = r->route->text_max ? ljgapd_text_types() : "application/json";
        r->close = want > 0; /* its body is not read */
        snprintf(detail, sizeof detail, "%s takes %.300s (Accept-Post), not %.40s", r->route->path,
                 types, ctype ? ctype : "a body without Content-Type");
        return ljgapd_respond_problem(c, r, MHD_HTTP_UNSUPPORTED_MEDIA_TYPE, detail, "Accept-Post",
                                      types);
    }
    if (want > r->limit) {
        r->close = 1;
        return ljgapd_respond_too_large(c, r);
    }
    if ((r->text || r->file) && query_copy(c, r)) return MHD_NO;
    if (want) {
        /* reserved before a byte is read: a body that does not fit is refused unread */
        size_t need = (size_t)want + 1;
        if (need > budget_limit(ljgapd_srv.bodies)) {
            r->close = 1;
            return ljgapd_respond_over_budget(c, r, need, "the share of request bodies",
                                              budget_limit(ljgapd_srv.bodies));
        }
        if (!budget_try(ljgapd_srv.bodies, need)) {
            r->close = 1;
            return ljgapd_respond_no_memory(c, r, "the request body", need);
        }
        r->held = need;
        r->body = malloc(need);
        if (!r->body) return MHD_NO;
        r->cap = need;
    }
    conns_receiving(ljgapd_srv.conns, r->rec);
    return MHD_YES;
}

/* Frees the body and gives its bytes back to the budget. */
static void body_free(request *r)
{
    free(r->body);
    r->body = NULL;
    budget_release(ljgapd_srv.bodies, r->held);
    r->held = 0;
    r->len = r->cap = 0;
}

/* Append a chunk of body. A body that outgrows its limit (or, growing without a
 * Content-Length, the memory budget) is freed and the rest counted and dropped (libmicrohttpd
 * 0.9.75 cannot queue an answer while a body is arriving, so the 413 or 503 goes out when the
 * body ends); -1 (close the connection) if memory runs out or the client goes on sending past
 * DISCARD_FACTOR times the limit. */
static int request_take(request *r, const char *data, size_t n)
{
    size_t limit = r->limit;
    if (!r->too_large && !r->no_memory && !r->status && r->len + n > limit) {
        r->too_large = 1;
        r->discarded = r->len;
        body_free(r);
    }
    if (r->len + n + 1 > r->cap && !r->too_large && !r->no_memory && !r->status) {
        size_t cap = r->cap ? r->cap : 4096;
        char *b;
        while (cap < r->len + n + 1)
            cap *= 2;
        if (cap > limit + 1) cap = limit + 1;
        if (!budget_try(ljgapd_srv.bodies, cap - r->held)) {
            r->no_memory = 1;
            r->discarded = r->len;
            body_free(r);
        } else {
            r->held = cap;
            b = realloc(r->body, cap);
            if (!b) return -1;
            r->body = b;
            r->cap = cap;
        }
    }
    if (r->too_large || r->no_memory || r->status) {
        r->discarded += n;
        return r->discarded > DISCARD_FACTOR * limit ? -1 : 0;
    }
    if (r->text) ljgap__token_feed(&r->tokens, data, n);
    memcpy(r->body + r->len, data, n);
    r->len += n;
    r->body[r->len] = '\0';
    return 0;
}

enum MHD_Result ljgapd_on_access(void *cls, struct MHD_Connection *c, const char *url,
                                 const char *method, const char *version, const char *upload_data,
                                 size_t *upload_data_size, void **con_cls)
{
    request *r = *con_cls;

    if (!r) {
        r = request_new(c, url, method);
        if (!r) return MHD_NO;
        *con_cls = r;
        atomic_fetch_add(&ljgapd_srv.inflight, 1);
        return request_begin(c, r, method);
    }
    r->url = url; /* the same string on every call; kept current to be safe */
    if (*upload_data_size) {
        size_t n = *upload_data_size;
        *upload_data_size = 0;
        return request_take(r, upload_data, n) == 0 ? MHD_YES : MHD_NO;
    }
    if (r->status) return MHD_YES;
    conns_busy(ljgapd_srv.conns, r->rec);
    if (r->too_large) return ljgapd_respond_too_large(c, r);
    if (r->no_memory) {
        r->close = 1;
        return ljgapd_respond_no_memory(c, r, "the request body, sent without Content-Length,",
                                        r->discarded + 1);
    }
    return r->route->answer(c, r);
}

void ljgapd_on_completed(void *cls, struct MHD_Connection *c, void **con_cls,
                         enum MHD_RequestTerminationCode toe)
{
    request *r = *con_cls;

    if (!r) return;
    /* behind a proxy the remote address is the proxy's: name the client it forwarded */
    fprintf(stderr, "%s %s %d %.1fms id=%s%s%s%s%s\n", r->method, r->path, r->status,
            1e3 * ljgap__clock_since(&r->t0), r->id, ljgapd_srv.cfg.trust_proxy ? " client=" : "",
            ljgapd_srv.cfg.trust_proxy ? r->client : "", r->note,
            toe == MHD_REQUEST_TERMINATED_COMPLETED_OK ? "" : " (connection closed early)");
    conns_idle(ljgapd_srv.conns, r->rec);
    if (r->counted) conns_client_leave(ljgapd_srv.conns, r->client);
    ljgapd_work_release(r);
    free(r->params);
    body_free(r);
    free(r);
    *con_cls = NULL;
    atomic_fetch_sub(&ljgapd_srv.inflight, 1);
}

void ljgapd_on_connection(void *cls, struct MHD_Connection *c, void **socket_context,
                          enum MHD_ConnectionNotificationCode toe)
{
    if (toe == MHD_CONNECTION_NOTIFY_STARTED) {
        const union MHD_ConnectionInfo *ci =
            MHD_get_connection_info(c, MHD_CONNECTION_INFO_CONNECTION_FD);
        *socket_context = ci ? conns_open(ljgapd_srv.conns, ci->connect_fd) : NULL;
    } else {
        conns_close(ljgapd_srv.conns, *socket_context);
        *socket_context = NULL;
    }
}

/* libmicrohttpd's messages: prefixed, and a message repeated within a second is counted, not
 * printed; the count goes out with the next different message (or the next second's). */
void ljgapd_mhd_log(void *cls, const char *fmt, va_list ap)
{
    static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
    static char last[256];
    static struct timespec t_last;
    static unsigned long repeats;
    char msg[256];
    size_t n;

    vsnprintf(msg, sizeof msg, fmt, ap);
    n = strlen(msg);
    while (n > 0 && (msg[n - 1] == '\n' || msg[n - 1] == '\r'))
        msg[--n] = '\0';
    pthread_mutex_lock(&lock);
    if (strcmp(msg, last) == 0 && ljgap__clock_since(&t_last) < 1.0) {
        repeats++;
    } else {
        if (repeats) fprintf(stderr, "ljgapd: libmicrohttpd: (%lu more like: %s)\n", repeats, last);
        fprintf(stderr, "ljgapd: libmicrohttpd: %s\n", msg);
        snprintf(last, sizeof last, "%s", msg);
        clock_gettime(CLOCK_MONOTONIC, &t_last);
        repeats = 0;
    }
    pthread_mutex_unlock(&lock);
}
