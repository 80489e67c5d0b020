/* test_psd.c -- POST /v1/psd through the handler: the JSON topography and the text upload.
 *
 *   - a synthetic periodic map (tests/lib/synth.h) as JSON: the answer's shape, h_rms exact,
 *     D, errors everywhere, a psd object ready for adhesion;
 *   - the same map as text (spaces, commas, CR LF, comments, a byte-order mark): the same answer;
 *   - a profile; the psd object round-trips into adhesion with "units":"SI" (and with a
 *     material it starts inside the theory's domain, which the whole band does not);
 *   - every bad input, JSON and text, is 422 with one error at its pointer (text: line and
 *     column in the detail); text to another endpoint is 404; out of memory is 500;
 *   - psd answers computed on several threads while a simulation plans its FFTs agree.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "handler.h"
#include "ljgap.h"
#include "ljgap_sim.h"

#include "../lib/realsurf.h"
#include "../lib/synth.h"

#include <cjson/cJSON.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../lib/oom.h"

#define MAT "{\"E_star\":1e11,\"dgamma\":0.05,\"epsilon\":3e-10}" /* χ = 3.375e-8 m */

/* ---- a growing string ---- */

typedef struct {
    char *s;
    size_t n, cap;
} buf;

static void add(buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void add(buf *b, const char *fmt, ...)
{
    va_list ap;
    for (;;) {
        va_start(ap, fmt);
        int k = vsnprintf(b->s ? b->s + b->n : NULL, b->s ? b->cap - b->n : 0, fmt, ap);
        va_end(ap);
        assert_true(k >= 0);
        if (b->s && b->n + (size_t)k < b->cap) {
            b->n += (size_t)k;
            return;
        }
        b->cap = 2 * (b->cap + (size_t)k + 64);
        b->s = realloc(b->s, b->cap);
        assert_non_null(b->s);
    }
}

/* ---- maps ---- */

typedef struct {
    size_t nx, ny;
    double dx;
    double *h;
    double rms; /* of the map minus its mean */
} map;

/* A periodic synthetic map: P = C k^(2D-8) over the whole grid, h_rms about hrms. */
static map make_map(size_t nx, size_t ny, double dx, double D, double hrms, unsigned long seed)
{
    map m = {nx, ny, dx, malloc(nx * ny * sizeof(double)), 0};
    double L = (double)(nx > ny ? nx : ny) * dx;
    synth_law l = {1, D, 2 * M_PI / L, M_PI / dx};
    synth_moments mom;
    assert_non_null(m.h);
    l.C = hrms * hrms / (2 * M_PI * (pow(l.k2, 2 * D - 6) - pow(l.k1, 2 * D - 6)) / (2 * D - 6));
    assert_int_equal(synth_surface(m.h, nx, ny, dx, dx, &l, seed, 0, &mom), 0);
    double mu = 0, ss = 0;
    for (size_t i = 0; i < nx * ny; i++)
        mu += m.h[i] / (double)(nx * ny);
    for (size_t i = 0; i < nx * ny; i++)
        ss += (m.h[i] - mu) * (m.h[i] - mu);
    m.rms = sqrt(ss / (double)(nx * ny));
    return m;
}

/* {"topography":{"heights":[...],"dx":..,"periodic":..}EXTRA} */
static char *map_json(const map *m, int periodic, const char *extra)
{
    buf b = {0};
    add(&b, "{\"topography\":{\"heights\":[");
    for (size_t j = 0; j < m->ny; j++) {
        add(&b, "%s[", j ? "," : "");
        for (size_t i = 0; i < m->nx; i++)
            add(&b, "%s%.17g", i ? "," : "", m->h[j * m->nx + i]);
        add(&b, "]");
    }
    add(&b, "],\"dx\":%.17g,\"periodic\":%s}%s}", m->dx, periodic ? "true" : "false",
        extra ? extra : "");
    return b.s;
}

/* The matrix as text: style 0 spaces and LF, 1 commas with CR LF, comments, blank lines and a
 * byte-order mark, 2 commas with CR alone (classic Mac OS line ends, as spreadsheets' "CSV
 * (Macintosh)" writes them), a comment and a blank line. */
static char *map_text(const map *m, int style)
{
    static const char *const eol[] = {"\n", "\r\n", "\r"};
    buf b = {0};
    if (style == 1) add(&b, "\xEF\xBB\xBF# a header comment\r\n\r\n");
    if (style == 2) add(&b, "# a header comment\r\r");
    for (size_t j = 0; j < m->ny; j++) {
        for (size_t i = 0; i < m->nx; i++)
            add(&b, "%s%.17g", i ? (style ? " , " : " ") : (style ? "  " : ""),
                m->h[j * m->nx + i]);
        add(&b, "%s%s", style && j % 3 == 0 ? "  # row comment" : "", eol[style]);
    }
    return b.s;
}

/* ---- answers ---- */

typedef struct {
    int status;
    cJSON *body;
} answer;

static answer parse_reply(ljgap__reply *r)
{
    answer a = {r->status, cJSON_Parse(r->body)};
    if (!a.body) fail_msg("not JSON: %.300s", r->body);
    ljgap__reply_free(r);
    return a;
}

static answer ask(const char *endpoint, const char *body)
{
    ljgap__reply r;
    ljgap__handle(endpoint, body, strlen(body), &r);
    return parse_reply(&r);
}

/* A text upload; query is "name=value&..." (no decoding needed here). */
static answer ask_text(const char *endpoint, const char *query, const char *body, size_t len)
{
    ljgap__param p[16];
    char *q = strdup(query), *save = NULL;
    size_t n = 0;
    ljgap__reply r;
    assert_non_null(q);
    for (char *t = strtok_r(q, "&", &save); t && n < 16; t = strtok_r(NULL, "&", &save)) {
        char *eq = strchr(t, '=');
        p[n].name = t;
        p[n].value = eq ? (*eq = '\0', eq + 1) : NULL;
        n++;
    }
    ljgap__handle_text(endpoint, p, n, body, len, NULL, &r);
    free(q);
    return parse_reply(&r);
}

static const cJSON *get(const cJSON *o, const char *name)
{
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(o, name);
    if (!it) fail_msg("field %s is missing", name);
    return it;
}

static double num(const cJSON *o, const char *name)
{
    const cJSON *it = get(o, name);
    if (!cJSON_IsNumber(it)) fail_msg("field %s is not a number", name);
    return it->valuedouble;
}

static void near(double got, double want, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol))
        fail_msg("%s: got %.17g, want %.17g (tolerance %.3g)", what, got, want, tol);
}

