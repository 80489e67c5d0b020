/* fuzz_handler.c -- libFuzzer target on ljgap__handle_call, the one request handler.
 *
 * An input is "ENDPOINT\nBODY" or "ENDPOINT\tACCEPT\nBODY": the first line names the endpoint
 * (adhesion, traction, pdf, sweep, contact, psd, psd/combine, or anything else for a 404;
 * "simulations" goes through ljgap__sim_request_parse and, when valid, ljgap__sim_request_run,
 * and then, when there is an Accept, its result through ljgap__sim_status_answer as a finished job's
 * status; "text:NAME?QUERY" is a text upload, ljgap__handle_text with the query split at '&' and '='
 * into parameters, as the daemon hands them over after decoding), and after a tab the value of
 * the Accept header; the rest is the request body, handed over in a buffer of exactly its
 * length (no NUL after it), so that any read past the end is caught by AddressSanitizer. An
 * input without a newline is all endpoint name and an empty body.
 *
 * Besides crashes, leaks and undefined behaviour (the sanitizers), every answer is checked
 * against the contract (docs/api.md) and the handler's own rules, and any breach aborts (the
 * fuzzer keeps the input):
 *   - status is 200, 400, 404, 406 or 422 (500 would be out of memory, 503 a cancel: neither
 *     happens here), 404 exactly when the endpoint is unknown, 406 only with an Accept;
 *   - a text/csv answer (200 only) is valid UTF-8 and well formed: '#' comment lines, then a
 *     header, then rows with as many cells as the header, each cell empty, a finite number,
 *     inf, true or false;
 *   - any other body is exactly one JSON object in valid UTF-8 (RFC 8259 §8.1), len ==
 *     strlen(body), and every number in it is finite; the content type is application/json for 200,
 * application/problem+json else;
 *   - 200: meta {method, elapsed_ms >= 0, version, warnings[] of strings, cached false},
 *     an "error" object (a sweep's in its first result), an "error" object in every "si" that
 *     holds more than the scales (a sweep's in each of si.results that is not null), and no
 *     warning saying a result was not finite (that would be NaN or Inf computed by the core and
 *     papered over with null; the SI errors' labels are si.error...);
 *   - problems: type /problems/..., title, status equal to the HTTP
 *     status, detail, errors[] of {pointer, detail}; every pointer is a well-formed RFC 6901
 *     pointer that names a member of the request or a missing member of one that exists; for a
 *     text upload, a cell, row or the whole of /topography/heights within the lines sent, a
 *     field of /topography, /fit or /material, or /NAME of a parameter that was sent.
 *
 * The pseudo-endpoint "@x-forwarded-for" feeds the body (up to its first NUL) to
 * ljgapd_forwarded_client, the daemon's reading of an X-Forwarded-For header: it must answer 0
 * with an empty name, or 1 with a numeric address that fits the buffer, for buffers of any size.
 *
 * The pseudo-endpoint "@max-memory" feeds the body (up to its first NUL) to budget_parse_size,
 * the daemon's reading of --max-memory SIZE: it must refuse (-1) or give exactly the digits times
 * the suffix's power of 1024, nonzero and at most 2^50 bytes.
 *
 * The pseudo-endpoint "@heights" checks the count of a text height matrix's values that the
 * daemon makes as the body arrives (memest.h, its memory estimate): counted in two pieces split
 * anywhere it is the count of the whole, and it bounds the heights the parser reads
 * (ljgap__topo_text_parse), so the estimate made from it bounds the computation's memory.
 *
 * The pseudo-endpoint "@jobrow" fuzzes what the daemon reads back from its job store (a
 * database row is input too). The body's first seven lines are a job record's id, state,
 * progress, created, started, finished and now (numbers through strtod, so inf, nan and hex
 * come through), the rest is the stored answer (none when there are fewer lines); the record
 * goes through ljgap__job_status_json, whose answer must be one JSON object in valid UTF-8 with
 * finite numbers, a known status, progress in [0, 1], elapsed_ms >= 0, a result object exactly
 * when done and a well-formed problem whenever it failed.
 *
 * The pseudo-endpoint "@pgrow" fuzzes the PostgreSQL job store's reading of a row: the body's
 * lines are the row's columns in libpq's text format (jobstore.h, LJGAP_PG_*; "\\N" for NULL;
 * thirteen lines make a claim's row, with the request in bytea hex), read by
 * ljgap__jobstore_pg_row into a record that must stay within its bounds and then pass the same
 * checks as "@jobrow".
 *
 * The handler's limits are lowered (fuzz_limits, and sim_control for simulations) so each
 * input runs in milliseconds; a computation that ignored them would trip libFuzzer's -timeout.
 *
 * The same file is linked into build/.../fuzz/replay (tests/fuzz/replay.c) with the normal
 * compiler: there a breach is counted (ljgap__fuzz_failures) instead of aborting.
 */
