/* test_csv.c -- the CSV answers (server/api/csv.c) and content negotiation (server/api/accept.c).
 *
 * The CSV form must carry the JSON answer's numbers and nothing else: each answer is asked
 * for as JSON, then turned into CSV (ljgap__csv_reply, so the two share every byte of input),
 * and the CSV is parsed back line by line: every comment "# PATH [UNIT] = VALUE ± ERR" names a
 * JSON path whose value (and error: error.PATH, or si.error.REST for si.REST) it must equal,
 * every column a JSON array, and every number in the JSON must have been met (no field left
 * out, the SI errors included). Numbers are compared to within the last bit cJSON prints (it
 * writes 15 significant digits when they read back to within one part in 2^52). The handler's
 * own CSV path (Accept: text/csv) must give the same table as the conversion. Then the Accept
 * header: q-values, wildcards, ties, malformed ranges, 406 for what nothing satisfies, and the
 * simulation status answer.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "accept.h"
#include "csv.h"
#include "handler.h"

#include <cjson/cJSON.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PSD "{\"kind\":\"power\",\"D\":2.5,\"k1\":1,\"k2\":8,\"m0\":0.5}"
#define MAT "\"material\":{\"E_star\":1e9,\"dgamma\":0.05,\"epsilon\":3e-10}"

/* ---- a parsed CSV answer ---- */

typedef struct {
    char **lines; /* every line, without its newline */
    int n;
    int header; /* index of the header line */
} csv_doc;

static csv_doc csv_parse(const char *text)
{
    csv_doc d = {0};
    const char *p = text;
    d.header = -1;
    while (*p) {
        const char *e = strchr(p, '\n');
        assert_non_null(e); /* every line ends in a newline */
        d.lines = realloc(d.lines, (size_t)(d.n + 1) * sizeof *d.lines);
        assert_non_null(d.lines);
        d.lines[d.n] = strndup(p, (size_t)(e - p));
        if (d.header < 0 && d.lines[d.n][0] != '#') d.header = d.n;
        d.n++;
        p = e + 1;
    }
    assert_true(d.header > 0); /* comments first, then the header */
    return d;
}

static void csv_free(csv_doc *d)
{
    for (int i = 0; i < d->n; i++)
        free(d->lines[i]);
    free(d->lines);
}

/* Splits line at commas into at most max cells (modified in place); returns the count. */
static int cells(char *line, char **cell, int max)
{
    int n = 0;
    for (char *p = line;; p++) {
        if (n < max) cell[n] = p;
        n++;
        p = strchr(p, ',');
        if (!p) break;
        *p = '\0';
    }
    return n;
}

/* ---- JSON paths: a.b[2].c ---- */

static const cJSON *resolve(const cJSON *v, const char *path)
{
    char tok[64];
    while (v && *path) {
        size_t n;
        if (*path == '.') path++;
        if (*path == '[') {
            int i = atoi(path + 1);
            v = cJSON_IsArray(v) ? cJSON_GetArrayItem(v, i) : NULL;
            path = strchr(path, ']') + 1;
            continue;
        }
        n = strcspn(path, ".[");
        assert_true(n < sizeof tok);
        memcpy(tok, path, n);
        tok[n] = '\0';
        v = cJSON_GetObjectItemCaseSensitive(v, tok);
        path += n;
    }
    return v;
}

/* ---- what has been met ---- */

static const cJSON **seen;
static size_t n_seen, cap_seen;

static void mark(const cJSON *v)
{
    if (n_seen == cap_seen) {
        cap_seen = cap_seen ? 2 * cap_seen : 256;
        seen = realloc(seen, cap_seen * sizeof *seen);
        assert_non_null(seen);
    }
    seen[n_seen++] = v;
}

static int was_seen(const cJSON *v)
{
    for (size_t i = 0; i < n_seen; i++)
        if (seen[i] == v) return 1;
    return 0;
}