static void all_finite(const cJSON *v)
{
    const cJSON *c;
    if (cJSON_IsNumber(v)) assert_true(isfinite(v->valuedouble));
    cJSON_ArrayForEach(c, v) all_finite(c);
}

/* The answer without meta, printed: what text and JSON must share. */
static char *without_meta(const cJSON *body)
{
    cJSON *c = cJSON_Duplicate(body, 1);
    assert_non_null(c);
    cJSON_DeleteItemFromObjectCaseSensitive(c, "meta");
    char *s = cJSON_PrintUnformatted(c);
    cJSON_Delete(c);
    return s;
}

/* A 422 validation problem with one error at pointer (and, when not NULL, a detail starting
 * with detail_start). */
static void expect_one(answer a, const char *pointer, const char *detail_start, const char *what)
{
    const cJSON *errs, *e;
    if (a.status != 422) fail_msg("%s: status %d, want 422", what, a.status);
    errs = get(a.body, "errors");
    e = cJSON_GetArrayItem(errs, 0);
    if (cJSON_GetArraySize(errs) != 1 || strcmp(get(e, "pointer")->valuestring, pointer) != 0) {
        char *s = cJSON_PrintUnformatted(errs);
        fail_msg("%s: expected one error at \"%s\", got %s", what, pointer, s);
    }
    if (detail_start &&
        strncmp(get(e, "detail")->valuestring, detail_start, strlen(detail_start)) != 0)
        fail_msg("%s: detail \"%s\" does not start with \"%s\"", what,
                 get(e, "detail")->valuestring, detail_start);
    cJSON_Delete(a.body);
}

/* ---- the answer ---- */

static void json_periodic_map(void **state)
{
    map m = make_map(64, 64, 2e-8, 2.4, 1e-9, 3);
    char *req = map_json(&m, 1, NULL);
    answer a = ask("psd", req);
    const cJSON *k, *P, *err, *fit, *psd, *grid, *meta;
    size_t n;
    assert_int_equal(a.status, 200);
    all_finite(a.body);
    meta = get(a.body, "meta");
    assert_string_equal(get(meta, "method")->valuestring, "periodogram");
    k = get(a.body, "k");
    P = get(a.body, "P");
    n = (size_t)cJSON_GetArraySize(k);
    assert_true(n >= 10);
    assert_int_equal(cJSON_GetArraySize(P), n);
    assert_int_equal(cJSON_GetArraySize(get(a.body, "modes")), n);
    err = get(a.body, "error");
    assert_int_equal(cJSON_GetArraySize(get(err, "P")), n);
    for (size_t i = 0; i < n; i++) {
        assert_true(cJSON_GetArrayItem(get(err, "P"), (int)i)->valuedouble > 0);
        if (i)
            assert_true(cJSON_GetArrayItem(k, (int)i)->valuedouble >
                        cJSON_GetArrayItem(k, (int)i - 1)->valuedouble);
    }
    near(num(a.body, "h_rms"), m.rms, 1e-12 * m.rms, "h_rms is the map's rms");
    assert_true(num(err, "h_rms") > 0 && num(err, "rms_slope") > 0);
    fit = get(a.body, "fit");
    near(num(fit, "D"), 2.4, 0.02, "D");
    near(num(fit, "H"), 3 - num(fit, "D"), 1e-12, "H = 3 - D");
    assert_true(num(get(err, "fit"), "D") > 0 && num(get(err, "fit"), "C") > 0);
    grid = get(a.body, "grid");
    assert_true(cJSON_IsTrue(get(grid, "periodic")) && cJSON_IsFalse(get(grid, "profile")));
    assert_string_equal(get(grid, "window")->valuestring, "none");
    near(num(grid, "k_min"), 2 * M_PI / (64 * 2e-8), 1, "k_min");
    near(num(grid, "k_max"), M_PI / 2e-8, 1, "k_max");
    /* the psd object: the band's lower edge, the bins, the band's upper edge (issue 25), with
     * P_err and the fitted tail with its error, nothing about the theory's domain */
    psd = get(a.body, "psd");
    assert_string_equal(get(psd, "kind")->valuestring, "table");
    const cJSON *pk = get(psd, "k"), *rel = get(a.body, "reliable");
    assert_int_equal(cJSON_GetArraySize(pk), n + 2);
    assert_int_equal(cJSON_GetArraySize(get(psd, "P_err")), n + 2);
    near(cJSON_GetArrayItem(pk, 0)->valuedouble, num(rel, "k_min"), 0, "starts at the band");
    assert_true(cJSON_GetArrayItem(pk, 0)->valuedouble < cJSON_GetArrayItem(k, 0)->valuedouble);
    for (size_t i = 0; i < n; i++)
        near(cJSON_GetArrayItem(pk, (int)i + 1)->valuedouble,
             cJSON_GetArrayItem(k, (int)i)->valuedouble, 0, "the bins' k");
    assert_true(cJSON_GetArrayItem(pk, (int)n + 1)->valuedouble <= num(rel, "k_max"));
    assert_string_equal(get(rel, "by")->valuestring, "nyquist");
    near(num(get(psd, "tail"), "exponent"), 2 * num(fit, "D") - 8, 1e-12, "tail exponent");
    near(num(get(psd, "tail"), "exponent_err"), 2 * num(get(err, "fit"), "D"), 1e-12,
         "tail exponent's error");
    assert_string_equal(get(grid, "detrend")->valuestring, "mean");
    assert_null(cJSON_GetObjectItemCaseSensitive(a.body, "domain"));
    assert_null(cJSON_GetObjectItemCaseSensitive(a.body, "si"));
    cJSON_Delete(a.body);
    free(req);
    free(m.h);
}