#include "budget.h"
#include "forwarded.h"
#include "handler.h"
#include "memest.h"
#include "request.h"
#include "topo_text.h"
#include "jobstatus.h"
#include "jobstore.h"

#include <arpa/inet.h>
#include <netinet/in.h>

#include <cjson/cJSON.h>
#include <gsl/gsl_errno.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <wchar.h>

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Set by the replay driver: count breaches instead of aborting. */
int ljgap__fuzz_noabort;
long ljgap__fuzz_failures;

/* The lowered limits: short computations, few points, few samples, two sweep threads. */
static const ljgap__limits fuzz_limits = {.max_seconds = 0.25,
                                         .max_samples = 2000,
                                         .max_points = 16,
                                         .sweep_threads = 2,
                                         .max_topo_points = 4096,
                                         .cancel = NULL};

/* A simulation runs for at most this long (it answers 422 cap-exceeded beyond). */
static const ljgap__sim_control sim_control = {.max_seconds = 0.25};

static void breach(const char *ep, const ljgap__reply *r, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void breach(const char *ep, const ljgap__reply *r, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "fuzz_handler: endpoint \"%.40s\", status %d: ", ep, r->status);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\n  body: %.600s\n", r->body ? r->body : "(null)");
    ljgap__fuzz_failures++;
    if (!ljgap__fuzz_noabort) abort();
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    gsl_set_error_handler_off();
    if (!setlocale(LC_CTYPE, "C.UTF-8")) {
        fprintf(stderr, "fuzz_handler: no C.UTF-8 locale to check answers with\n");
        abort();
    }
    ljgap__handler_set_limits(&fuzz_limits);
    return 0;
}

/* Is s[0..n) well-formed UTF-8? Decoded by the C library (locale C.UTF-8, which refuses
 * overlong forms, surrogates and code points past U+10FFFF), independently of the server. */
static int utf8_ok(const char *s, size_t n)
{
    mbstate_t st;
    memset(&st, 0, sizeof st);
    for (size_t i = 0, k; i < n; i += k) {
        wchar_t wc;
        k = mbrtowc(&wc, s + i, n - i, &st);
        if (k == (size_t)-1 || k == (size_t)-2) return 0;
        if (k == 0) k = 1; /* a NUL byte (len != strlen is reported on its own) */
    }
    return 1;
}

/* Is every number in v finite? */
static int all_finite(const cJSON *v)
{
    if (cJSON_IsNumber(v)) return isfinite(v->valuedouble);
    for (const cJSON *c = v->child; c; c = c->next)
        if (!all_finite(c)) return 0;
    return 1;
}

/* The member or element of v named by one unescaped pointer token, or NULL. */
static const cJSON *step(const cJSON *v, const char *tok)
{
    if (cJSON_IsObject(v)) return cJSON_GetObjectItemCaseSensitive(v, tok);
    if (!cJSON_IsArray(v) || !*tok || strspn(tok, "0123456789") != strlen(tok) ||
        (tok[0] == '0' && tok[1]) || strlen(tok) > 9)
        return NULL;
    return cJSON_GetArrayItem(v, atoi(tok));
}

/* 0 when ptr is a well-formed RFC 6901 pointer whose target exists in doc, or whose parent
 * exists and is an object (a missing member); else a reason. */