/* Every number, string and boolean below v was met. */
static void all_seen(const cJSON *v, const char *where)
{
    if (cJSON_IsArray(v) || cJSON_IsObject(v)) {
        for (const cJSON *c = v->child; c; c = c->next)
            all_seen(c, c->string ? c->string : where);
        return;
    }
    if (!cJSON_IsNull(v) && !was_seen(v)) fail_msg("the CSV leaves out a value of %s", where);
}

/* Does the text equal the JSON number (to the last bit cJSON prints), null, or boolean? */
static void same(const char *text, const cJSON *v, const char *what)
{
    char *end;
    double x;
    if (!v) fail_msg("%s: no such field in the JSON answer", what);
    mark(v);
    if (cJSON_IsNull(v)) {
        if (*text && strcmp(text, "inf") != 0 && strcmp(text, "null") != 0)
            fail_msg("%s: \"%s\" for null", what, text);
        return;
    }
    if (cJSON_IsBool(v)) {
        assert_string_equal(text, cJSON_IsTrue(v) ? "true" : "false");
        return;
    }
    if (cJSON_IsString(v)) {
        assert_string_equal(text, v->valuestring);
        return;
    }
    x = strtod(text, &end);
    if (*end || end == text) fail_msg("%s: \"%s\" is not a number", what, text);
    if (!(fabs(x - v->valuedouble) <= 2.3e-16 * fabs(v->valuedouble)))
        fail_msg("%s: CSV %.17g, JSON %.17g", what, x, v->valuedouble);
}

/* The error of the field at path: in the outermost "error" object that has it, as the CSV
 * writer looks (error.PATH, then A.error.REST for each prefix A of PATH: si.error.summary.g_eq_m
 * for si.summary.g_eq_m). */
static const cJSON *error_of(const cJSON *ans, const char *path)
{
    char p[240];
    for (size_t cut = 0; cut == 0 || path[cut]; cut++) {
        const cJSON *e;
        if (cut && path[cut] != '.') continue;
        snprintf(p, sizeof p, "%.*s%serror.%s", (int)cut, path, cut ? "." : "",
                 path + cut + (cut ? 1 : 0));
        if ((e = resolve(ans, p))) return e;
    }
    fail_msg("%s: no error for it in the JSON answer", path);
    return NULL;
}

/* Checks every comment line "# PATH [UNIT] = VALUE ± ERR" against the answer. */
static void check_comments(const csv_doc *d, const cJSON *ans)
{
    for (int i = 1; i < d->header; i++) {
        char path[200], *eq, *pm, *value;
        const char *line = d->lines[i];
        size_t n;
        assert_true(strncmp(line, "# ", 2) == 0);
        eq = strstr(line, " = ");
        assert_non_null(eq);
        n = strcspn(line + 2, " ");
        assert_true(n < sizeof path);
        memcpy(path, line + 2, n);
        path[n] = '\0';
        value = strdup(eq + 3);
        if ((pm = strstr(value, " ± "))) {
            *pm = '\0';
            same(pm + strlen(" ± "), error_of(ans, path), path);
        }
        same(value, resolve(ans, path), path);
        free(value);
    }
}

/* The CSV form of ans (a 200 answer of endpoint, given as JSON text). */
static char *to_csv(const char *endpoint, const char *json)
{
    ljgap__reply r = {200, strdup(json), strlen(json), "application/json", 0};
    char *s;
    assert_int_equal(ljgap__csv_reply(endpoint, &r), 0);
    assert_int_equal(r.status, 200);
    assert_string_equal(r.content_type, LJGAP_CT_CSV);
    assert_int_equal(r.len, strlen(r.body));
    s = r.body;
    return s;
}

/* The handler with an Accept header. */
static void handle_accept(const char *endpoint, const char *accept, const char *body, size_t len,
                          ljgap__reply *r)
{
    ljgap__call call = {.accept = accept};
    ljgap__handle_call(endpoint, body, len, &call, r);
}

/* Asks endpoint for request as JSON; returns the body (checked 200). */
static char *ask_json(const char *endpoint, const char *request)
{
    ljgap__reply r;
    ljgap__handle(endpoint, request, strlen(request), &r);
    if (r.status != 200) fail_msg("%s: %d %s", endpoint, r.status, r.body);
    return r.body;
}