static void text_equals_json(void **state)
{
    map m = make_map(48, 40, 1e-8, 2.6, 2e-9, 5);
    char *req = map_json(&m, 0, NULL), *t0 = map_text(&m, 0), *t1 = map_text(&m, 1);
    char *t2 = map_text(&m, 2);
    answer a = ask("psd", req), b = ask_text("psd", "dx=1e-08", t0, strlen(t0));
    answer c = ask_text("psd", "periodic=false&dx=1.0e-8&dy=1e-8", t1, strlen(t1));
    answer d = ask_text("psd", "dx=1e-8", t2, strlen(t2));
    assert_int_equal(a.status, 200);
    assert_int_equal(b.status, 200);
    assert_int_equal(c.status, 200);
    assert_int_equal(d.status, 200);
    char *sa = without_meta(a.body), *sb = without_meta(b.body), *sc = without_meta(c.body);
    char *sd = without_meta(d.body);
    assert_string_equal(sa, sb);
    assert_string_equal(sa, sc);
    assert_string_equal(sa, sd); /* CR alone ends a line: not one long profile */
    near(num(get(a.body, "grid"), "nx"), 48, 0, "nx: a row is a line");
    near(num(get(a.body, "grid"), "ny"), 40, 0, "ny");
    free(sa), free(sb), free(sc), free(sd);
    cJSON_Delete(a.body), cJSON_Delete(b.body), cJSON_Delete(c.body), cJSON_Delete(d.body);
    /* with a material, the same again */
    free(req);
    req = map_json(&m, 0, ",\"material\":" MAT);
    a = ask("psd", req);
    b = ask_text("psd", "dx=1e-8&E_star=1e11&dgamma=0.05&epsilon=3e-10", t0, strlen(t0));
    assert_int_equal(a.status, 200);
    sa = without_meta(a.body), sb = without_meta(b.body);
    assert_string_equal(sa, sb);
    free(sa), free(sb);
    cJSON_Delete(a.body), cJSON_Delete(b.body);
    free(req), free(t0), free(t1), free(t2), free(m.h);
}

/* The text parser's numbers are strtod's (cJSON's) to the bit, in every notation: each map
 * written in one notation as text and as JSON gives the same answer. */
static void text_numbers_are_strtods(void **state)
{
    static const char *const fmts[] = {"%.3e", "%.9f", "%g", "%.16e", "%+.5E", "%.0f"};
    map m = make_map(16, 16, 1e-8, 2.5, 1e-9, 21);
    for (size_t f = 0; f < sizeof fmts / sizeof *fmts; f++) {
        buf t = {0}, j = {0};
        /* %.0f: integers (heights scaled up, still under 1 km) */
        double scale = f == 5 ? 1e11 : 1;
        add(&j, "{\"topography\":{\"dx\":1e-8,\"heights\":[");
        for (size_t r = 0; r < 16; r++) {
            add(&j, "%s[", r ? "," : "");
            for (size_t i = 0; i < 16; i++) {
                char v[64];
                snprintf(v, sizeof v, fmts[f], m.h[r * 16 + i] * scale);
                add(&t, "%s%s", i ? " " : "", v);
                add(&j, "%s%s", i ? "," : "", v[0] == '+' ? v + 1 : v); /* JSON has no '+' */
            }
            add(&t, "\n");
            add(&j, "]");
        }
        add(&j, "]}}");
        answer a = ask("psd", j.s), b = ask_text("psd", "dx=1e-8", t.s, t.n);
        if (a.status != 200 || b.status != 200) fail_msg("%s: %d, %d", fmts[f], a.status, b.status);
        char *sa = without_meta(a.body), *sb = without_meta(b.body);
        if (strcmp(sa, sb) != 0) fail_msg("notation %s: text and JSON differ", fmts[f]);
        free(sa), free(sb);
        cJSON_Delete(a.body), cJSON_Delete(b.body);
        free(t.s), free(j.s);
    }
    free(m.h);
}