static const char *pointer_problem(const cJSON *doc, const char *ptr)
{
    const cJSON *v = doc, *parent = NULL;
    size_t n = strlen(ptr);
    char *tok = malloc(n + 1);
    const char *why = NULL;
    if (!tok) return NULL;
    if (n && ptr[0] != '/') why = "does not start with /";
    for (const char *p = ptr; !why && *p;) {
        size_t k = 0;
        for (p++; *p && *p != '/'; p++) {
            if (*p == '~' && (p[1] == '0' || p[1] == '1'))
                tok[k++] = *++p == '0' ? '~' : '/';
            else if (*p == '~')
                why = "has a ~ not followed by 0 or 1";
            else
                tok[k++] = *p;
        }
        tok[k] = '\0';
        if (!v) {
            why = parent ? "names a member below a missing one" : "names nothing";
            break;
        }
        parent = v;
        v = step(v, tok);
    }
    if (!why && !v && !cJSON_IsObject(parent)) why = "names nothing in the request";
    free(tok);
    return why;
}

/* A text upload: its parameters and the number of lines of its body. */
typedef struct {
    ljgap__param p[64];
    size_t np;
    size_t lines;
} text_req;

/* 0 when ptr is a pointer a text upload may get (see the top of this file), else a reason. */
static const char *text_pointer_problem(const text_req *t, const char *ptr)
{
    static const char *const fields[] = {"/topography/dx",
                                         "/topography/dy",
                                         "/topography/periodic",
                                         "/topography/detrend",
                                         "/topography/tip_radius",
                                         "/topography/resolution",
                                         "/fit/k_min",
                                         "/fit/k_max",
                                         "/material",
                                         NULL};
    unsigned long row, col;
    int used = 0, more = 0;
    if (strcmp(ptr, "/topography/heights") == 0) return NULL;
    if (sscanf(ptr, "/topography/heights/%lu%n", &row, &used) == 1 &&
        (!ptr[used] || (sscanf(ptr + used, "/%lu%n", &col, &more) == 1 && !ptr[used + more])))
        return row < t->lines ? NULL : "names a row beyond the lines sent";
    for (int i = 0; fields[i]; i++)
        if (strncmp(ptr, fields[i], strlen(fields[i])) == 0) return NULL;
    for (size_t i = 0; i < t->np; i++) {
        char want[200];
        size_t k = 0;
        want[k++] = '/';
        for (const char *c = t->p[i].name; *c && k + 3 < sizeof want; c++) {
            if (*c == '~' || *c == '/')
                want[k++] = '~', want[k++] = *c == '~' ? '0' : '1';
            else
                want[k++] = *c;
        }
        want[k] = '\0';
        /* the server cuts a name at 60 bytes or its first byte that is not UTF-8: a prefix of
         * the name's pointer (down to "/") is fine */
        if (strncmp(want, ptr, strlen(ptr)) == 0) return NULL;
    }
    return "names neither a field nor a parameter that was sent";
}

static void check_problem(const char *ep, const ljgap__reply *r, const cJSON *doc, const cJSON *req,
                          const text_req *text)
{
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(doc, "type");
    const cJSON *st = cJSON_GetObjectItemCaseSensitive(doc, "status");
    const cJSON *errs = cJSON_GetObjectItemCaseSensitive(doc, "errors"), *e;
    if (strcmp(r->content_type, "application/problem+json") != 0)
        breach(ep, r, "a problem sent as %s", r->content_type);
    if (!cJSON_IsString(type) || strncmp(type->valuestring, "/problems/", 10) != 0 ||
        !cJSON_IsString(cJSON_GetObjectItemCaseSensitive(doc, "title")) ||
        !cJSON_IsString(cJSON_GetObjectItemCaseSensitive(doc, "detail")) || !cJSON_IsNumber(st) ||
        st->valuedouble != r->status || !cJSON_IsArray(errs)) {
        breach(ep, r, "not a problem document (type, title, status, detail, errors)");
        return;
    }
    cJSON_ArrayForEach(e, errs)
    {
        const cJSON *p = cJSON_GetObjectItemCaseSensitive(e, "pointer");
        const char *why;
        if (!cJSON_IsString(p) || !cJSON_IsString(cJSON_GetObjectItemCaseSensitive(e, "detail")))
            breach(ep, r, "an errors[] entry without a string pointer and detail");
        else if (req && (why = pointer_problem(req, p->valuestring)))
            breach(ep, r, "pointer \"%.100s\" %s", p->valuestring, why);
        else if (text && (why = text_pointer_problem(text, p->valuestring)))
            breach(ep, r, "pointer \"%.100s\" %s", p->valuestring, why);
    }
}