/* The handler's own CSV path (Accept: text/csv) gives the same table as the conversion from
 * the JSON text; the numbers agree to within what cJSON's printing loses (the handler writes
 * its doubles exactly), the time in the comments may differ. */
static void check_handler_csv(const char *endpoint, const char *request, const char *csv)
{
    ljgap__reply r;
    csv_doc a, b;
    handle_accept(endpoint, "text/csv", request, strlen(request), &r);
    assert_int_equal(r.status, 200);
    assert_string_equal(r.content_type, LJGAP_CT_CSV);
    a = csv_parse(r.body);
    b = csv_parse(csv);
    assert_int_equal(a.n - a.header, b.n - b.header);
    for (int i = 0; i < a.n - a.header; i++) {
        char *ca[24], *cb[24];
        int n = cells(a.lines[a.header + i], ca, 24);
        assert_int_equal(cells(b.lines[b.header + i], cb, 24), n);
        for (int k = 0; k < n && k < 24; k++) {
            char *ea, *eb;
            double x = strtod(ca[k], &ea), y = strtod(cb[k], &eb);
            if (i == 0 || *ea || *eb || ea == ca[k])
                assert_string_equal(ca[k], cb[k]);
            else if (!(x == y || fabs(x - y) <= 2.3e-16 * fabs(y)))
                fail_msg("row %d column %d: %s against %s", i, k, ca[k], cb[k]);
        }
    }
    csv_free(&a);
    csv_free(&b);
    ljgap__reply_free(&r);
}

static void test_traction(void **state)
{
    const char *rq = "{\"psd\":" PSD ",\"g_ave\":{\"min\":1.5,\"max\":5,\"n\":7}," MAT "}";
    char *json = ask_json("traction", rq), *csv = to_csv("traction", json);
    cJSON *ans = cJSON_Parse(json);
    csv_doc d = csv_parse(csv);
    const cJSON *s0 = resolve(ans, "si.sigma0_Pa");
    char *c[8];
    (void)state;
    n_seen = 0;
    assert_string_equal(d.lines[d.header], "g_ave [eps],sigma [sigma0],sigma_err [sigma0],"
                                           "g_ave_m [m],sigma_Pa [Pa],sigma_Pa_err [Pa]");
    check_comments(&d, ans);
    assert_int_equal(d.n - d.header - 1, 7);
    for (int i = 0; i < 7; i++) {
        char p[64];
        assert_int_equal(cells(d.lines[d.header + 1 + i], c, 8), 6);
        snprintf(p, sizeof p, "g_ave[%d]", i);
        same(c[0], resolve(ans, p), p);
        snprintf(p, sizeof p, "sigma[%d]", i);
        same(c[1], resolve(ans, p), p);
        snprintf(p, sizeof p, "error.sigma[%d]", i);
        same(c[2], resolve(ans, p), p);
        snprintf(p, sizeof p, "si.g_ave_m[%d]", i);
        same(c[3], resolve(ans, p), p);
        snprintf(p, sizeof p, "si.sigma_Pa[%d]", i);
        same(c[4], resolve(ans, p), p);
        snprintf(p, sizeof p, "si.error.sigma_Pa[%d]", i);
        same(c[5], resolve(ans, p), p);
        /* and it is the error in σ0 times σ0 */
        assert_true(fabs(strtod(c[5], NULL) -
                         cJSON_GetArrayItem(resolve(ans, "error.sigma"), i)->valuedouble *
                             s0->valuedouble) <= 1e-15 * strtod(c[5], NULL));
    }
    all_seen(ans, "the answer");
    check_handler_csv("traction", rq, csv);
    csv_free(&d);
    cJSON_Delete(ans);
    free(json);
    free(csv);
}

