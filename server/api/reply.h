/* reply.h -- the reply type: what every layer of the server answers with.
 *
 * The request handler (handler.h) fills one, and so do the CSV writer (csv.h), the problem pages
 * (problems.h) and the job runner (jobs.h); the daemon (ljgapd/respond.c) and the CLI turn it
 * into an HTTP response or an exit status. It lives in its own header so that those modules
 * include it downward instead of reaching up into the handler.
 */
#ifndef LJGAP_REPLY_H
#define LJGAP_REPLY_H

#include <stddef.h>

typedef struct {
    int status;               /* HTTP status code */
    char *body;               /* malloc'd, NUL-terminated; free with ljgap__reply_free */
    size_t len;               /* strlen(body) */
    const char *content_type; /* "application/json", "application/problem+json", text/csv
                               * (csv.h) or text/html (problems.h) */
    int cacheable;            /* set by the handler (ljgap__handle_call) on a 200 JSON answer
                               * whose body ends with LJGAP_REPLY_UNCACHED_TAIL: a cache may
                               * keep it with that tail replaced by LJGAP_REPLY_CACHED_TAIL.
                               * 0 for everything else (CSV, problems, pages). */
} ljgap__reply;

/* The last bytes of a cacheable answer (meta.cached, meta's last member, meta the answer's last)
 * and what a cache answers instead. */
#define LJGAP_REPLY_UNCACHED_TAIL "\"cached\":false}}"
#define LJGAP_REPLY_CACHED_TAIL "\"cached\":true}}"

/* Frees r->body and empties *r (NULL is fine). */
void ljgap__reply_free(ljgap__reply *r);

#endif