/* Does the answer's si (if any) carry the errors of what it holds: si.error when it has more
 * than the scales, an error in each si.results[i] that is not null? */
static int si_errors_ok(const cJSON *doc)
{
    const cJSON *si = cJSON_GetObjectItemCaseSensitive(doc, "si");
    const cJSON *res = cJSON_GetObjectItemCaseSensitive(si, "results");
    int computed = 0;
    for (const cJSON *c = si ? si->child : NULL; c; c = c->next)
        computed |= strcmp(c->string, "chi_m") && strcmp(c->string, "sigma0_Pa") &&
                    strcmp(c->string, "E_star_Pa") && strcmp(c->string, "results") &&
                    strcmp(c->string, "error");
    if (res) {
        if (!cJSON_IsArray(res)) return 0;
        for (const cJSON *x = res->child; x; x = x->next)
            if (!cJSON_IsNull(x) && !cJSON_IsObject(cJSON_GetObjectItemCaseSensitive(x, "error")))
                return 0;
    }
    return !computed || cJSON_IsObject(cJSON_GetObjectItemCaseSensitive(si, "error"));
}

static void check_ok(const char *ep, const ljgap__reply *r, const cJSON *doc)
{
    const cJSON *meta = cJSON_GetObjectItemCaseSensitive(doc, "meta"), *w, *ms;
    const cJSON *res = cJSON_GetObjectItemCaseSensitive(doc, "results");
    if (strcmp(r->content_type, "application/json") != 0)
        breach(ep, r, "a 200 answer sent as %s", r->content_type);
    ms = cJSON_GetObjectItemCaseSensitive(meta, "elapsed_ms");
    w = cJSON_GetObjectItemCaseSensitive(meta, "warnings");
    if (!cJSON_IsObject(meta) ||
        !cJSON_IsString(cJSON_GetObjectItemCaseSensitive(meta, "method")) ||
        !cJSON_IsString(cJSON_GetObjectItemCaseSensitive(meta, "version")) ||
        !cJSON_IsFalse(cJSON_GetObjectItemCaseSensitive(meta, "cached")) || !cJSON_IsNumber(ms) ||
        !(ms->valuedouble >= 0) || !cJSON_IsArray(w) ||
        !cJSON_IsObject(cJSON_GetObjectItemCaseSensitive(
            strcmp(ep, "sweep") == 0 ? cJSON_GetArrayItem(res, 0) : doc, "error"))) {
        breach(ep, r,
               "a 200 answer without meta {method, elapsed_ms, version, warnings, "
               "cached} or without error");
        return;
    }
    if (!si_errors_ok(doc)) breach(ep, r, "an si object without the errors of its values");
    for (const cJSON *s = w->child; s; s = s->next) {
        if (!cJSON_IsString(s))
            breach(ep, r, "a warning that is not a string");
        else if (strstr(s->valuestring, "is not a finite number"))
            breach(ep, r, "a non-finite result went out as null: %.200s", s->valuestring);
    }
}

/* "@x-forwarded-for": the header parser, with buffers of several sizes. */
static void fuzz_forwarded(const char *body, size_t len)
{
    static const size_t sizes[] = {0, 1, 8, 16, 46, 64};
    char *xff = malloc(len + 1), out[64];
    unsigned char addr[sizeof(struct in6_addr)];
    ljgap__reply none = {0};
    if (!xff) return;
    memcpy(xff, body, len);
    xff[len] = '\0';
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        int ok;
        memset(out, 'x', sizeof out);
        ok = ljgapd_forwarded_client(xff, out, sizes[i]);
        if (ok != 0 && ok != 1) breach("@x-forwarded-for", &none, "returned %d", ok);
        if (sizes[i] == 0) continue;
        if (!memchr(out, '\0', sizes[i])) breach("@x-forwarded-for", &none, "name not ended");
        if (!ok && out[0]) breach("@x-forwarded-for", &none, "0 with a name");
        if (ok && inet_pton(AF_INET, out, addr) != 1 && inet_pton(AF_INET6, out, addr) != 1)
            breach("@x-forwarded-for", &none, "1 with \"%.64s\", not an address", out);
    }
    free(xff);
}