static void test_pdf(void **state)
{
    const char *rq = "{\"psd\":{\"kind\":\"power\",\"D\":2.5,\"k1\":1,\"m0\":0.5},"
                     "\"g_ave\":0.98,\"k2\":[2,null],"
                     "\"grid\":{\"min\":0.6,\"max\":1.6,\"n\":11}," MAT "}";
    char *json = ask_json("pdf", rq), *csv = to_csv("pdf", json);
    cJSON *ans = cJSON_Parse(json);
    csv_doc d = csv_parse(csv);
    int rows = 0;
    (void)state;
    n_seen = 0;
    assert_string_equal(d.lines[d.header],
                        "pdf,k2 [1/chi],g [eps],phi [1/eps],g_m [m],phi_per_m [1/m]");
    check_comments(&d, ans);
    for (int i = d.header + 1; i < d.n; i++, rows++) {
        char *c[8], p[64];
        int k, at;
        assert_int_equal(cells(d.lines[i], c, 8), 6);
        k = atoi(c[0]);
        at = rows - 11 * k; /* 11 points per PDF, in order */
        assert_true(k >= 0 && k < 2 && at >= 0 && at < 11);
        snprintf(p, sizeof p, "pdfs[%d].k2", k);
        same(c[1], resolve(ans, p), p);
        if (k == 1) assert_string_equal(c[1], "inf"); /* null: k2 = infinity */
        snprintf(p, sizeof p, "pdfs[%d].g[%d]", k, at);
        same(c[2], resolve(ans, p), p);
        snprintf(p, sizeof p, "pdfs[%d].phi[%d]", k, at);
        same(c[3], resolve(ans, p), p);
        snprintf(p, sizeof p, "si.pdfs[%d].g_m[%d]", k, at);
        same(c[4], resolve(ans, p), p);
        snprintf(p, sizeof p, "si.pdfs[%d].phi_per_m[%d]", k, at);
        same(c[5], resolve(ans, p), p);
    }
    assert_int_equal(rows, 22);
    all_seen(ans, "the answer");
    check_handler_csv("pdf", rq, csv);
    csv_free(&d);
    cJSON_Delete(ans);
    free(json);
    free(csv);
}

static void test_sweep(void **state)
{
    const char *rq = "{\"psd\":{\"kind\":\"power\",\"D\":2.5,\"k1\":1,\"m0\":0.5},"
                     "\"vary\":\"m0\",\"values\":[0.1,1]," MAT "}";
    static const char *const names[] = {"g_eq", "sigma_max", "g_at_max", "dgamma_eff"};
    char *json = ask_json("sweep", rq), *csv = to_csv("sweep", json);
    cJSON *ans = cJSON_Parse(json);
    csv_doc d = csv_parse(csv);
    (void)state;
    n_seen = 0;
    assert_string_equal(
        d.lines[d.header],
        "values [eps^2],g_eq [eps],g_eq_err [eps],sigma_max [sigma0],sigma_max_err [sigma0],"
        "g_at_max [eps],g_at_max_err [eps],dgamma_eff [dgamma],dgamma_eff_err [dgamma],"
        "m0 [eps^2],k0 [1/chi],g_eq_m [m],g_eq_m_err [m],sigma_max_Pa [Pa],"
        "sigma_max_Pa_err [Pa],g_at_max_m [m],g_at_max_m_err [m],dgamma_eff_J_m2 [J/m^2],"
        "dgamma_eff_J_m2_err [J/m^2],m0_m2 [m^2]");
    check_comments(&d, ans);
    assert_int_equal(d.n - d.header - 1, 2);
    for (int i = 0; i < 2; i++) {
        char *c[24], p[64];
        assert_int_equal(cells(d.lines[d.header + 1 + i], c, 24), 20);
        snprintf(p, sizeof p, "values[%d]", i);
        same(c[0], resolve(ans, p), p);
        for (int f = 0; f < 4; f++) {
            snprintf(p, sizeof p, "results[%d].%s", i, names[f]);
            same(c[1 + 2 * f], resolve(ans, p), p);
            snprintf(p, sizeof p, "results[%d].error.%s", i, names[f]);
            same(c[2 + 2 * f], resolve(ans, p), p);
        }
        snprintf(p, sizeof p, "results[%d].m0", i);
        same(c[9], resolve(ans, p), p);
        snprintf(p, sizeof p, "results[%d].k0", i);
        same(c[10], resolve(ans, p), p);
        for (int f = 0; f < 4; f++) {
            static const char *const si[] = {"g_eq_m", "sigma_max_Pa", "g_at_max_m",
                                             "dgamma_eff_J_m2"};
            snprintf(p, sizeof p, "si.results[%d].%s", i, si[f]);
            same(c[11 + 2 * f], resolve(ans, p), p);
            snprintf(p, sizeof p, "si.results[%d].error.%s", i, si[f]);
            same(c[12 + 2 * f], resolve(ans, p), p);
        }
        snprintf(p, sizeof p, "si.results[%d].m0_m2", i);
        same(c[19], resolve(ans, p), p);
    }
    all_seen(ans, "the answer");
    check_handler_csv("sweep", rq, csv);
    csv_free(&d);
    cJSON_Delete(ans);
    free(json);
    free(csv);
}

