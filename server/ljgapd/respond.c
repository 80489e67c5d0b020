/* respond.c -- the only code in ljgapd that creates responses.
 *
 * Every answer goes through respond(), which adds the common headers (Content-Type,
 * X-Request-Id, nosniff, the page's Content-Security-Policy, Connection: close while stopping)
 * and queues it. Routes answer through ljgapd_respond_json, ljgapd_respond_reply,
 * ljgapd_respond_problem, ljgapd_respond_busy, ljgapd_respond_cancelled and ljgapd_respond_file;
 * none builds a response by hand. Problems written here are the HTTP-level ones (404, 405, 413,
 * 415, 503, 500); the handler writes its own (400, 404, 406, 422) with the same base URI,
 * /problems/ (problems.h: each type is a page the daemon serves), and openapi.json lists them all.
 */
#include "daemon.h"
#include "problems.h"
#include "webfiles.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#define PROBLEM_BASE LJGAP_PROBLEM_BASE /* a page of this server, as in handler.c */

/* Adds the common headers (and Retry-After to a 503 that has none: openapi.json says every 503
 * has it), queues resp and records the status. Takes ownership of resp. */
static enum MHD_Result respond(struct MHD_Connection *c, request *r, int status,
                               struct MHD_Response *resp, const char *ctype)
{
    enum MHD_Result ret;

    if (!resp) return MHD_NO; /* out of memory: drop the connection, nothing else can be sent */
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, ctype);
    MHD_add_response_header(resp, "X-Request-Id", r->id);
    MHD_add_response_header(resp, "X-Content-Type-Options", "nosniff");
    /* The page loads nothing from elsewhere and runs no inline code. */
    MHD_add_response_header(resp, "Content-Security-Policy", "default-src 'self'");
    if (status == MHD_HTTP_SERVICE_UNAVAILABLE &&
        !MHD_get_response_header(resp, MHD_HTTP_HEADER_RETRY_AFTER)) {
        char retry[16];
        snprintf(retry, sizeof retry, "%u", ljgapd_srv.cfg.retry_after);
        MHD_add_response_header(resp, MHD_HTTP_HEADER_RETRY_AFTER, retry);
    }
    if (atomic_load(&ljgapd_srv.stopping) || r->close)
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CONNECTION, "close");
    ret = MHD_queue_response(c, (unsigned)status, resp);
    MHD_destroy_response(resp);
    if (ret == MHD_YES) r->status = status;
    return ret;
}

enum MHD_Result ljgapd_respond_json_hdr(struct MHD_Connection *c, request *r, int status,
                                        const char *ctype, const char *body, size_t len,
                                        const char *header, const char *value)
{
    struct MHD_Response *resp =
        MHD_create_response_from_buffer(len, (void *)body, MHD_RESPMEM_MUST_COPY);
    if (resp && header) MHD_add_response_header(resp, header, value);
    return respond(c, r, status, resp, ctype);
}

enum MHD_Result ljgapd_respond_json(struct MHD_Connection *c, request *r, int status,
                                    const char *ctype, const char *body, size_t len)
{
    return ljgapd_respond_json_hdr(c, r, status, ctype, body, len, NULL, NULL);
}

enum MHD_Result ljgapd_respond_reply(struct MHD_Connection *c, request *r, ljgap__reply *rep)
{
    enum MHD_Result ret =
        ljgapd_respond_json(c, r, rep->status, rep->content_type, rep->body, rep->len);
    ljgap__reply_free(rep);
    return ret;
}

/* Problem types of the answers written here (their titles are problems.c's, as the
 * handler's are: one title per type). */
static const char *problem_slug(int status)
{
    switch (status) {
    case MHD_HTTP_NOT_FOUND:
        return "not-found";
    case MHD_HTTP_METHOD_NOT_ALLOWED:
        return "method-not-allowed";
    case MHD_HTTP_CONTENT_TOO_LARGE:
        return "content-too-large";
    case MHD_HTTP_UNSUPPORTED_MEDIA_TYPE:
        return "unsupported-media-type";
    case MHD_HTTP_SERVICE_UNAVAILABLE:
        return "busy";
    default:
        return "out-of-memory";
    }
}