/* "@max-memory": budget_parse_size refuses or reads exactly DIGITS[KMG][B]. */
static void fuzz_max_memory(const char *body, size_t len)
{
    ljgap__reply none = {0};
    char *s = strndup(body, len), *end = NULL;
    size_t v = 0;
    unsigned long long digits;
    unsigned shift = 0;
    if (!s) return;
    if (budget_parse_size(s, &v) == 0) {
        digits = strtoull(s, &end, 10);
        if (*end && strchr("kK", *end)) shift = 10;
        if (*end && strchr("mM", *end)) shift = 20;
        if (*end && strchr("gG", *end)) shift = 30;
        if (v == 0 || v > (size_t)1 << 50 || v != (size_t)(digits << shift))
            breach("@max-memory", &none, "\"%.40s\" read as %zu", s, v);
    }
    free(s);
}

/* "@heights": the count of values, whole or in two pieces, bounds the heights parsed. */
static void fuzz_heights(const char *body, size_t len)
{
    ljgap__reply none = {0};
    ljgap__token_count whole = {0}, parts = {0};
    ljgap__topo_spec t = {0};
    ljgap__verr ve = {0};
    size_t cut = len ? (unsigned char)body[0] % (len + 1) : 0;
    ljgap__token_feed(&whole, body, len);
    ljgap__token_feed(&parts, body, cut);
    ljgap__token_feed(&parts, body + cut, len - cut);
    if (parts.tokens != whole.tokens)
        breach("@heights", &none, "%zu values in pieces, %zu whole", parts.tokens, whole.tokens);
    if (!(ve.errors = cJSON_CreateArray())) return;
    ljgap__topo_text_parse(body, len, 4096, &t, &ve);
    if (t.h && t.nx * t.ny > whole.tokens)
        breach("@heights", &none, "%zu x %zu heights read, %zu values counted", t.nx, t.ny,
               whole.tokens);
    free(t.h);
    cJSON_Delete(ve.errors);
}

/* The next line of [*p, end) as a NUL-terminated copy in buf (cut at size - 1); 0 at the end. */
static int next_line(const char **p, const char *end, char *buf, size_t size)
{
    const char *nl;
    size_t n;
    if (*p >= end) return 0;
    nl = memchr(*p, '\n', (size_t)(end - *p));
    n = (size_t)((nl ? nl : end) - *p);
    snprintf(buf, size, "%.*s", (int)(n < size ? n : size - 1), *p);
    *p = nl ? nl + 1 : end;
    return 1;
}

/* A record read back, shown as a status object (ep: the pseudo-endpoint, for messages), checked
 * against the contract; frees the record. */