/* A value without a finite answer (null in results and si.results) is a row of empty cells but
 * for its value (and k0); the SI columns and their errors come from si.results[i]. */
static void test_sweep_failed_value(void **state)
{
    const char *json = "{\"vary\":\"D\",\"values\":[2.5,2.9],\"results\":[{\"g_eq\":2.6,"
                       "\"sigma_max\":0.1,\"g_at_max\":3,\"dgamma_eff\":0.2,\"m0\":0.5,\"k0\":0.47,"
                       "\"error\":{\"g_eq\":1e-7,\"sigma_max\":1e-7,\"g_at_max\":1e-7,"
                       "\"dgamma_eff\":1e-7}},{\"g_eq\":null,\"sigma_max\":null,\"g_at_max\":null,"
                       "\"dgamma_eff\":null,\"m0\":null,\"k0\":0.47,\"error\":{\"g_eq\":null,"
                       "\"sigma_max\":null,\"g_at_max\":null,\"dgamma_eff\":null}}],"
                       "\"si\":{\"chi_m\":3e-10,\"sigma0_Pa\":1e8,\"E_star_Pa\":1e9,\"results\":["
                       "{\"g_eq_m\":7e-10,\"sigma_max_Pa\":1e7,\"g_at_max_m\":9e-10,"
                       "\"dgamma_eff_J_m2\":0.01,\"m0_m2\":4.5e-20,\"error\":{\"g_eq_m\":3e-17,"
                       "\"sigma_max_Pa\":10,\"g_at_max_m\":3e-17,\"dgamma_eff_J_m2\":5e-9}},null]},"
                       "\"meta\":{\"method\":\"pde\",\"warnings\":[\"values[1]: no answer\"]}}";
    char *csv = to_csv("sweep", json);
    csv_doc d = csv_parse(csv);
    (void)state;
    assert_string_equal(d.lines[d.n - 2], "2.5,2.6,1e-07,0.1,1e-07,3,1e-07,0.2,1e-07,0.5,0.47,"
                                          "7e-10,3e-17,10000000,10,9e-10,3e-17,0.01,5e-09,4.5e-20");
    assert_string_equal(d.lines[d.n - 1], "2.9,,,,,,,,,,0.47,,,,,,,,,");
    assert_string_equal(d.lines[d.header - 1], "# meta.warnings[0] = values[1]: no answer");
    csv_free(&d);
    free(csv);
}

static void test_simulation(void **state)
{
    const char *rq = "{\"psd\":{\"kind\":\"power\",\"D\":2.2,\"k1\":1,\"k2\":4,\"m0\":0.05},"
                     "\"n\":16,\"realizations\":2,\"g_ave\":[2,3]}";
    ljgap__reply r;
    ljgap__sim_request *sr = ljgap__sim_request_parse(rq, strlen(rq), &r);
    cJSON *ans;
    char *csv;
    csv_doc d;
    (void)state;
    assert_non_null(sr);
    ljgap__sim_request_run(sr, NULL, &r);
    ljgap__sim_request_free(sr);
    assert_int_equal(r.status, 200);
    ans = cJSON_Parse(r.body);
    csv = to_csv("simulations", r.body);
    ljgap__reply_free(&r);
    d = csv_parse(csv);
    n_seen = 0;
    assert_string_equal(d.lines[d.header], "g_ave [eps],sigma [sigma0],sigma_err [sigma0],"
                                           "sigma_std [sigma0],sigma_out [sigma0],"
                                           "residual [sigma0],jump");
    check_comments(&d, ans);
    for (int i = 0; i < 2; i++) {
        static const char *const col[] = {"g_ave",     "sigma",    "error.sigma", "sigma_std",
                                          "sigma_out", "residual", "jump"};
        char *c[8], p[64];
        assert_int_equal(cells(d.lines[d.header + 1 + i], c, 8), 7);
        for (int k = 0; k < 7; k++) {
            snprintf(p, sizeof p, "%s[%d]", col[k], i);
            same(c[k], resolve(ans, p), p);
        }
    }
    all_seen(ans, "the answer");
    csv_free(&d);
    cJSON_Delete(ans);
    free(csv);
}