static void profile(void **state)
{
    map m = make_map(256, 256, 1e-8, 2.3, 1e-9, 9);
    map row = {256, 1, 1e-8, m.h, 0};
    char *req = map_json(&row, 1, NULL);
    answer a = ask("psd", req);
    const cJSON *pr, *w;
    int warned = 0;
    assert_int_equal(a.status, 200);
    all_finite(a.body);
    assert_true(cJSON_IsTrue(get(get(a.body, "grid"), "profile")));
    pr = get(a.body, "profile");
    assert_int_equal(cJSON_GetArraySize(get(pr, "PP")), cJSON_GetArraySize(get(a.body, "P")));
    near(num(pr, "alpha"), 7 - 2 * num(get(a.body, "fit"), "D"), 0.1, "alpha = 7 - 2D");
    assert_true(num(get(get(a.body, "error"), "profile"), "alpha") > 0);
    cJSON_ArrayForEach(w, get(get(a.body, "meta"), "warnings")) warned |=
        strstr(w->valuestring, "isotropic") != NULL;
    assert_true(warned);
    cJSON_Delete(a.body);
    free(req), free(m.h);
}

/* The psd object goes into adhesion as it is. With the material, it starts at the proposed
 * k1 above k0/χ and the adhesion's m0 is the domain's; the whole band, below k0/χ at its start,
 * is refused by adhesion at /psd/k/0: the reason for the domain. */
static void psd_roundtrip_into_adhesion(void **state)
{
    map m = make_map(128, 128, 2e-8, 2.3, 1e-9, 13);
    char *req = map_json(&m, 1, ",\"material\":" MAT), *req2 = map_json(&m, 1, NULL);
    answer a = ask("psd", req), b = ask("psd", req2);
    const cJSON *dom, *psd;
    buf ad = {0};
    double chi = 3 * 9e-20 * 1e11 / (16 * 0.05);
    assert_int_equal(a.status, 200);
    dom = get(a.body, "domain");
    near(num(dom, "k0"), 0.46978 / chi, 1e-4 / chi, "k0/χ");
    assert_string_equal(get(dom, "inside")->valuestring, "part");
    assert_true(num(dom, "fraction") > 0 && num(dom, "fraction") < 1);
    assert_true(num(dom, "k1") >= 1.1 * num(dom, "k0") * (1 - 1e-12));
    near(num(dom, "k1_dimensionless"), num(dom, "k1") * chi, 1e-9, "k1 χ");
    assert_true(cJSON_IsObject(get(a.body, "si")));
    psd = get(a.body, "psd");
    near(cJSON_GetArrayItem(get(psd, "k"), 0)->valuedouble, num(dom, "k1"), 0, "psd from k1");
    char *ps = cJSON_PrintUnformatted(psd);
    add(&ad, "{\"psd\":%s,\"material\":" MAT ",\"units\":\"SI\",\"tol\":1e-4}", ps);
    answer c = ask("adhesion", ad.s);
    if (c.status != 200) fail_msg("adhesion refused the psd object: %s", cJSON_Print(c.body));
    near(num(c.body, "m0"), num(dom, "m0_dimensionless"), 1e-9 * num(c.body, "m0"), "m0");
    near(sqrt(num(get(c.body, "si"), "m0_m2")), num(dom, "h_rms"), 1e-9 * num(dom, "h_rms"),
         "h_rms above k1");
    cJSON_Delete(c.body);
    free(ps), free(ad.s);
    /* the whole band: refused at its first point */
    ps = cJSON_PrintUnformatted(get(b.body, "psd"));
    ad = (buf){0};
    add(&ad, "{\"psd\":%s,\"material\":" MAT ",\"units\":\"SI\"}", ps);
    expect_one(ask("adhesion", ad.s), "/psd/k/0", NULL, "the whole band below k0/χ");
    free(ps), free(ad.s);
    cJSON_Delete(a.body), cJSON_Delete(b.body);
    free(req), free(req2), free(m.h);
}

/* ---- bad input ---- */

/* A 16 × 16 request with one change: the heights text with cell (r, c) replaced by cell (or
 * the whole heights by heights when not NULL), the other topography fields by topo_rest. */
static char *bad_json(const char *cell, int r, int c, const char *heights, const char *topo_rest,
                      const char *extra)
{
    buf b = {0};
    add(&b, "{\"topography\":{\"heights\":");
    if (heights) {
        add(&b, "%s", heights);
    } else {
        add(&b, "[");
        for (int j = 0; j < 16; j++) {
            add(&b, "%s[", j ? "," : "");
            for (int i = 0; i < 16; i++) {
                if (j == r && i == c)
                    add(&b, "%s%s", i ? "," : "", cell);
                else
                    add(&b, "%s%g", i ? "," : "", 1e-9 * sin(0.7 * i + 1.3 * j * j));
            }
            add(&b, "]");
        }
        add(&b, "]");
    }
    add(&b, "%s}%s}", topo_rest ? topo_rest : ",\"dx\":1e-8", extra ? extra : "");
    return b.s;
}

/* A JSON matrix of n copies of row. */
static buf rows(const char *row, int n)
{
    buf b = {0};
    add(&b, "[");
    for (int j = 0; j < n; j++)
        add(&b, "%s[%s]", j ? "," : "", row);
    add(&b, "]");
    return b;
}

static void expect_json(char *req, const char *pointer, const char *what)
{
    expect_one(ask("psd", req), pointer, NULL, what);
    free(req);
}

