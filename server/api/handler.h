/* handler.h -- the one request handler behind the CLI, the HTTP daemon and the fuzzer.
 *
 * A pure function: endpoint name + JSON request body (+ the Accept header) -> HTTP status +
 * body (the contract is docs/api.md). It validates (422 problem+json with a JSON pointer per
 * bad field), converts to core calls, and serialises results as JSON or, where the endpoint
 * has one and Accept asks for it, as CSV (csv.h). It never touches sockets or files.
 */
#ifndef LJGAP_HANDLER_H
#define LJGAP_HANDLER_H

#include "settings.h" /* ljgap__limits, ljgap__call, ljgap__param */
#include "reply.h"  /* ljgap__reply, ljgap__reply_free */

#include <stddef.h>

/* Endpoint names: "adhesion", "traction", "pdf", "sweep", "contact", "psd", "psd/combine".
 * Unknown endpoint -> 404 problem. Always fills *out (status 500 with a problem body if
 * memory runs out). Thread-safe. JSON answers (ljgap__handle_call with no call). */
void ljgap__handle(const char *endpoint, const char *body, size_t len, ljgap__reply *out);

/* ljgap__handle with per-call settings (call may be NULL: the same as ljgap__handle). */
void ljgap__handle_call(const char *endpoint, const char *body, size_t len, const ljgap__call *call,
                       ljgap__reply *out);

/* Is this endpoint name one the handler computes (so the HTTP layer can answer 404/405)? */
int ljgap__handler_has(const char *endpoint);

/* ---- text uploads: psd's height matrix as text/plain or text/csv ----
 * The body is the matrix (one row a line, numbers in metres separated by white space or
 * commas, '#' comments), the query parameters carry the rest of the request: dx, dy, periodic
 * and, optionally, the material's fields (E_star or E1, nu1, E2, nu2; dgamma; epsilon). The
 * answer is the one ljgap__handle("psd") gives for the same map as JSON. Problems are 422 with
 * the pointer the same field has in the JSON request (/topography/heights/ROW/COL, whose
 * detail names the line and column; /topography/dx; /material/E_star; an unknown parameter at
 * /NAME); an endpoint without a text form is 404. Bodies up to LJGAP_TEXT_MAX_BYTES are meant
 * (the daemon enforces it); the map itself is capped by limits.max_topo_points. call may be
 * NULL, as for ljgap__handle_call. */

void ljgap__handle_text(const char *endpoint, const ljgap__param *params, size_t nparams,
                       const char *body, size_t len, const ljgap__call *call, ljgap__reply *out);
/* ---- instrument files: psd's height map as a file (psd.c; server/files/ reads it) ----
 * The body is the file's bytes (len of them), its format recognised by content; the query
 * parameters are the text upload's plus format (a format's name, forcing it) and channel (an
 * index or a title; default the height channel). dx, dy come from the file (the query gives
 * them only for a file that states no size). The answer is psd's with "source" (what the file
 * said); problems: 415 no format read here, 422 bad-file (format, offset or member), 422 at
 * /channel or /format, 413 a map over the server's cap. call may be NULL. */
void ljgap__handle_file(const char *endpoint, const ljgap__param *params, size_t nparams,
                       const unsigned char *body, size_t len, const ljgap__call *call,
                       ljgap__reply *out);
/* Does this endpoint take a text upload ("psd")? */
int ljgap__handler_has_text(const char *endpoint);

/* ---- ljgap combine: the body of POST /v1/psd/combine from documents ----
 * Each of docs[0..n) (lens[i] bytes of JSON) is a /v1/psd answer or a psd object: an answer's
 * psd object (a table with P_err; an answer whose psd is null or has no P_err is an error that
 * says so), a psd object ({k, P, P_err, ...}) as it is. per_decade > 0 adds
 * points_per_decade. Returns the body
 * (malloc'd; free it), or NULL with the reason in err. */
char *ljgap__combine_body(const char *const *docs, const size_t *lens, size_t n, double per_decade,
                         char *err, size_t errlen);

/* ---- simulations: the numerical model (ljgap_sim.h) as a job ----
 * Not an endpoint of ljgap__handle: a run takes minutes, so the daemon queues it (jobs.h) and
 * the CLI runs it in the foreground. Both go through these calls, so the validation, the
 * problems and the answer are the same (api.md "simulations"). Parse and free are pure and
 * thread-safe like ljgap__handle; run uses only its own request. */
typedef struct ljgap__sim_request ljgap__sim_request;

/* How a run is driven: everything may be zero. */
typedef struct {
    double max_seconds;         /* wall-time cap of the run; <= 0: the core's default (600 s) */
    const volatile int *cancel; /* nonzero stops the run (a 503 "unavailable" problem) */
    void (*progress)(void *ctx, double fraction); /* fraction done, 0..1, now and then */
    void *progress_ctx;                           /* first argument of progress */
} ljgap__sim_control;

/* Validates a POST /v1/simulations body. Returns the request, to be run once and freed, or
 * NULL with *out filled with the problem (400 malformed JSON, 422 with a pointer per bad
 * field, 500 out of memory). */
ljgap__sim_request *ljgap__sim_request_parse(const char *body, size_t len, ljgap__reply *out);
/* Runs it (ljgap_sim_run) and fills *out: 200 with the result object (g_ave, sigma,
 * sigma_std, m0_realized, elapsed_ms, error, ... and meta; for the hybrid also k_split and
 * fine), or a problem. */
void ljgap__sim_request_run(ljgap__sim_request *rq, const ljgap__sim_control *ctl, ljgap__reply *out);
void ljgap__sim_request_free(ljgap__sim_request *rq); /* NULL is fine */

/* The answer to GET /v1/simulations/ID, given the job's status object (the JSON string of
 * jobs.h's ljgap__jobs_status) and the HTTP status it goes with (200, or 202 while a cancelled
 * job is still stopping): that object as application/json, or, when accept prefers text/csv
 * and the job is done, its result as CSV; 406 when accept allows neither (or only CSV while
 * the job is not done). */
void ljgap__sim_status_answer(const char *status_json, int http_status, const char *accept,
                             ljgap__reply *out);

#endif
