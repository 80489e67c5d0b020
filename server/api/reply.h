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
    char *body;               /* malloc'd, NUL-terminated; free with ljgap_reply_free */
    size_t len;               /* strlen(body) */
    const char *content_type; /* "application/json", "application/problem+json", text/csv
                               * (csv.h) or text/html (problems.h) */
} ljgap_reply;

/* Frees r->body and empties *r (NULL is fine). */
void ljgap_reply_free(ljgap_reply *r);

#endif