/* ---- Accept ---- */

static void test_accept_pick(void **state)
{
    static const char *const two[] = {"application/json", "text/csv"};
    static const struct {
        const char *accept;
        int want;
    } cases[] = {
        {NULL, 0},
        {"", 0},
        {"  ", 0},
        {"*/*", 0},
        {"application/json", 0},
        {"text/csv", 1},
        {"TEXT/CSV", 1},
        {"text/*", 1},
        {"text/csv, application/json", 1}, /* tie: the client's order */
        {"application/json, text/csv", 0},
        {"text/csv;q=0.5, application/json", 0},
        {"text/csv;q=0.9, application/json;q=0.8", 1},
        {"text/csv; charset=utf-8; q=1.0", 1},
        {"text/csv;q=\"x\", application/json;q=0.6", 0}, /* q is never quoted: skipped */
        {"text/csv;x=\"a,b;q=0\";q=0.7, application/json;q=0.6", 1}, /* quoted , and ; */
        {"*/*;q=0.1, text/csv", 1},
        {"text/csv;q=0, */*", 0}, /* the exact range refuses csv, the wildcard takes json */
        {"text/csv;q=0", -1},     /* refuses the one asked for, allows nothing else */
        {"application/*;q=0, text/*", 1},
        {"image/png", -1},
        {"json", -1},           /* not a media range */
        {"text/csv;q=1.5", -1}, /* malformed q: the range is skipped */
        {"text/csv;q=0.1234", -1},
        {"text/csv;q=", -1},
        {"*/csv", -1}, /* not a media range */
        {",, ,text/csv,,", 1},
        {"text/html, application/xhtml+xml, application/xml;q=0.9, */*;q=0.8", 0}, /* browsers */
        {"text/csv ; q=0.3 , application/json ; q=0.2", 1},
        {"text/csv;header=present", 1},
        {"text/csv;q=0.001", 1},
        {"text/csv;q=0.000", -1},
        {"text/plain, text/csv;q=0.2", 1},
    };
    (void)state;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        int got = ljgap__accept_pick(cases[i].accept, two, 2);
        if (got != cases[i].want)
            fail_msg("Accept \"%s\": %d, want %d", cases[i].accept ? cases[i].accept : "(null)",
                     got, cases[i].want);
    }
    assert_int_equal(ljgap__accept_pick("text/csv", two, 1), -1); /* JSON only on offer */
    assert_int_equal(ljgap__accept_pick("*/*", two, 1), 0);
}

static const char *type_of(const ljgap__reply *r)
{
    static char t[80];
    cJSON *doc = cJSON_Parse(r->body);
    snprintf(t, sizeof t, "%s",
             cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(doc, "type")) ?: "");
    cJSON_Delete(doc);
    return t;
}

