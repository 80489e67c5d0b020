/* problems.c -- the table of problem types and the pages the daemon serves for them.
 *
 * One row per type that any answer uses (the handler's, the daemon's); the handler takes the
 * status and title from here, and the daemon serves /problems/SLUG from the same row, so a
 * type cannot be answered without a page that explains it. The pages are plain HTML with no
 * inline code or style (the daemon's Content-Security-Policy is default-src 'self'); they link
 * the page's own style sheet.
 */
#include "problems.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "textbuf.h"

static const ljgap__problem_doc docs[] = {
    {"malformed-json", 400, "Malformed JSON",
     "The request body is not exactly one JSON value in UTF-8: it is empty, cut short, has "
     "text after the value, or has bytes that are not UTF-8. The detail gives the byte "
     "offset where reading stopped.",
     "Send one JSON object as the body, encoded in UTF-8. Check quoting (JSON wants double "
     "quotes), trailing commas and the end of the body; jq . &lt; request.json shows where "
     "a file goes wrong."},
    {"not-found", 404, "Not found",
     "Nothing answers at this path: a misspelt endpoint (the compute endpoints are "
     "/v1/adhesion, /v1/traction, /v1/pdf, /v1/sweep, /v1/contact and /v1/simulations), a "
     "file the page does not have, or a simulation job that never existed or was dropped "
     "(finished jobs are kept for an hour, and only the most recent ones).",
     "Check the path against /openapi.json. For a simulation job, submit it again."},
    {"method-not-allowed", 405, "Method not allowed",
     "The path exists but does not take this method: compute endpoints take POST, the page, "
     "/healthz, /version and /openapi.json take GET and HEAD, a simulation job takes GET, "
     "HEAD and DELETE.",
     "Use one of the methods in the answer's Allow header."},
    {"not-acceptable", 406, "Not acceptable",
     "The request's Accept header allows no form this endpoint can answer in. Every endpoint "
     "answers application/json; traction, pdf, sweep and finished simulation jobs also answer "
     "text/csv. A simulation job that is not done yet has only its JSON status.",
     "Ask for application/json or text/csv (where offered), or leave Accept out. To take CSV "
     "when it is there and the JSON status otherwise, send Accept: text/csv, "
     "application/json;q=0.5."},
    {"content-too-large", 413, "Content too large",
     "The request body is larger than the server accepts (1 MiB by default; 64 MiB for a "
     "height matrix sent to /v1/psd as text), or the request could never fit the server's "
     "memory budget (--max-memory): a body larger than the share bodies may hold, or a "
     "computation or simulation whose working memory is larger than one may hold. The detail "
     "names the limit.",
     "Send fewer points: a table PSD of at most 10 000 rows, at most 10 000 mean gaps or "
     "sweep values. Thin out a measured spectrum or a height map before sending it; for a "
     "simulation, a smaller n. The server's operator can raise --max-memory."},
    {"unsupported-media-type", 415, "Unsupported media type",
     "The body was not declared as a type the path takes, or /v1/psd was sent a file of no "
     "format it reads. Compute requests must say Content-Type: application/json (curl's -d "
     "alone sends application/x-www-form-urlencoded); /v1/psd also takes a height matrix as "
     "text/plain or text/csv, and an instrument file as application/octet-stream (NanoScope, "
     "X3P, .sur, .gwy, .gsf, netCDF, MetroPro .dat, .ibw, Park .tiff, .plu, xyz columns), "
     "recognised by its content. The Accept-Post header lists the types; for a file, the "
     "detail lists the formats read.",
     "Add the header Content-Type: application/json (curl -H 'Content-Type: "
     "application/json'), or one of the types in Accept-Post. For an instrument file, export "
     "it from the instrument's software in one of the formats listed (Gwyddion converts "
     "many others to .gwy or .gsf)."},
    {"bad-file", 422, "Unreadable instrument file",
     "The body is an instrument file of a format /v1/psd reads (the problem's format member "
     "names it), but it cannot be read: it is cut short (a truncated upload), or corrupt or "
     "inconsistent (a header whose grid does not fit its data, a value that is no number). "
     "The problem's offset member gives the byte where reading failed, or member the part of "
     "a container (a zip member of X3P, a GWY container member).",
     "Send the whole file as it was written (curl --data-binary @FILE, not -d, which strips "
     "line ends); check that the upload was not cut short; open the file in the instrument's "
     "software or in Gwyddion and export it again. If format= forced a format, check it."},
    {"validation", 422, "Invalid request",
     "The body is valid JSON but some values are not: a missing or unknown field, a wrong "
     "type, a number out of range, a spectrum outside the theory (k1 at or below k0 = "
     "0.46978, D outside (2, 3)), or a request over one of the server's caps. Every bad field "
     "is listed in errors[], each with a JSON pointer to it (/psd/k1, /g_ave/n, ...) and what "
     "is wrong with it.",
     "Change the fields the pointers name, as each entry's detail says; all of them are "
     "reported at once, so one corrected request should pass. The fields, their ranges and "
     "defaults are in /openapi.json."},
    {"outside-model", 422, "Outside the model",
     "The request passed validation but the computation found the spectrum outside the "
     "model's domain (for example a PSD whose height variance is not a finite positive "
     "number). errors[] points at /psd.",
     "Check the PSD: its level (C, m0 or h_rms), its cut-offs and, for a table, its values "
     "and tail exponent."},
    {"cap-exceeded", 422, "Over the server's caps",
     "The computation needs more than the server allows for one request: wall time (20 s "
     "by default), grid points times steps, bands or Monte Carlo samples. For a simulation "
     "job, the run did not finish within its time cap.",
     "Ask for a larger tol, fewer mean gaps or sweep values, fewer samples; for a "
     "simulation, a smaller n, fewer realizations or fewer mean gaps. Spectra with D close "
     "to 3 and no upper cut-off are expensive: give a finite k2."},
    {"no-answer", 422, "No finite answer",
     "The computation ran but could not form a finite answer, for example a traction curve "
     "with no equilibrium gap inside the range it explored. The detail and the warnings say "
     "what failed.",
     "Move the request towards the model's comfortable range: a smaller height variance, k1 "
     "further above k0, a finite k2, or another method as a cross-check."},
    {"busy", 503, "Busy",
     "The server is too busy to take the request now: it waited --queue-wait seconds (10 by "
     "default) without a free compute slot, or the wait queue was already full (--queue, 64 "
     "by default), or this client already has --client-connections requests in progress "
     "behind a proxy, or the queue of simulation jobs is full, or the server is shutting "
     "down, or its memory budget (--max-memory) is in use by other requests: a body that "
     "does not fit now is refused before it is read, a computation waits for memory as for a "
     "slot. Slots go to the waiting client that holds the fewest, so one person's batch "
     "cannot starve another.",
     "Retry after the number of seconds in the Retry-After header (an estimate of the queue "
     "ahead). The page does this by itself. A script sending many requests at once can send "
     "them a few at a time instead."},
    {"unavailable", 503, "Computation cancelled",
     "The computation was stopped before it finished: the server is shutting down, the "
     "simulation job was cancelled (DELETE, or Ctrl-C on the command line), or the client's "
     "connection closed (or was shut down for sending) while the request waited or ran.",
     "Send the request again once the server is back; submit the simulation again. Keep the "
     "connection open until the answer arrives."},
    {"job-store", 503, "Job store unavailable",
     "The simulation jobs' store (the SQLite database in the daemon's state directory) could "
     "not be read or written just now: a full disk, a file locked by another program, an I/O "
     "error. Computations that are not jobs are not affected.",
     "Retry after the seconds in Retry-After. If it persists, tell whoever runs the server: "
     "the daemon's log names the reason."},
    {"job-damaged", 500, "Job record damaged",
     "A simulation job's stored record could not be shown or run as stored: a field read back "
     "from the store is not what the server writes (the detail names it). The record was "
     "changed outside the server, or the disk damaged it.",
     "Submit the simulation again; it gets a new id. Tell whoever runs the server if it "
     "happens again."},
    {"job-abandoned", 500, "Job abandoned",
     "The simulation job was started 3 times and each time the server stopped or crashed "
     "before it finished, so it is not run again (a job that crashes the server must not "
     "crash it for ever).",
     "Check the request (a smaller n, fewer realizations or mean gaps) and submit it again; "
     "tell whoever runs the server, whose log says what happened."},
    {"out-of-memory", 500, "Out of memory", "The server ran out of memory while answering.",
     "Try a smaller request (fewer points, a coarser grid); if it persists, tell whoever runs "
     "the server."},
};