static void bad_json_inputs(void **state)
{
    /* the base request is fine */
    char *ok = bad_json("1e-9", 0, 0, NULL, NULL, NULL);
    answer a = ask("psd", ok);
    assert_int_equal(a.status, 200);
    cJSON_Delete(a.body);
    free(ok);
    expect_json(bad_json("\"abc\"", 3, 4, NULL, NULL, NULL), "/topography/heights/3/4", "string");
    expect_json(bad_json("\"NaN\"", 0, 0, NULL, NULL, NULL), "/topography/heights/0/0", "NaN");
    expect_json(bad_json("1e400", 5, 15, NULL, NULL, NULL), "/topography/heights/5/15", "1e400");
    expect_json(bad_json("null", 2, 2, NULL, NULL, NULL), "/topography/heights/2/2", "null");
    expect_json(bad_json("2e3", 2, 2, NULL, NULL, NULL), "/topography/heights/2/2", "2 km");
    expect_json(bad_json("[1]", 2, 2, NULL, NULL, NULL), "/topography/heights/2/2", "nested");
    expect_json(bad_json("1e-9, 2e-9", 7, 0, NULL, NULL, NULL), "/topography/heights/7",
                "ragged row");
    expect_json(bad_json(NULL, 0, 0, "[]", NULL, NULL), "/topography/heights", "no rows");
    expect_json(bad_json(NULL, 0, 0, "{}", NULL, NULL), "/topography/heights", "not an array");
    expect_json(bad_json(NULL, 0, 0, "[1,2]", NULL, NULL), "/topography/heights/0",
                "rows not arrays");
    /* too small: 15 rows, rows of 15, a profile of 15; all equal */
    buf b = rows("1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16", 15);
    expect_json(bad_json(NULL, 0, 0, b.s, NULL, NULL), "/topography/heights", "15 rows");
    free(b.s);
    b = rows("1,2,3,4,5,6,7,8,9,10,11,12,13,14,15", 16);
    expect_json(bad_json(NULL, 0, 0, b.s, NULL, NULL), "/topography/heights/0", "rows of 15");
    free(b.s);
    expect_json(bad_json(NULL, 0, 0, "[[1,2,3,4,5,6,7,8,9,10,11,12,13,14,15]]", NULL, NULL),
                "/topography/heights", "a profile of 15");
    b = rows("3e-9,3e-9,3e-9,3e-9,3e-9,3e-9,3e-9,3e-9,3e-9,3e-9,3e-9,3e-9,3e-9,3e-9,3e-9,3e-9", 16);
    expect_json(bad_json(NULL, 0, 0, b.s, NULL, NULL), "/topography/heights", "all equal");
    free(b.s);
    /* a plane, not periodic: nothing left after the plane goes (the core says so) */
    b = (buf){0};
    add(&b, "[");
    for (int j = 0; j < 16; j++) {
        add(&b, "%s[", j ? "," : "");
        for (int i = 0; i < 16; i++)
            add(&b, "%s%g", i ? "," : "", 1e-9 * i - 2e-9 * j);
        add(&b, "]");
    }
    add(&b, "]");
    char *plane = bad_json(NULL, 0, 0, b.s, NULL, NULL);
    answer p = ask("psd", plane);
    free(plane);
    assert_int_equal(p.status, 422);
    assert_string_equal(get(p.body, "type")->valuestring, "/problems/outside-model");
    assert_string_equal(get(cJSON_GetArrayItem(get(p.body, "errors"), 0), "pointer")->valuestring,
                        "/topography/heights");
    cJSON_Delete(p.body);
    free(b.s);
    /* the spacings, periodic, fields */
    expect_json(bad_json("0", 0, 0, NULL, ",\"dx\":0", NULL), "/topography/dx", "dx = 0");
    expect_json(bad_json("0", 0, 0, NULL, ",\"dx\":-1e-9", NULL), "/topography/dx", "dx < 0");
    expect_json(bad_json("0", 0, 0, NULL, ",\"dx\":2", NULL), "/topography/dx", "dx = 2 m");
    expect_json(bad_json("0", 0, 0, NULL, ",\"dx\":\"1e-9\"", NULL), "/topography/dx",
                "dx a string");
    expect_json(bad_json("0", 0, 0, NULL, "", NULL), "/topography/dx", "no dx");
    expect_json(bad_json("0", 0, 0, NULL, ",\"dx\":1e-9,\"dy\":0", NULL), "/topography/dy",
                "dy = 0");
    expect_json(bad_json("0", 0, 0, NULL, ",\"dx\":1e-9,\"periodic\":\"yes\"", NULL),
                "/topography/periodic", "periodic a string");
    expect_json(bad_json("0", 0, 0, NULL, ",\"dx\":1e-9,\"dz\":1", NULL), "/topography/dz",
                "unknown field");
    expect_json(bad_json("0", 0, 0, NULL, NULL, ",\"psd\":{}"), "/psd", "a psd field");
    expect_json(bad_json("0", 0, 0, NULL, NULL, ",\"material\":{\"E_star\":1e11,\"dgamma\":0.05}"),
                "/material/epsilon", "material without epsilon");
    expect_one(ask("psd", "{}"), "/topography", NULL, "no topography");
    expect_one(ask("psd", "{\"topography\":[]}"), "/topography", NULL, "topography an array");
    /* the server's cap on points */
    ljgap__limits l;
    ljgap__limits_default(&l);
    l.max_topo_points = 255;
    ljgap__handler_set_limits(&l);
    expect_json(bad_json("0", 0, 0, NULL, NULL, NULL), "/topography/heights", "over the cap");
    ljgap__limits_default(&l);
    ljgap__handler_set_limits(&l);
}