/* A problem of type slug (a row of problems.c) with status. */
static enum MHD_Result problem_answer(struct MHD_Connection *c, request *r, int status,
                                      const char *slug, const char *detail, const char *header,
                                      const char *value)
{
    const ljgap__problem_doc *doc = ljgap__problem_find(slug);
    cJSON *p = cJSON_CreateObject();
    char type[64], *text = NULL;
    struct MHD_Response *resp = NULL;

    snprintf(type, sizeof type, PROBLEM_BASE "%s", slug);
    if (p && doc && cJSON_AddStringToObject(p, "type", type) &&
        cJSON_AddStringToObject(p, "title", doc->title) &&
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

enum MHD_Result ljgapd_respond_problem(struct MHD_Connection *c, request *r, int status,
                                       const char *detail, const char *header, const char *value)
{
    return problem_answer(c, r, status, problem_slug(status), detail, header, value);
}

enum MHD_Result ljgapd_respond_cancelled(struct MHD_Connection *c, request *r, const char *detail)
{
    return problem_answer(c, r, MHD_HTTP_SERVICE_UNAVAILABLE, "unavailable", detail,
                          MHD_HTTP_HEADER_RETRY_AFTER, "1");
}

enum MHD_Result ljgapd_respond_busy(struct MHD_Connection *c, request *r, const char *detail,
                                    unsigned seconds)
{
    char retry[16];
    snprintf(retry, sizeof retry, "%u", seconds);
    return ljgapd_respond_problem(c, r, MHD_HTTP_SERVICE_UNAVAILABLE, detail,
                                  MHD_HTTP_HEADER_RETRY_AFTER, retry);
}

enum MHD_Result ljgapd_respond_file(struct MHD_Connection *c, request *r, int fd, size_t size,
                                    const char *ctype)
{
    struct MHD_Response *resp = MHD_create_response_from_fd(size, fd);
    if (!resp) close(fd);
    return respond(c, r, MHD_HTTP_OK, resp, ctype);
}

enum MHD_Result ljgapd_respond_static(struct MHD_Connection *c, request *r, const void *data,
                                      size_t len, const char *ctype, const char *etag,
                                      const char *if_none_match)
{
    int fresh = ljgapd_web_etag_match(if_none_match, etag);
    struct MHD_Response *resp =
        MHD_create_response_from_buffer(fresh ? 0 : len, (void *)data, MHD_RESPMEM_PERSISTENT);
    if (resp) {
        MHD_add_response_header(resp, MHD_HTTP_HEADER_ETAG, etag);
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-cache");
    }
    return respond(c, r, fresh ? MHD_HTTP_NOT_MODIFIED : MHD_HTTP_OK, resp, ctype);
}

enum MHD_Result ljgapd_respond_too_large(struct MHD_Connection *c, request *r)
{
    char detail[64];
    snprintf(detail, sizeof detail, "the request body is limited to %zu bytes",
             r->limit ? r->limit : ljgapd_srv.cfg.max_body);
    return ljgapd_respond_problem(c, r, MHD_HTTP_CONTENT_TOO_LARGE, detail, NULL, NULL);
}

enum MHD_Result ljgapd_respond_over_budget(struct MHD_Connection *c, request *r, size_t need,
                                           const char *what, size_t bytes)
{
    char detail[240], a[32], b[32], m[32];
    budget_format(need, a, sizeof a);
    budget_format(bytes, b, sizeof b);
    budget_format(ljgapd_srv.cfg.max_memory, m, sizeof m);
    snprintf(detail, sizeof detail,
             "the request needs about %s of memory, more than %s (%s) of this server's memory "
             "budget (--max-memory %s) ever allows: send a smaller one",
             a, what, b, m);
    r->close = r->close || !r->body; /* an unread body is not read */
    return ljgapd_respond_problem(c, r, MHD_HTTP_CONTENT_TOO_LARGE, detail, NULL, NULL);
}

enum MHD_Result ljgapd_respond_no_memory(struct MHD_Connection *c, request *r, const char *what,
                                         size_t need)
{
    char detail[240], a[32], m[32];
    budget_format(need, a, sizeof a);
    budget_format(ljgapd_srv.cfg.max_memory, m, sizeof m);
    snprintf(r->note, sizeof r->note, " (memory budget in use: %s refused)", a);
    snprintf(detail, sizeof detail,
             "%s needs %s of memory and the server's memory budget (--max-memory %s) is in use "
             "by other requests now: retry after the given seconds",
             what, a, m);
    return ljgapd_respond_busy(c, r, detail, pool_retry_after(ljgapd_srv.slots));
}