static void check_record(const char *ep, ljgap__job_record *rec)
{
    static const char *const states[] = {"queued", "running", "done", "failed", "cancelled"};
    ljgap__reply r = {0}, pr = {0};
    cJSON *doc = NULL;
    const cJSON *st, *prog, *ms, *res, *prob;
    int known = 0;
    r.status = 200;
    r.content_type = "application/json";
    if (!(r.body = ljgap__job_status_json(rec))) goto end; /* out of memory */
    r.len = strlen(r.body);
    if (!utf8_ok(r.body, r.len)) breach(ep, &r, "not valid UTF-8");
    doc = cJSON_ParseWithLength(r.body, r.len);
    if (!cJSON_IsObject(doc)) {
        breach(ep, &r, "the status is not one JSON object");
        goto end;
    }
    if (!all_finite(doc)) breach(ep, &r, "a number that is not finite");
    st = cJSON_GetObjectItemCaseSensitive(doc, "status");
    prog = cJSON_GetObjectItemCaseSensitive(doc, "progress");
    ms = cJSON_GetObjectItemCaseSensitive(doc, "elapsed_ms");
    res = cJSON_GetObjectItemCaseSensitive(doc, "result");
    prob = cJSON_GetObjectItemCaseSensitive(doc, "problem");
    for (size_t i = 0; cJSON_IsString(st) && i < sizeof states / sizeof states[0]; i++)
        known |= strcmp(st->valuestring, states[i]) == 0;
    if (!known || !cJSON_IsString(cJSON_GetObjectItemCaseSensitive(doc, "id")) ||
        !cJSON_IsNumber(prog) || !(prog->valuedouble >= 0 && prog->valuedouble <= 1) ||
        !cJSON_IsNumber(ms) || !(ms->valuedouble >= 0)) {
        breach(ep, &r, "no id, a status outside the five, or progress or elapsed_ms wrong");
        goto end;
    }
    if ((strcmp(st->valuestring, "done") == 0) != cJSON_IsObject(res) ||
        (strcmp(st->valuestring, "failed") == 0 && !cJSON_IsObject(prob)))
        breach(ep, &r, "a result not exactly when done, or a failure without a problem");
    if (cJSON_IsObject(prob)) { /* checked as if it had been sent on its own */
        const cJSON *ps = cJSON_GetObjectItemCaseSensitive(prob, "status");
        pr = r;
        pr.status = cJSON_IsNumber(ps) ? (int)ps->valuedouble : 0;
        pr.content_type = "application/problem+json";
        check_problem(ep, &pr, prob, NULL, NULL);
    }
end:
    cJSON_Delete(doc);
    free(r.body);
    ljgap__job_record_clear(rec);
}

/* "@jobrow": a stored record, shown as a status object. */
static void fuzz_jobrow(const char *body, size_t len)
{
    const char *p = body, *end = body + len;
    ljgap__job_record rec;
    double *num[] = {&rec.progress, &rec.created, &rec.started, &rec.finished, &rec.now};
    char line[64], state[32] = "";
    int lines = 0;
    memset(&rec, 0, sizeof rec);
    lines += next_line(&p, end, rec.id, sizeof rec.id);
    lines += next_line(&p, end, state, sizeof state);
    rec.state = ljgap__job_state_parse(state);
    for (size_t i = 0; i < sizeof num / sizeof num[0]; i++)
        if (next_line(&p, end, line, sizeof line)) *num[i] = strtod(line, NULL), lines++;
    if (lines == 7) { /* an answer follows, possibly empty */
        rec.answer_len = (size_t)(end - p);
        if (!(rec.answer = malloc(rec.answer_len + 1))) return;
        if (rec.answer_len) memcpy(rec.answer, p, rec.answer_len);
        rec.answer[rec.answer_len] = '\0';
    }
    check_record("@jobrow", &rec);
}

/* "@pgrow": a row of the PostgreSQL job store in libpq's text format, one column a line
 * (LJGAP_PG_* order; "\\N" is SQL NULL; the request column makes it a claim's row), read by
 * ljgap__jobstore_pg_row and then shown as a status object. */
static void fuzz_pgrow(char *body, size_t len)
{
    const char *val[LJGAP_PG_COLS] = {0};
    int lens[LJGAP_PG_COLS] = {0}, ncols = 0;
    ljgap__job_record rec;
    char *p = body, *end = body + len;
    while (p < end && ncols < LJGAP_PG_COLS) {
        char *nl = memchr(p, '\n', (size_t)(end - p));
        size_t n = (size_t)((nl ? nl : end) - p);
        if (!(n == 2 && p[0] == '\\' && p[1] == 'N')) {
            val[ncols] = p;
            lens[ncols] = (int)n;
        }
        ncols++;
        p = nl ? nl + 1 : end;
    }
    memset(&rec, 0, sizeof rec);
    if (ljgap__jobstore_pg_row(&rec, val, lens,
                              ncols == LJGAP_PG_COLS ? LJGAP_PG_COLS : LJGAP_PG_REQUEST) != 0)
        return; /* out of memory: cleared */
    if (strlen(rec.id) > LJGAP_JOB_ID_LEN || strlen(rec.kind) > LJGAP_JOB_KIND_MAX ||
        (rec.request && rec.request[rec.request_len] != '\0') ||
        (rec.answer && rec.answer[rec.answer_len] != '\0') ||
        (ncols < LJGAP_PG_COLS && rec.request)) {
        ljgap__reply none = {0};
        breach("@pgrow", &none, "a record out of its bounds");
    }
    check_record("@pgrow", &rec);
}