static void test_handler_negotiates(void **state)
{
    const char *rq = "{\"psd\":" PSD "}";
    const char *bad = "{\"psd\":{\"kind\":\"power\",\"D\":2.5,\"k1\":0.3,\"m0\":0.5}}";
    const char *tr = "{\"psd\":" PSD ",\"g_ave\":[2,3]}";
    ljgap__reply r;
    (void)state;
    /* adhesion has no CSV form: text/csv alone is 406, before the body is looked at */
    handle_accept("adhesion", "text/csv", "{", 1, &r);
    assert_int_equal(r.status, 406);
    assert_string_equal(r.content_type, "application/problem+json");
    assert_string_equal(type_of(&r), "/problems/not-acceptable");
    ljgap__reply_free(&r);
    handle_accept("adhesion", "text/csv, */*;q=0.1", rq, strlen(rq), &r);
    assert_int_equal(r.status, 200);
    assert_string_equal(r.content_type, "application/json");
    ljgap__reply_free(&r);
    /* problems stay JSON whatever Accept says */
    handle_accept("traction", "text/csv", bad, strlen(bad), &r);
    assert_int_equal(r.status, 422);
    assert_string_equal(r.content_type, "application/problem+json");
    ljgap__reply_free(&r);
    handle_accept("traction", "image/png", tr, strlen(tr), &r);
    assert_int_equal(r.status, 406);
    ljgap__reply_free(&r);
    handle_accept("traction", "*/*", tr, strlen(tr), &r);
    assert_string_equal(r.content_type, "application/json");
    ljgap__reply_free(&r);
    handle_accept("traction", "application/json;q=0.5, text/*", tr, strlen(tr), &r);
    assert_int_equal(r.status, 200);
    assert_string_equal(r.content_type, LJGAP_CT_CSV);
    ljgap__reply_free(&r);
    /* an unknown endpoint is 404 whatever Accept says */
    handle_accept("nope", "image/png", tr, strlen(tr), &r);
    assert_int_equal(r.status, 404);
    ljgap__reply_free(&r);
}

static void test_sim_status(void **state)
{
    const char *running = "{\"id\":\"ab\",\"status\":\"running\",\"progress\":0.5,"
                          "\"elapsed_ms\":10}";
    const char *done = "{\"id\":\"ab\",\"status\":\"done\",\"progress\":1,\"elapsed_ms\":10,"
                       "\"result\":{\"g_ave\":[2],\"sigma\":[0.1],\"sigma_std\":[0.01],"
                       "\"sigma_out\":[0.1],\"residual\":[1e-9],\"jump\":[false],"
                       "\"m0_realized\":[0.05],\"m0\":0.05,\"error\":{\"sigma\":[0.002]},"
                       "\"meta\":{\"method\":\"numerical\",\"warnings\":[]}}}";
    ljgap__reply r;
    (void)state;
    ljgap__sim_status_answer(running, 200, NULL, &r);
    assert_int_equal(r.status, 200);
    assert_string_equal(r.body, running);
    assert_string_equal(r.content_type, "application/json");
    ljgap__reply_free(&r);
    ljgap__sim_status_answer(running, 202, "text/csv, application/json;q=0.5", &r);
    assert_int_equal(r.status, 202);
    assert_string_equal(r.body, running);
    ljgap__reply_free(&r);
    ljgap__sim_status_answer(running, 200, "text/csv", &r);
    assert_int_equal(r.status, 406);
    assert_non_null(strstr(r.body, "the job is running"));
    ljgap__reply_free(&r);
    ljgap__sim_status_answer(done, 200, "text/csv", &r);
    assert_int_equal(r.status, 200);
    assert_string_equal(r.content_type, LJGAP_CT_CSV);
    assert_non_null(strstr(r.body, "\ng_ave [eps],sigma [sigma0],sigma_err [sigma0],"));
    assert_non_null(strstr(r.body, "\n2,0.1,0.002,0.01,0.1,1e-09,false\n"));
    ljgap__reply_free(&r);
    ljgap__sim_status_answer(done, 200, "application/xml", &r);
    assert_int_equal(r.status, 406);
    ljgap__reply_free(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_traction),
        cmocka_unit_test(test_pdf),
        cmocka_unit_test(test_sweep),
        cmocka_unit_test(test_sweep_failed_value),
        cmocka_unit_test(test_simulation),
        cmocka_unit_test(test_accept_pick),
        cmocka_unit_test(test_handler_negotiates),
        cmocka_unit_test(test_sim_status),
    };
    gsl_set_error_handler_off();
    return cmocka_run_group_tests(tests, NULL, NULL);
}