/* A 16 × 16 text matrix with line r (1-based, of the matrix) replaced by line. */
static char *bad_text(int r, const char *line)
{
    buf b = {0};
    for (int j = 1; j <= 16; j++) {
        if (j == r) {
            add(&b, "%s\n", line);
            continue;
        }
        for (int i = 0; i < 16; i++)
            add(&b, "%s%g", i ? " " : "", 1e-9 * cos(0.9 * i + 0.4 * j * j));
        add(&b, "\n");
    }
    return b.s;
}

static void expect_text(const char *query, char *body, const char *pointer, const char *detail,
                        const char *what)
{
    expect_one(ask_text("psd", query, body, strlen(body)), pointer, detail, what);
    free(body);
}

#define ROW15 "1 2 3 4 5 6 7 8 9 10 11 12 13 14 15"

static void bad_text_inputs(void **state)
{
    char *ok = bad_text(0, "");
    answer a = ask_text("psd", "dx=1e-8", ok, strlen(ok));
    assert_int_equal(a.status, 200);
    cJSON_Delete(a.body);
    free(ok);
    expect_text("dx=1e-8", bad_text(3, ROW15 " abc"), "/topography/heights/2/15",
                "line 3, column 37: \"abc\" is not a number", "a word");
    expect_text("dx=1e-8", bad_text(1, "nan " ROW15), "/topography/heights/0/0",
                "line 1, column 1: \"nan\"", "nan");
    expect_text("dx=1e-8", bad_text(5, ROW15 " inf"), "/topography/heights/4/15",
                "line 5, column 37: \"inf\"", "inf");
    expect_text("dx=1e-8", bad_text(5, ROW15 " 0x1p-30"), "/topography/heights/4/15",
                "line 5, column 37", "hex");
    expect_text("dx=1e-8", bad_text(2, "1e400 " ROW15), "/topography/heights/1/0",
                "line 2, column 1: \"1e400\" overflows", "1e400");
    expect_text("dx=1e-8", bad_text(2, "2000 " ROW15), "/topography/heights/1/0",
                "line 2, column 1: \"2000\" is outside", "2 km");
    expect_text("dx=1e-8", bad_text(16, ROW15), "/topography/heights/15",
                "line 16 has 15 values, the first row (line 1) has 16", "ragged");
    expect_text("dx=1e-8", bad_text(4, "1,2,3,4,5,6,7,8,,9,10,11,12,13,14,15,16"),
                "/topography/heights/3/8", "line 4, column 17: an empty value", "two commas");
    expect_text("dx=1e-8", bad_text(4, "1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,"),
                "/topography/heights/3/16", "line 4, column 39: the line ends with a comma",
                "trailing comma");
    expect_text("dx=1e-8", strdup(""), "/topography/heights", "no heights", "empty body");
    expect_text("dx=1e-8", strdup("# only a comment\n\n   \n"), "/topography/heights", "no heights",
                "comments only");
    expect_text("dx=1e-8", bad_text(1, "\x01\xff\xfe " ROW15), "/topography/heights/0/0",
                "line 1, column 1: \"???\" is not a number", "binary junk");
    expect_text("dx=1e-8", strdup(ROW15 "\n"), "/topography/heights", "a profile of 15 heights",
                "a profile of 15");
    char *t15 = bad_text(0, ""); /* 15 lines of 16 */
    *strrchr(t15, '\n') = '\0';
    *(strrchr(t15, '\n') + 1) = '\0';
    expect_text("dx=1e-8", t15, "/topography/heights", "15 rows", "15 rows");
}

static void bad_text_query(void **state)
{
    expect_text("", bad_text(0, ""), "/topography/dx", NULL, "no dx");
    expect_text("dx=abc", bad_text(0, ""), "/topography/dx", NULL, "dx a word");
    expect_text("dx=-1e-9", bad_text(0, ""), "/topography/dx", NULL, "dx < 0");
    expect_text("dx=inf", bad_text(0, ""), "/topography/dx", NULL, "dx inf");
    expect_text("dx=1e-8&dy=0", bad_text(0, ""), "/topography/dy", NULL, "dy = 0");
    expect_text("dx=1e-8&periodic=maybe", bad_text(0, ""), "/topography/periodic", NULL,
                "periodic maybe");
    expect_text("dx=1e-8&dx=2e-8", bad_text(0, ""), "/topography/dx",
                "the query parameter \"dx\" is given more than once", "dx twice");
    expect_text("dx=1e-8&heights=1", bad_text(0, ""), "/heights", "unknown query parameter",
                "heights in the query");
    expect_text("dx=1e-8&a/b~c=1", bad_text(0, ""), "/a~1b~0c", "unknown query parameter",
                "escaped pointer");
    expect_text("dx=1e-8&E_star=1e11&dgamma=0.05", bad_text(0, ""), "/material/epsilon", NULL,
                "material without epsilon");
    /* periodic without a value is true */
    char *t = bad_text(0, "");
    answer a = ask_text("psd", "dx=1e-8&periodic", t, strlen(t));
    assert_int_equal(a.status, 200);
    assert_true(cJSON_IsTrue(get(get(a.body, "grid"), "periodic")));
    cJSON_Delete(a.body);
    /* text for another endpoint */
    ljgap__reply r;
    ljgap__handle_text("adhesion", NULL, 0, t, strlen(t), NULL, &r);
    assert_int_equal(r.status, 404);
    assert_true(ljgap__handler_has_text("psd") && !ljgap__handler_has_text("adhesion"));
    ljgap__reply_free(&r);
    /* the cap on points stops the parse */
    ljgap__limits l;
    ljgap__limits_default(&l);
    l.max_topo_points = 100;
    ljgap__handler_set_limits(&l);
    expect_one(ask_text("psd", "dx=1e-8", t, strlen(t)), "/topography/heights",
               "more than 100 heights (line 7)", "over the cap");
    ljgap__limits_default(&l);
    ljgap__handler_set_limits(&l);
    free(t);
}