/* Is the cell empty, a finite number, inf, true or false? */
static int cell_ok(const char *s, size_t n)
{
    char buf[64], *end;
    double v;
    if (n == 0 || (n == 3 && !memcmp(s, "inf", 3)) || (n == 4 && !memcmp(s, "true", 4)) ||
        (n == 5 && !memcmp(s, "false", 5)))
        return 1;
    if (n >= sizeof buf) return 0;
    memcpy(buf, s, n);
    buf[n] = '\0';
    v = strtod(buf, &end);
    return *end == '\0' && isfinite(v) && !strpbrk(buf, "nNiIxX");
}

/* A CSV answer: '#' lines, a header, rows of as many cells as the header, good cells. */
static void check_csv(const char *ep, const ljgap__reply *r)
{
    const char *p = r->body, *e = r->body + r->len;
    long header = -1, line = 0;
    if (r->status != 200) breach(ep, r, "a CSV answer with status %d", r->status);
    if (r->len == 0 || r->body[r->len - 1] != '\n') breach(ep, r, "CSV that does not end a line");
    for (; p < e; line++) {
        const char *nl = memchr(p, '\n', (size_t)(e - p)), *c = p;
        long cells = 1;
        if (!nl) break;
        if (*p == '#' && header < 0) {
            p = nl + 1;
            continue;
        }
        for (const char *q = p; q < nl; q++)
            cells += *q == ',';
        if (header < 0) {
            header = cells;
        } else {
            if (cells != header)
                breach(ep, r, "CSV line %ld has %ld cells, not %ld", line, cells, header);
            for (const char *q = p; q <= nl; q++)
                if (q == nl || *q == ',') {
                    if (!cell_ok(c, (size_t)(q - c)))
                        breach(ep, r, "CSV line %ld: a bad cell \"%.*s\"", line, (int)(q - c), c);
                    c = q + 1;
                }
        }
        p = nl + 1;
    }
    if (header < 0) breach(ep, r, "CSV without a header line");
}