#define N_DOCS (sizeof docs / sizeof docs[0])

const ljgap__problem_doc *ljgap__problem_find(const char *slug)
{
    for (size_t i = 0; slug && i < N_DOCS; i++)
        if (strcmp(docs[i].slug, slug) == 0) return &docs[i];
    return NULL;
}

const ljgap__problem_doc *ljgap__problem_at(size_t i)
{
    return i < N_DOCS ? &docs[i] : NULL;
}

static void page_head(ljgap__textbuf *b, const char *title)
{
    ljgap__textbuf_printf(
        b,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
        "<title>%s - ljgap</title>\n"
        "<link rel=\"icon\" href=\"/favicon.svg\" type=\"image/svg+xml\">\n"
        "<link rel=\"stylesheet\" href=\"/style.css\">\n</head>\n<body>\n<main>\n",
        title);
}

static void page_foot(ljgap__textbuf *b)
{
    ljgap__textbuf_printf(b, "<p><a href=\"" LJGAP_PROBLEM_BASE "\">All problem types</a> · "
                            "<a href=\"/\">the ljgap page</a> · "
                            "<a href=\"/openapi.json\">the API description</a></p>\n"
                            "</main>\n</body>\n</html>\n");
}

void ljgap__problem_page(const char *rest, ljgap__reply *out)
{
    const ljgap__problem_doc *d = NULL;
    ljgap__textbuf b = {0};
    memset(out, 0, sizeof *out);
    if (rest && rest[0]) {
        if (!(d = ljgap__problem_find(rest))) {
            ljgap__reply_problem(out, "not-found",
                                "no such problem type; the list is at " LJGAP_PROBLEM_BASE);
            return;
        }
        page_head(&b, d->title);
        ljgap__textbuf_printf(&b,
                             "<h1>%s</h1>\n<p><code>" LJGAP_PROBLEM_BASE "%s</code> · HTTP %d, "
                             "application/problem+json</p>\n<h2>What it means</h2>\n<p>%s</p>\n"
                             "<h2>How to fix the request</h2>\n<p>%s</p>\n",
                             d->title, d->slug, d->status, d->meaning, d->fix);
    } else {
        page_head(&b, "Problem types");
        ljgap__textbuf_printf(&b, "<h1>Problem types</h1>\n<p>Every answer with a 4xx or 5xx "
                                 "status is an RFC 9457 problem (application/problem+json) "
                                 "whose <code>type</code> is one of these pages.</p>\n<ul>\n");
        for (size_t i = 0; i < N_DOCS; i++)
            ljgap__textbuf_printf(
                &b, "<li><a href=\"" LJGAP_PROBLEM_BASE "%s\">%s</a>: HTTP %d, %s</li>\n",
                docs[i].slug, docs[i].slug, docs[i].status, docs[i].title);
        ljgap__textbuf_printf(&b, "</ul>\n");
    }
    page_foot(&b);
    if (b.oom) {
        ljgap__reply_problem(out, "out-of-memory", "the server ran out of memory");
        return;
    }
    out->status = 200;
    out->body = b.s;
    out->len = b.len;
    out->content_type = "text/html; charset=utf-8";
}

/* "; "-joined warnings after prefix into buf. */
void ljgap__ans_join_warnings(char *buf, size_t size, const char *prefix, const ljgap_warnings *w)
{
    size_t used = (size_t)snprintf(buf, size, "%s", prefix);
    for (int i = 0; i < w->n && used < size; i++)
        used += (size_t)snprintf(buf + used, size - used, "%s%s", i ? "; " : ": ", w->msg[i]);
}