/* A measured-like map (roll-off, cutoff at 20 k_f): the fit is sound inside its band, the psd
 * object keeps the bins up to Nyquist without a tail (the bins above the band leave the law),
 * a warning says so; the same surface without the cutoff gets the tail. */
static void tail_only_where_the_law_holds(void **state)
{
    const size_t n = 128;
    double kf = 2 * M_PI / (n * 1e-8), m0;
    map m = {n, n, 1e-8, malloc(n * n * sizeof(double)), 0};
    assert_non_null(m.h);
    for (int cut = 1; cut >= 0; cut--) {
        realsurf_spec s = {0};
        s.D = 2.4, s.k_r = 2 * kf, s.k_c = cut ? 20 * kf : 0;
        s.C = realsurf_level(s.D, s.k_r, M_PI / 1e-8, 1e-18);
        assert_int_equal(realsurf_make(m.h, n, n, 1e-8, 1e-8, &s, 4, &m0), 0);
        char *req = map_json(&m, 1, NULL);
        answer a = ask("psd", req);
        assert_int_equal(a.status, 200);
        const cJSON *fit = get(a.body, "fit"), *psd = get(a.body, "psd");
        assert_true(cJSON_IsTrue(get(fit, "sound")));
        near(num(fit, "D"), 2.4, 0.1, "D");
        assert_int_equal(cJSON_GetArraySize(get(psd, "P_err")), cJSON_GetArraySize(get(psd, "k")));
        if (cut) {
            assert_true(num(fit, "k_max") <= 20 * kf * 1.13);
            assert_null(cJSON_GetObjectItemCaseSensitive(psd, "tail"));
            char *w = cJSON_PrintUnformatted(get(get(a.body, "meta"), "warnings"));
            assert_non_null(strstr(w, "the psd object has no tail"));
            free(w);
        } else {
            near(num(get(psd, "tail"), "exponent"), 2 * num(fit, "D") - 8, 1e-12, "tail");
        }
        cJSON_Delete(a.body);
        free(req);
    }
    free(m.h);
}

/* ---- the inputs of issue 25: fit band, detrend, tip radius, resolution, P_err ---- */

static void new_inputs(void **state)
{
    map m = make_map(64, 64, 1e-8, 2.4, 1e-9, 21);
    double kf = 2 * M_PI / (64 * 1e-8);
    buf x = {0};
    add(&x, ",\"fit\":{\"k_min\":%.17g,\"k_max\":%.17g}", 2 * kf, 20 * kf);
    char *req = map_json(&m, 0, x.s);
    answer a = ask("psd", req);
    assert_int_equal(a.status, 200);
    const cJSON *fit = get(a.body, "fit");
    assert_string_equal(get(fit, "band")->valuestring, "given");
    assert_true(num(fit, "k_min") >= 2 * kf * (1 - 1e-9) && num(fit, "k_max") <= 20 * kf);
    assert_string_equal(get(get(a.body, "grid"), "detrend")->valuestring, "plane");
    cJSON_Delete(a.body), free(req), free(x.s);
    /* the same from a text upload's query */
    char *t = map_text(&m, 0);
    x = (buf){0};
    add(&x, "dx=1e-8&fit_k_min=%.17g&fit_k_max=%.17g&detrend=lines&resolution=1e-7", 2 * kf,
        20 * kf);
    a = ask_text("psd", x.s, t, strlen(t));
    assert_int_equal(a.status, 200);
    assert_string_equal(get(get(a.body, "fit"), "band")->valuestring, "given");
    assert_string_equal(get(get(a.body, "grid"), "detrend")->valuestring, "lines");
    assert_string_equal(get(get(a.body, "reliable"), "by")->valuestring, "resolution");
    near(num(get(a.body, "reliable"), "k_max"), M_PI / 1e-7, 1e-3, "pi / resolution");
    cJSON_Delete(a.body), free(x.s);
    /* bad values at their pointers, JSON and query */
    const char *topo = ",\"dx\":1e-8";
    char rest[200];
    const struct {
        const char *field, *ptr;
    } bad[] = {{"\"detrend\":\"tilt\"", "/topography/detrend"},
               {"\"detrend\":3", "/topography/detrend"},
               {"\"tip_radius\":-1e-8", "/topography/tip_radius"},
               {"\"tip_radius\":\"big\"", "/topography/tip_radius"},
               {"\"resolution\":0", "/topography/resolution"},
               {"\"resolution\":1e9", "/topography/resolution"}};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        snprintf(rest, sizeof rest, "%s,%s", topo, bad[i].field);
        expect_json(bad_json("1e-9", 0, 0, NULL, rest, NULL), bad[i].ptr, bad[i].field);
    }
    expect_json(bad_json("1e-9", 0, 0, NULL, NULL, ",\"fit\":{\"k_min\":-1}"), "/fit/k_min",
                "k_min < 0");
    expect_json(bad_json("1e-9", 0, 0, NULL, NULL, ",\"fit\":{\"k_min\":1e8,\"k_max\":1e7}"),
                "/fit/k_max", "k_max below k_min");
    expect_json(bad_json("1e-9", 0, 0, NULL, NULL, ",\"fit\":{\"kmin\":1e8}"), "/fit/kmin",
                "unknown field of fit");
    expect_json(bad_json("1e-9", 0, 0, NULL, NULL, ",\"fit\":[1,2]"), "/fit", "fit an array");
    expect_text("dx=1e-8&fit_k_min=abc", map_text(&m, 0), "/fit/k_min", NULL, "fit_k_min a word");
    expect_text("dx=1e-8&tip_radius=-1", map_text(&m, 0), "/topography/tip_radius", NULL,
                "tip_radius < 0");
    expect_text("dx=1e-8&detrend=tilt", map_text(&m, 0), "/topography/detrend", NULL,
                "detrend tilt");
    free(t);
    /* P_err and tail.exponent_err of a table: accepted, checked */
    const char *tab = "{\"psd\":{\"kind\":\"table\",\"k\":[1,2,4],\"P\":[1e-3,2e-4,3e-5]%s},"
                      "\"tol\":1e-4}";
    const struct {
        const char *extra, *ptr;
    } tb[] = {{",\"P_err\":[1e-4,1e-5,-1e-6]", "/psd/P_err/2"},
              {",\"P_err\":[1e-4,\"x\",1e-6]", "/psd/P_err/1"},
              {",\"P_err\":[1e-4,1e-5]", "/psd/P_err"},
              {",\"P_err\":3", "/psd/P_err"},
              {",\"tail\":{\"exponent\":-3,\"exponent_err\":-0.1}", "/psd/tail/exponent_err"},
              {",\"tail\":{\"exponent\":-3,\"exponent_err\":\"a\"}", "/psd/tail/exponent_err"}};
    for (size_t i = 0; i < sizeof tb / sizeof *tb; i++) {
        x = (buf){0};
        add(&x, tab, tb[i].extra);
        expect_one(ask("adhesion", x.s), tb[i].ptr, NULL, tb[i].extra);
        free(x.s);
    }
    x = (buf){0};
    add(&x, tab, ",\"P_err\":[1e-4,0,1e-6],\"tail\":{\"exponent\":-3,\"exponent_err\":0.1}");
    buf y = {0};
    add(&y, tab, ",\"tail\":{\"exponent\":-3}");
    a = ask("adhesion", x.s);
    answer b = ask("adhesion", y.s);
    assert_int_equal(a.status, 200);
    assert_int_equal(b.status, 200);
    near(num(a.body, "dgamma_eff"), num(b.body, "dgamma_eff"), 0, "the errors change nothing");
    cJSON_Delete(a.body), cJSON_Delete(b.body), free(x.s), free(y.s);
    free(m.h);
}