/* A finished job's status around a simulation's 200 result, answered as accept asks. */
static void sim_status(const char *accept, ljgap__reply *r)
{
    static const char head[] = "{\"id\":\"0\",\"status\":\"done\",\"progress\":1,"
                               "\"elapsed_ms\":1,\"result\":";
    char *st = malloc(sizeof head + r->len + 1);
    if (!st) return;
    memcpy(st, head, sizeof head - 1);
    memcpy(st + sizeof head - 1, r->body, r->len);
    strcpy(st + sizeof head - 1 + r->len, "}");
    ljgap__reply_free(r);
    ljgap__sim_status_answer(st, 200, accept, r);
    free(st);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const uint8_t *nl = memchr(data, '\n', size);
    size_t linelen = nl ? (size_t)(nl - data) : size;
    const uint8_t *tab = memchr(data, '\t', linelen);
    size_t eplen = tab ? (size_t)(tab - data) : linelen;
    size_t len = nl ? size - linelen - 1 : 0;
    char *ep = malloc(eplen + 1), *body = malloc(len ? len : 1), *accept = NULL;
    ljgap__reply r = {0};
    cJSON *doc = NULL, *req = NULL;
    text_req *text = NULL;
    const char *end = NULL;
    int known;
    if (!ep || !body) goto end;
    memcpy(ep, data, eplen);
    ep[eplen] = '\0';
    if (tab && !(accept = strndup((const char *)tab + 1, linelen - eplen - 1))) goto end;
    if (len) memcpy(body, nl + 1, len);
    if (strcmp(ep, "@x-forwarded-for") == 0) {
        fuzz_forwarded(body, len);
        goto end;
    }
    if (strcmp(ep, "@max-memory") == 0) {
        fuzz_max_memory(body, len);
        goto end;
    }
    if (strcmp(ep, "@heights") == 0) {
        fuzz_heights(body, len);
        goto end;
    }
    if (strcmp(ep, "@jobrow") == 0) {
        fuzz_jobrow(body, len);
        goto end;
    }
    if (strcmp(ep, "@pgrow") == 0) {
        fuzz_pgrow(body, len);
        goto end;
    }
    known = ljgap__handler_has(ep);
    if (strncmp(ep, "text:", 5) == 0) {
        /* "text:NAME?a=1&b": split the query in place (ep is ours) */
        char *q = strchr(ep + 5, '?'), *save = NULL;
        text = calloc(1, sizeof *text);
        if (!text) goto end;
        if (q) *q++ = '\0';
        for (char *t = q ? strtok_r(q, "&", &save) : NULL; t && text->np < 64;
             t = strtok_r(NULL, "&", &save)) {
            char *eq = strchr(t, '=');
            text->p[text->np].name = t;
            text->p[text->np++].value = eq ? (*eq = '\0', eq + 1) : NULL;
        }
        for (size_t i = 0; i < len; i++) /* LF, and CR before anything but LF, end a line */
            text->lines +=
                body[i] == '\n' || (body[i] == '\r' && i + 1 < len && body[i + 1] != '\n');
        text->lines++;
        known = ljgap__handler_has_text(ep + 5);
        {
            ljgap__call call = {.accept = accept};
            ljgap__handle_text(ep + 5, text->p, text->np, body, len, &call, &r);
        }
    } else if (strcmp(ep, "simulations") == 0) {
        ljgap__sim_request *sr = ljgap__sim_request_parse(body, len, &r);
        known = 1;
        if (sr) ljgap__sim_request_run(sr, &sim_control, &r);
        ljgap__sim_request_free(sr);
        if (r.status == 200 && accept) sim_status(accept, &r);
    } else {
        ljgap__call call = {.accept = accept};
        ljgap__handle_call(ep, body, len, &call, &r);
    }
    if (!r.body || !r.content_type) {
        breach(ep, &r, "no body or no content type");
        goto end;
    }
    if (strlen(r.body) != r.len) breach(ep, &r, "len %zu != strlen(body)", r.len);
    if (r.status != 200 && r.status != 400 && r.status != 404 && r.status != 406 && r.status != 422)
        breach(ep, &r, "status outside 200, 400, 404, 406, 422");
    if ((r.status == 404) != !known) breach(ep, &r, "404 must mean exactly: unknown endpoint");
    if (r.status == 406 && !accept) breach(ep, &r, "406 without an Accept header");
    if (!utf8_ok(r.body, r.len)) breach(ep, &r, "not valid UTF-8");
    if (strncmp(r.content_type, "text/csv", 8) == 0) {
        check_csv(ep, &r);
        goto end;
    }
    doc = cJSON_ParseWithLengthOpts(r.body, r.len, &end, 0);
    if (!cJSON_IsObject(doc) || end != r.body + r.len) {
        breach(ep, &r, "the body is not one JSON object");
        goto end;
    }
    if (!all_finite(doc)) breach(ep, &r, "a number that is not finite");
    if (r.status == 200) {
        const cJSON *res = cJSON_GetObjectItemCaseSensitive(doc, "result"); /* job status */
        check_ok(ep, &r, res && !strcmp(ep, "simulations") ? res : doc);
    } else {
        /* pointers are checked against the request when it is JSON (422 answers) */
        if (r.status == 422 && !text) req = cJSON_ParseWithLength(body, len);
        check_problem(ep, &r, doc, req, r.status == 422 ? text : NULL);
    }
end:
    cJSON_Delete(doc);
    cJSON_Delete(req);
    free(text);
    ljgap__reply_free(&r);
    free(ep);
    free(body);
    free(accept);
    return 0;
}
