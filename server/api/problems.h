/* problems.h -- the problem types of every application/problem+json answer, and their pages.
 *
 * Each answer's "type" is a relative URI, /problems/SLUG (RFC 9457 §3.1.1: resolved against
 * the request's URI, so it names a page on the server that sent it). The table here is the one
 * list of them: what each means and how to fix the request. The daemon serves
 * GET /problems/SLUG from it as a small HTML page, and GET /problems/ as the index of all.
 * openapi.json lists the same set (a test checks that every type it lists resolves).
 */
#ifndef LJGAP_PROBLEMS_H
#define LJGAP_PROBLEMS_H

#include "ljgap.h" /* ljgap_warnings */
#include "reply.h"

#define LJGAP_PROBLEM_BASE "/problems/" /* every problem type starts with this */

typedef struct {
    const char *slug;    /* the last path segment of the type URI */
    int status;          /* the HTTP status it comes with */
    const char *title;   /* short, as in the answer's "title" */
    const char *meaning; /* what went wrong (one or two sentences) */
    const char *fix;     /* what to change in the request */
} ljgap__problem_doc;

/* The entry for slug, or NULL. */
const ljgap__problem_doc *ljgap__problem_find(const char *slug);
/* Entry i (0, 1, ...), NULL past the last. */
const ljgap__problem_doc *ljgap__problem_at(size_t i);

/* The page of a problem type: rest is what follows /problems/ in the path ("" for the index
 * of all types). Fills *out with 200 text/html, or 404 problem+json for an unknown slug, or
 * the out-of-memory problem (free with ljgap__reply_free). */
void ljgap__problem_page(const char *rest, ljgap__reply *out);

/* A problem answer of type /problems/SLUG (its status and title from the table above) with this
 * detail and an empty errors[]. */
void ljgap__reply_problem(ljgap__reply *out, const char *slug, const char *detail);

/* "; "-joined warnings after prefix into buf (a problem's detail). */
void ljgap__ans_join_warnings(char *buf, size_t size, const char *prefix, const ljgap_warnings *w);

#endif