/* ---- out of memory, threads ---- */

static void out_of_memory(void **state)
{
    map m = make_map(16, 16, 1e-8, 2.5, 1e-9, 1);
    char *req = map_json(&m, 0, ",\"material\":" MAT);
    oom_sweep("psd", req, 5000);
    free(req), free(m.h);
}

typedef struct {
    const char *req;
    char *answer;
} worker_arg;

static void *worker(void *p)
{
    worker_arg *w = p;
    ljgap__reply r;
    for (int i = 0; i < 4; i++) {
        ljgap__handle("psd", w->req, strlen(w->req), &r);
        if (r.status == 200) {
            cJSON *b = cJSON_Parse(r.body);
            free(w->answer);
            w->answer = b ? without_meta(b) : NULL;
            cJSON_Delete(b);
        }
        ljgap__reply_free(&r);
    }
    return NULL;
}

/* psd plans FFTs on compute threads while a simulation plans its own: FFTW's planner must be
 * serialised across modules (core/topo/topo.c makes it thread-safe). */
static void concurrent_with_simulation(void **state)
{
    map m = make_map(96, 80, 1e-8, 2.5, 1e-9, 17);
    char *req = map_json(&m, 0, NULL);
    worker_arg args[3] = {{req, NULL}, {req, NULL}, {req, NULL}};
    pthread_t th[3];
    ljgap_psd psd;
    ljgap_sim_opts o;
    ljgap_sim_result res;
    double g = 3;
    assert_int_equal(ljgap_psd_power(&psd, 2.2, 1, 8, LJGAP_LEVEL_M0, 0.01), LJGAP_OK);
    ljgap_sim_opts_default(&o);
    o.n = 32;
    o.realizations = 8;
    for (int t = 0; t < 3; t++)
        assert_int_equal(pthread_create(&th[t], NULL, worker, &args[t]), 0);
    assert_int_equal(ljgap_sim_run(&psd, &o, &g, 1, &res, NULL), LJGAP_OK);
    ljgap_sim_result_free(&res);
    for (int t = 0; t < 3; t++)
        pthread_join(th[t], NULL);
    for (int t = 0; t < 3; t++) {
        assert_non_null(args[t].answer);
        assert_string_equal(args[t].answer, args[0].answer);
    }
    for (int t = 0; t < 3; t++)
        free(args[t].answer);
    free(req), free(m.h);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(json_periodic_map),
        cmocka_unit_test(text_equals_json),
        cmocka_unit_test(text_numbers_are_strtods),
        cmocka_unit_test(profile),
        cmocka_unit_test(psd_roundtrip_into_adhesion),
        cmocka_unit_test(bad_json_inputs),
        cmocka_unit_test(bad_text_inputs),
        cmocka_unit_test(bad_text_query),
        cmocka_unit_test(new_inputs),
        cmocka_unit_test(tail_only_where_the_law_holds),
        cmocka_unit_test(out_of_memory),
        cmocka_unit_test(concurrent_with_simulation),
    };
    gsl_set_error_handler_off();
    return cmocka_run_group_tests(tests, NULL, NULL);
}
