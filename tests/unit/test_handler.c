/* test_handler.c -- the request handler against its contract (docs/api.md).
 *
 * One test per validation rule (the rules[] table; each row runs as its own cmocka test):
 * each sends a request that is valid except for one thing and asserts a 422 validation
 * problem whose errors[] holds exactly one entry, at the expected JSON pointer. Then the
 * other problem statuses (400, 404, cap, cancel, out of memory, by failing cJSON's allocator
 * at every allocation in turn), and the success paths of each endpoint, checked against
 * invariants (mass, mean, m0 -> 0 limits) and theory.md §4.
 *
 * Requests are written with ' for " to keep them readable; ask() swaps them.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "handler.h"
#include "ljgap.h"

#include <cjson/cJSON.h>

#include "../lib/oom.h"
#include <gsl/gsl_errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PSD "{'kind':'power','D':2.5,'k1':1,'k2':8,'m0':0.5}"
#define PSD_INF "{'kind':'power','D':2.5,'k1':1,'m0':0.5}"
/* E* = 1 GPa, Δγ = 50 mJ/m², ε = 0.3 nm: χ = 3ε²E* /(16Δγ) = 3.375e-10 m */
#define DG_EPS "'dgamma':0.05,'epsilon':3e-10"
#define MAT "'material':{'E_star':1e9," DG_EPS "}"
#define CHI 3.375e-10
/* PSD in SI: k1 = 1/χ, k2 = 8/χ (1/m), h_rms = √0.5 ε (m): the dimensionless PSD */
#define PSD_SI                                                                                     \
    "{'kind':'power','D':2.5,'k1':2962962962.962963,'k2':23703703703.703704,"                      \
    "'h_rms':2.1213203435596424e-10}"

/* The answer of one request: status, content type and the parsed body. */
typedef struct {
    int status;
    const char *ctype;
    cJSON *body;
} answer;

static answer ask(const char *endpoint, const char *request)
{
    char *s = strdup(request);
    ljgap__reply r;
    answer a;
    assert_non_null(s);
    for (char *c = s; *c; c++)
        if (*c == '\'') *c = '"';
    ljgap__handle(endpoint, s, strlen(s), &r);
    assert_non_null(r.body);
    assert_int_equal(r.len, strlen(r.body));
    a.status = r.status;
    a.ctype = r.content_type;
    a.body = cJSON_Parse(r.body);
    if (!a.body) fail_msg("answer is not JSON: %s", r.body);
    ljgap__reply_free(&r);
    free(s);
    return a;
}

static const char *str(const cJSON *o, const char *name)
{
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(o, name);
    assert_true(cJSON_IsString(it));
    return it->valuestring;
}

static double num(const cJSON *o, const char *name)
{
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(o, name);
    if (!cJSON_IsNumber(it)) fail_msg("field %s is not a number", name);
    return it->valuedouble;
}

static const cJSON *get(const cJSON *o, const char *name)
{
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(o, name);
    if (!it) fail_msg("field %s is missing", name);
    return it;
}

/* The problem+json shape; returns errors[]. */
static const cJSON *check_problem(const answer *a, int status, const char *type_slug)
{
    char type[120];
    snprintf(type, sizeof type, "/problems/%s", type_slug);
    assert_int_equal(a->status, status);
    assert_string_equal(a->ctype, "application/problem+json");
    assert_string_equal(str(a->body, "type"), type);
    assert_true(strlen(str(a->body, "title")) > 0);
    assert_true(strlen(str(a->body, "detail")) > 0);
    assert_int_equal((int)num(a->body, "status"), status);
    assert_true(cJSON_IsArray(get(a->body, "errors")));
    return get(a->body, "errors");
}

/* A 422 validation problem with exactly one error, at pointer. */
static void expect_pointer(const char *endpoint, const char *request, const char *pointer)
{
    answer a = ask(endpoint, request);
    const cJSON *errs = check_problem(&a, 422, "validation");
    const cJSON *e = cJSON_GetArrayItem(errs, 0);
    if (cJSON_GetArraySize(errs) != 1 || strcmp(str(e, "pointer"), pointer) != 0) {
        char *s = cJSON_PrintUnformatted(errs);
        fail_msg("expected one error at \"%s\", got %s", pointer, s);
    }
    assert_true(strlen(str(e, "detail")) > 0);
    cJSON_Delete(a.body);
}

/* ---- one rule, one test: a request valid but for one field ---- */

typedef struct {
    const char *name;     /* test name */
    const char *endpoint; /* where it is sent */
    const char *request;  /* ' for " */
    const char *pointer;  /* the one error expected */
} rule;

#define POWER(fields) "{'psd':{'kind':'power'," fields "}}"
#define TABLE(fields) "{'psd':{'kind':'table'," fields "}}"
#define WITH(fields) "{'psd':" PSD "," fields "}"
#define WITH_INF(fields) "{'psd':" PSD_INF "," fields "}"

static const rule rules[] = {
    /* the psd object */
    {"k1_below_k0", "adhesion", POWER("'D':2.5,'k1':0.4,'k2':8,'m0':0.5"), "/psd/k1"},
    {"k1_is_k0", "adhesion", POWER("'D':2.5,'k1':0.4697841169402636,'m0':0.5"), "/psd/k1"},
    {"table_k_below_k0", "adhesion", TABLE("'k':[0.4,2,3],'P':[1,1,1]"), "/psd/k/0"},
    {"D_is_3", "adhesion", POWER("'D':3,'k1':1,'k2':8,'m0':0.5"), "/psd/D"},
    {"D_is_2", "adhesion", POWER("'D':2,'k1':1,'k2':8,'m0':0.5"), "/psd/D"},
    {"H_outside", "adhesion", POWER("'H':1.2,'k1':1,'m0':0.5"), "/psd/H"},
    {"D_and_H", "adhesion", POWER("'D':2.5,'H':0.5,'k1':1,'m0':0.5"), "/psd/H"},
    {"D_missing", "adhesion", POWER("'k1':1,'m0':0.5"), "/psd/D"},
    {"k2_not_above_k1", "adhesion", POWER("'D':2.5,'k1':2,'k2':2,'m0':0.5"), "/psd/k2"},
    {"non_finite_number", "adhesion", POWER("'D':2.5,'k1':1,'m0':1e999"), "/psd/m0"},
    {"zero_C", "adhesion", POWER("'D':2.5,'k1':1,'C':0"), "/psd/C"},
    {"negative_h_rms", "adhesion", POWER("'D':2.5,'k1':1,'h_rms':-1"), "/psd/h_rms"},
    {"D_is_string", "adhesion", POWER("'D':'2.5','k1':1,'m0':0.5"), "/psd/D"},
    {"psd_is_array", "adhesion", "{'psd':[1]}", "/psd"},
    {"missing_psd", "adhesion", "{}", "/psd"},
    {"missing_k1", "adhesion", POWER("'D':2.5,'m0':0.5"), "/psd/k1"},
    {"missing_kind", "adhesion", "{'psd':{'D':2.5,'k1':1,'m0':0.5}}", "/psd/kind"},
    {"two_level_fields", "adhesion", POWER("'D':2.5,'k1':1,'m0':0.5,'h_rms':0.7"), "/psd/h_rms"},
    {"no_level_field", "adhesion", POWER("'D':2.5,'k1':1"), "/psd"},
    {"unknown_kind", "adhesion", "{'psd':{'kind':'fractal','D':2.5,'k1':1,'m0':0.5}}", "/psd/kind"},
    {"table_unsorted", "adhesion", TABLE("'k':[1,2,2,3],'P':[1,1,1,1]"), "/psd/k/2"},
    {"table_non_positive", "adhesion", TABLE("'k':[1,2,3,4],'P':[1,1,1,0]"), "/psd/P/3"},
    {"table_length_mismatch", "adhesion", TABLE("'k':[1,2,3],'P':[1,1]"), "/psd/P"},
    {"table_too_short", "adhesion", TABLE("'k':[1],'P':[1,1]"), "/psd/k"},
    {"tail_exponent", "adhesion", TABLE("'k':[1,2],'P':[1,1],'tail':{'exponent':-2}"),
     "/psd/tail/exponent"},
    {"unknown_psd_field", "adhesion", POWER("'D':2.5,'k1':1,'m0':0.5,'m_0':1"), "/psd/m_0"},
    /* common fields */
    {"unknown_method", "adhesion", WITH("'method':'fem'"), "/method"},
    {"method_not_string", "adhesion", WITH("'method':3"), "/method"},
    {"tol_zero", "adhesion", WITH("'tol':0"), "/tol"},
    {"tol_too_large", "adhesion", WITH("'tol':0.2"), "/tol"},
    {"tol_boolean", "adhesion", WITH("'tol':true"), "/tol"},
    {"vmax_outside", "adhesion", WITH("'method':'paper','vmax':1.5"), "/vmax"},
    {"fixed_vmax_number", "adhesion", WITH("'method':'paper','fixed_vmax':1"), "/fixed_vmax"},
    {"fixed_vmax_string", "adhesion", WITH("'method':'paper','fixed_vmax':'true'"), "/fixed_vmax"},
    {"samples_too_few", "adhesion", WITH("'method':'montecarlo','samples':99"), "/samples"},
    {"samples_fraction", "adhesion", WITH("'method':'montecarlo','samples':1000.5"), "/samples"},
    {"samples_over_cap", "adhesion", WITH("'method':'montecarlo','samples':2e6"), "/samples"},
    {"seed_negative", "adhesion", WITH("'method':'montecarlo','seed':-1"), "/seed"},
    {"seed_fraction", "adhesion", WITH("'method':'montecarlo','seed':0.5"), "/seed"},
    {"unknown_top_field", "adhesion", WITH("'tolerance':1e-3"), "/tolerance"},
    {"other_endpoints_field", "adhesion", WITH("'g_ave':[1]"), "/g_ave"},
    {"unknown_field_escaped", "adhesion", WITH("'a/b~c':1"), "/a~1b~0c"},
    {"duplicate_field", "adhesion", WITH("'tol':1e-3,'tol':1e-4"), "/tol"},
    {"body_array", "adhesion", "[1,2]", ""},
    {"body_number", "adhesion", "42", ""},
    /* traction */
    {"traction_g_ave_missing", "traction", "{'psd':" PSD "}", "/g_ave"},
    {"traction_range_n_1", "traction", WITH("'g_ave':{'min':1,'max':3,'n':1}"), "/g_ave/n"},
    {"traction_range_n_fraction", "traction", WITH("'g_ave':{'min':1,'max':3,'n':2.5}"),
     "/g_ave/n"},
    {"traction_range_order", "traction", WITH("'g_ave':{'min':3,'max':1,'n':5}"), "/g_ave/max"},
    {"traction_range_unknown", "traction", WITH("'g_ave':{'min':1,'max':3,'n':5,'step':1}"),
     "/g_ave/step"},
    {"traction_array_negative", "traction", WITH("'g_ave':[1,-2,3]"), "/g_ave/1"},
    {"traction_array_empty", "traction", WITH("'g_ave':[]"), "/g_ave"},
    {"traction_g_ave_string", "traction", WITH("'g_ave':'1'"), "/g_ave"},
    /* pdf */
    {"pdf_null_needs_infinite_support", "pdf", WITH("'g_ave':1,'k2':[null]"), "/k2/0"},
    {"pdf_k2_not_above_k1", "pdf", WITH_INF("'g_ave':1,'k2':[5,1]"), "/k2/1"},
    {"pdf_g_ave_array", "pdf", WITH_INF("'g_ave':[1],'k2':[5]"), "/g_ave"},
    {"pdf_grid_min", "pdf", WITH_INF("'g_ave':1,'k2':[5],'grid':{'min':0,'max':2,'n':9}"),
     "/grid/min"},
    /* sweep */
    {"sweep_needs_power_law", "sweep",
     "{'psd':{'kind':'table','k':[1,2],'P':[1,1]},'vary':'m0','values':[0.1]}", "/psd/kind"},
    {"sweep_vary_unknown", "sweep", WITH("'vary':'k3','values':[3]"), "/vary"},
    {"sweep_k2_at_k1", "sweep", WITH_INF("'vary':'k2','values':[1]"), "/values/0"},
    /* the measurement's uncertainty (issue 29; tests/unit/test_uncert.c has the rest) */
    {"input_error_not_bool", "adhesion", WITH("'input_error':'yes'"), "/input_error"},
    {"power_h_rms_err_without_h_rms", "adhesion", POWER("'D':2.5,'k1':1,'m0':0.5,'h_rms_err':0.1"),
     "/psd/h_rms_err"},
    {"table_P_corr_not_array", "adhesion", TABLE("'k':[1,2],'P':[1,1],'P_err':[0,0],'P_corr':0.5"),
     "/psd/P_corr"},
    {"sweep_D_outside", "sweep", WITH("'vary':'D','values':[2.2,2.5,3.1]"), "/values/2"},
    {"sweep_k1_below_k0", "sweep", WITH("'vary':'k1','values':[2,0.3]"), "/values/1"},
    {"sweep_m0_zero", "sweep", WITH("'vary':'m0','values':[0.1,0]"), "/values/1"},
    {"sweep_values_empty", "sweep", WITH("'vary':'m0','values':[]"), "/values"},
    /* physical units */
    {"material_E_star_zero", "adhesion", WITH("'material':{'E_star':0," DG_EPS "}"),
     "/material/E_star"},
    {"material_E1_negative", "adhesion",
     WITH("'material':{'E1':-1e9,'nu1':0.3,'E2':1e9,'nu2':0.3," DG_EPS "}"), "/material/E1"},
    {"material_E2_zero", "adhesion",
     WITH("'material':{'E1':1e9,'nu1':0.3,'E2':0,'nu2':0.3," DG_EPS "}"), "/material/E2"},
    {"material_nu_above_half", "adhesion",
     WITH("'material':{'E1':1e9,'nu1':0.3,'E2':1e9,'nu2':0.51," DG_EPS "}"), "/material/nu2"},
    {"material_nu_minus_one", "adhesion",
     WITH("'material':{'E1':1e9,'nu1':-1,'E2':1e9,'nu2':0.3," DG_EPS "}"), "/material/nu1"},
    {"material_nu_missing", "adhesion", WITH("'material':{'E1':1e9,'nu1':0.3,'E2':1e9," DG_EPS "}"),
     "/material/nu2"},
    {"material_both_moduli", "adhesion", WITH("'material':{'E_star':1e9,'E1':1e9," DG_EPS "}"),
     "/material/E1"},
    {"material_no_modulus", "adhesion", WITH("'material':{" DG_EPS "}"), "/material/E_star"},
    {"material_dgamma_zero", "adhesion",
     WITH("'material':{'E_star':1e9,'dgamma':0,'epsilon':3e-10}"), "/material/dgamma"},
    {"material_epsilon_negative", "adhesion",
     WITH("'material':{'E_star':1e9,'dgamma':0.05,'epsilon':-3e-10}"), "/material/epsilon"},
    {"material_epsilon_missing", "adhesion", WITH("'material':{'E_star':1e9,'dgamma':0.05}"),
     "/material/epsilon"},
    {"material_dgamma_missing", "adhesion", WITH("'material':{'E_star':1e9,'epsilon':3e-10}"),
     "/material/dgamma"},
    {"material_unknown_field", "adhesion", WITH("'material':{'E':1e9,'E_star':1e9," DG_EPS "}"),
     "/material/E"},
    {"material_not_object", "adhesion", WITH("'material':1e9"), "/material"},
    {"units_SI_without_material", "adhesion", WITH("'units':'SI'"), "/units"},
    {"units_unknown", "adhesion", WITH("'units':'cgs'," MAT), "/units"},
    {"si_k1_below_k0", "adhesion",
     "{'psd':{'kind':'power','D':2.5,'k1':1e9,'h_rms':1e-10},'units':'SI'," MAT "}", "/psd/k1"},
    {"si_sweep_k1_below_k0", "sweep",
     "{'psd':" PSD_SI ",'units':'SI'," MAT ",'vary':'k1','values':[1e9]}", "/values/0"},
    {"contact_needs_material", "contact", WITH("'R':1e-6"), "/material"},
    {"contact_R_missing", "contact", WITH(MAT), "/R"},
    {"contact_R_zero", "contact", WITH(MAT ",'R':0"), "/R"},
    {"contact_R_string", "contact", WITH(MAT ",'R':'1um'"), "/R"},
};

static void rule_test(void **state)
{
    const rule *r = *state;
    expect_pointer(r->endpoint, r->request, r->pointer);
}

static void k1_message_explains_k0(void **state)
{
    answer a = ask("adhesion", POWER("'D':2.5,'k1':0.3,'m0':0.5"));
    const cJSON *e = cJSON_GetArrayItem(check_problem(&a, 422, "validation"), 0);
    assert_non_null(strstr(str(e, "detail"), "0.46978"));
    assert_non_null(strstr(str(e, "detail"), "(19)"));
    cJSON_Delete(a.body);
}

/* A table request of n points k = 1..n, every P = p; malloc'd. */
static char *big_table(size_t n, int p)
{
    char *req = malloc(24 * n + 100);
    size_t used;
    assert_non_null(req);
    used = (size_t)sprintf(req, "{'psd':{'kind':'table','k':[");
    for (size_t i = 0; i < n; i++)
        used += (size_t)sprintf(req + used, "%s%zu", i ? "," : "", i + 1);
    used += (size_t)sprintf(req + used, "],'P':[");
    for (size_t i = 0; i < n; i++)
        used += (size_t)sprintf(req + used, "%s%d", i ? "," : "", p);
    sprintf(req + used, "]}}");
    return req;
}

static void table_too_long(void **state)
{
    char *req = big_table(10001, 1);
    answer a = ask("adhesion", req);
    const cJSON *errs = check_problem(&a, 422, "validation");
    assert_int_equal(cJSON_GetArraySize(errs), 2);
    assert_string_equal(str(cJSON_GetArrayItem(errs, 0), "pointer"), "/psd/k");
    assert_string_equal(str(cJSON_GetArrayItem(errs, 1), "pointer"), "/psd/P");
    cJSON_Delete(a.body);
    free(req);
}

static void sweep_too_many_values(void **state)
{
    ljgap__limits l;
    ljgap__limits_default(&l);
    l.max_points = 2;
    ljgap__handler_set_limits(&l);
    expect_pointer("sweep", WITH("'vary':'m0','values':[0.1,0.2,0.3]"), "/values");
    ljgap__limits_default(&l);
    ljgap__handler_set_limits(&l);
}

/* ---- problems other than validation ---- */

static void all_errors_collected(void **state)
{
    answer a = ask("adhesion", "{'psd':{'kind':'power','D':3.5,'k1':0.2,'m0':-1},'tol':5,"
                               "'seed':-3,'x':1}");
    const cJSON *errs = check_problem(&a, 422, "validation");
    static const char *const want[] = {"/x", "/tol", "/seed", "/psd/D", "/psd/k1", "/psd/m0"};
    assert_int_equal(cJSON_GetArraySize(errs), 6);
    for (int i = 0; i < 6; i++) {
        int found = 0;
        const cJSON *e;
        cJSON_ArrayForEach(e, errs) found |= strcmp(str(e, "pointer"), want[i]) == 0;
        if (!found) fail_msg("no error at %s", want[i]);
    }
    cJSON_Delete(a.body);
}

static void errors_capped(void **state)
{
    char *req = big_table(300, -1);
    answer a = ask("adhesion", req);
    assert_int_equal(cJSON_GetArraySize(check_problem(&a, 422, "validation")), 100);
    assert_non_null(strstr(str(a.body, "detail"), "300"));
    cJSON_Delete(a.body);
    free(req);
}

static void malformed_json(void **state)
{
    static const char *const bad[] = {"{", "{'psd':}", "{} x", "", "nul", "{'a':1}{}"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        answer a = ask("adhesion", bad[i]);
        assert_int_equal(cJSON_GetArraySize(check_problem(&a, 400, "malformed-json")), 0);
        cJSON_Delete(a.body);
    }
}

static void body_not_nul_terminated(void **state)
{
    /* the handler reads len bytes only: "{}" followed by garbage it must not see */
    const char buf[] = "{}garbage";
    ljgap__reply r;
    ljgap__handle("adhesion", buf, 2, &r);
    assert_int_equal(r.status, 422); /* {} is valid JSON without psd */
    assert_non_null(strstr(r.body, "/psd"));
    ljgap__reply_free(&r);
    ljgap__handle("adhesion", buf, 4, &r);
    assert_int_equal(r.status, 400);
    ljgap__reply_free(&r);
}

static void unknown_endpoint(void **state)
{
    answer a = ask("adhesions", "{}");
    check_problem(&a, 404, "not-found");
    cJSON_Delete(a.body);
    a = ask("", "{}");
    check_problem(&a, 404, "not-found");
    cJSON_Delete(a.body);
    assert_true(ljgap__handler_has("adhesion"));
    assert_true(ljgap__handler_has("sweep"));
    assert_true(ljgap__handler_has("contact"));
    assert_false(ljgap__handler_has(NULL));
}

static void time_cap(void **state)
{
    ljgap__limits l;
    ljgap__limits_default(&l);
    l.max_seconds = 1e-12;
    ljgap__handler_set_limits(&l);
    answer a = ask("adhesion", "{'psd':" PSD "}");
    ljgap__limits_default(&l);
    ljgap__handler_set_limits(&l);
    check_problem(&a, 422, "cap-exceeded");
    assert_non_null(strstr(str(a.body, "detail"), "max_seconds"));
    cJSON_Delete(a.body);
}

static void cancelled(void **state)
{
    static volatile int stop = 1;
    ljgap__limits l;
    ljgap__limits_default(&l);
    l.cancel = &stop;
    ljgap__handler_set_limits(&l);
    answer a = ask("traction", "{'psd':" PSD ",'g_ave':[1.2,2]}");
    ljgap__limits_default(&l);
    ljgap__handler_set_limits(&l);
    check_problem(&a, 503, "unavailable");
    cJSON_Delete(a.body);
}

static void outside_model(void **state)
{
    /* valid field by field, but the variance overflows: the core refuses the PSD */
    answer a = ask("adhesion", "{'psd':{'kind':'power','D':2.01,'k1':1,'k2':1e15,'C':1e308}}");
    const cJSON *errs = check_problem(&a, 422, "outside-model");
    assert_string_equal(str(cJSON_GetArrayItem(errs, 0), "pointer"), "/psd");
    cJSON_Delete(a.body);
}

static void out_of_memory(void **state)
{
    oom_sweep("adhesion",
              "{\"psd\":{\"kind\":\"power\",\"D\":2.5,\"k1\":1,\"k2\":2,\"m0\":1e-4},\"tol\":1e-3}",
              400);
}

/* ---- success paths ---- */

/* Every number anywhere in v is finite (cJSON prints NaN/Inf as null, so also: the answer
 * has no null except where allowed). */
static void all_finite(const cJSON *v)
{
    const cJSON *c;
    if (cJSON_IsNumber(v)) assert_true(isfinite(v->valuedouble));
    cJSON_ArrayForEach(c, v) all_finite(c);
}

static void check_meta(const answer *a, const char *method)
{
    const cJSON *m = get(a->body, "meta");
    assert_int_equal(a->status, 200);
    assert_string_equal(a->ctype, "application/json");
    assert_string_equal(str(m, "method"), method);
    assert_string_equal(str(m, "version"), LJGAP_VERSION);
    assert_true(num(m, "elapsed_ms") >= 0);
    assert_true(cJSON_IsArray(get(m, "warnings")));
    assert_true(cJSON_IsFalse(get(m, "cached")));
    all_finite(a->body);
}

static const char *const summary_fields[] = {"g_eq", "sigma_max", "g_at_max", "dgamma_eff"};

static void check_summary(const cJSON *s, const cJSON *err)
{
    for (int i = 0; i < 4; i++) {
        num(s, summary_fields[i]);
        assert_true(num(err, summary_fields[i]) >= 0);
    }
    assert_true(num(s, "m0") > 0);
    assert_true(fabs(num(s, "k0") - 0.46978) < 1e-5);
}

static void near(double got, double want, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol))
        fail_msg("%s: got %.17g, want %.17g within %.3g", what, got, want, tol);
}

static void adhesion_smooth_limit(void **state)
{
    /* m0 -> 0: the flat Lennard-Jones law, sigma_max = 1 at 3^(1/6), dgamma_eff = 1 */
    answer a = ask("adhesion", "{'psd':{'kind':'power','D':2.5,'k1':1,'k2':8,'m0':1e-8}}");
    check_meta(&a, "pde");
    check_summary(a.body, get(a.body, "error"));
    near(num(a.body, "sigma_max"), 1, 1e-3, "sigma_max");
    near(num(a.body, "g_at_max"), pow(3, 1.0 / 6), 1e-2, "g_at_max");
    near(num(a.body, "dgamma_eff"), 1, 1e-3, "dgamma_eff");
    near(num(a.body, "m0"), 1e-8, 1e-20, "m0");
    cJSON_Delete(a.body);
}

static void adhesion_fig4(void **state)
{
    /* theory.md §4: C = 1/(4π), k1 = 1, k2 = ∞, D = 2.5. This checks the wiring (C sets the
     * level, fields land under their names); the core's own tests hold it to 1e-5. */
    char req[200];
    snprintf(req, sizeof req, "{'psd':{'kind':'power','D':2.5,'k1':1,'C':%.17g}}", 1 / (4 * M_PI));
    answer a = ask("adhesion", req);
    const cJSON *err = get(a.body, "error");
    check_meta(&a, "pde");
    check_summary(a.body, err);
    near(num(a.body, "m0"), 0.5, 1e-12, "m0");
    near(num(a.body, "g_eq"), 2.6028, 1e-4 + num(err, "g_eq"), "g_eq");
    near(num(a.body, "sigma_max"), 0.10126, 1e-4 + num(err, "sigma_max"), "sigma_max");
    near(num(a.body, "dgamma_eff"), 0.20147, 1e-4 + num(err, "dgamma_eff"), "dgamma_eff");
    cJSON_Delete(a.body);
}

static void traction_matches_adhesion(void **state)
{
    answer t = ask("traction", "{'psd':" PSD ",'g_ave':{'min':1,'max':4,'n':7}}");
    answer a = ask("adhesion", "{'psd':" PSD "}");
    const cJSON *g, *sig, *err;
    check_meta(&t, "pde");
    g = get(t.body, "g_ave");
    sig = get(t.body, "sigma");
    err = get(t.body, "error");
    assert_int_equal(cJSON_GetArraySize(g), 7);
    assert_int_equal(cJSON_GetArraySize(sig), 7);
    assert_int_equal(cJSON_GetArraySize(get(err, "sigma")), 7);
    near(cJSON_GetArrayItem(g, 0)->valuedouble, 1, 0, "g_ave[0]");
    near(cJSON_GetArrayItem(g, 6)->valuedouble, 4, 1e-15, "g_ave[6]");
    near(cJSON_GetArrayItem(g, 2)->valuedouble, 2, 1e-15, "g_ave[2]");
    check_summary(get(t.body, "summary"), get(err, "summary"));
    for (int i = 0; i < 4; i++) {
        const char *f = summary_fields[i];
        near(num(get(t.body, "summary"), f), num(a.body, f),
             10 * (num(get(err, "summary"), f) + num(get(a.body, "error"), f)) + 1e-9, f);
    }
    /* compressive near the wall, tensile beyond g_eq */
    assert_true(cJSON_GetArrayItem(sig, 0)->valuedouble < 0);
    assert_true(cJSON_GetArrayItem(sig, 6)->valuedouble > 0);
    cJSON_Delete(t.body);
    cJSON_Delete(a.body);
}

static void pdf_invariants(void **state)
{
    answer a = ask("pdf", "{'psd':" PSD_INF ",'g_ave':1.5,'k2':[5,null],'tol':1e-4}");
    const cJSON *pdfs, *errs, *p;
    int i = 0;
    check_meta(&a, "pde");
    pdfs = get(a.body, "pdfs");
    errs = get(get(a.body, "error"), "pdfs");
    assert_int_equal(cJSON_GetArraySize(pdfs), 2);
    assert_int_equal(cJSON_GetArraySize(errs), 2);
    near(num(cJSON_GetArrayItem(pdfs, 0), "k2"), 5, 0, "k2[0]");
    assert_true(cJSON_IsNull(get(cJSON_GetArrayItem(pdfs, 1), "k2")));
    cJSON_ArrayForEach(p, pdfs)
    {
        const cJSON *e = cJSON_GetArrayItem(errs, i++);
        int n = cJSON_GetArraySize(get(p, "g"));
        assert_true(n >= 2);
        assert_int_equal(cJSON_GetArraySize(get(p, "phi")), n);
        near(num(p, "mass"), 1, 1e-3, "mass");
        near(num(p, "mean"), 1.5, 1e-3, "mean");
        num(p, "sigma");
        assert_true(num(e, "phi_l1") >= 0);
        assert_true(num(e, "sigma") >= 0);
    }
    cJSON_Delete(a.body);
}

static void sweep_replaces_level(void **state)
{
    answer a = ask("sweep", "{'psd':{'kind':'power','D':2.5,'k1':1,'k2':8,'C':0.01},"
                            "'vary':'m0','values':[0.1,0.5]}");
    answer b = ask("adhesion", "{'psd':" PSD "}");
    const cJSON *res;
    check_meta(&a, "pde");
    assert_string_equal(str(a.body, "vary"), "m0");
    assert_int_equal(cJSON_GetArraySize(get(a.body, "values")), 2);
    res = get(a.body, "results");
    assert_int_equal(cJSON_GetArraySize(res), 2);
    for (int i = 0; i < 2; i++)
        check_summary(cJSON_GetArrayItem(res, i), get(cJSON_GetArrayItem(res, i), "error"));
    near(num(cJSON_GetArrayItem(res, 0), "m0"), 0.1, 1e-12, "m0[0]");
    /* values[1] is the PSD of b */
    near(num(cJSON_GetArrayItem(res, 1), "g_eq"), num(b.body, "g_eq"), 1e-9, "g_eq");
    /* rougher is less sticky */
    assert_true(num(cJSON_GetArrayItem(res, 1), "dgamma_eff") <
                num(cJSON_GetArrayItem(res, 0), "dgamma_eff"));
    cJSON_Delete(a.body);
    cJSON_Delete(b.body);
}

static void sweep_k1_keeps_level(void **state)
{
    answer a = ask("sweep", "{'psd':" PSD ",'vary':'k1','values':[1,2]}");
    const cJSON *res = get(a.body, "results");
    check_meta(&a, "pde");
    /* the level field m0 is kept: every result has m0 = 0.5 */
    near(num(cJSON_GetArrayItem(res, 0), "m0"), 0.5, 1e-12, "m0[0]");
    near(num(cJSON_GetArrayItem(res, 1), "m0"), 0.5, 1e-12, "m0[1]");
    cJSON_Delete(a.body);
}

static void ignored_field_warns(void **state)
{
    answer a = ask("adhesion", "{'psd':{'kind':'power','D':2.5,'k1':1,'k2':2,'m0':1e-4},"
                               "'seed':7,'tol':1e-3}");
    const cJSON *w = get(get(a.body, "meta"), "warnings");
    check_meta(&a, "pde");
    assert_true(cJSON_GetArraySize(w) >= 1);
    assert_non_null(strstr(cJSON_GetArrayItem(w, 0)->valuestring, "seed"));
    cJSON_Delete(a.body);
}

/* fixed_vmax: the paper's Fig. 2 curve at Vmax = 1/10 as computed (peak 5.22 at 0.885, not the
 * refined 6.8), with an error of the size of its distance from the converged PDF, and a
 * warning; with the PDE the field is ignored with a warning. */
static void fixed_vmax_request(void **state)
{
    answer a = ask("pdf", "{'psd':{'kind':'power','D':2.5,'k1':1,'k2':5,'C':0.0795775},"
                          "'g_ave':0.98,'k2':[5],'method':'paper','vmax':0.1,'fixed_vmax':true,"
                          "'tol':0.1}");
    check_meta(&a, "paper");
    const cJSON *p = cJSON_GetArrayItem(get(a.body, "pdfs"), 0), *phi = get(p, "phi");
    double pk = 0.0;
    for (int i = 0; i < cJSON_GetArraySize(phi); i++)
        pk = fmax(pk, cJSON_GetArrayItem(phi, i)->valuedouble);
    near(pk, 5.2248, 1e-3, "peak at Vmax = 1/10");
    const cJSON *e = cJSON_GetArrayItem(get(get(a.body, "error"), "pdfs"), 0);
    assert_true(num(e, "phi_l1") > 0.2 && num(e, "phi_l1") < 1.0);
    assert_true(cJSON_GetArraySize(get(get(a.body, "meta"), "warnings")) >= 1);
    cJSON_Delete(a.body);
    answer b = ask("adhesion", "{'psd':{'kind':'power','D':2.5,'k1':1,'k2':2,'m0':1e-4},"
                               "'fixed_vmax':true,'tol':1e-3}");
    const cJSON *w = get(get(b.body, "meta"), "warnings");
    check_meta(&b, "pde");
    assert_non_null(strstr(cJSON_GetArrayItem(w, 0)->valuestring, "fixed_vmax"));
    cJSON_Delete(b.body);
}

/* ---- physical units and contact ---- */

/* The same PSD given dimensionless and in SI (k/χ, h_rms ε, C of (6) in SI, table in SI)
 * gives the same answer; the si object converts it back. */
static void si_matches_dimensionless(void **state)
{
    char req[600];
    const double eps = 3e-10, s0 = 16 * 0.05 / (9 * sqrt(3) * eps), D = 2.5;
    const double C = 0.5 * (2 * D - 6) / (2 * M_PI * (pow(8, 2 * D - 6) - 1)); /* m0 = 0.5 */
    answer a = ask("adhesion", "{'psd':" PSD ",'tol':1e-5}");
    answer b = ask("adhesion", "{'psd':" PSD_SI ",'units':'SI'," MAT ",'tol':1e-5}");
    const cJSON *si = get(b.body, "si");
    answer c, t;
    check_meta(&b, "pde");
    for (int i = 0; i < 4; i++)
        near(num(b.body, summary_fields[i]), num(a.body, summary_fields[i]),
             1e-9 * fabs(num(a.body, summary_fields[i])), summary_fields[i]);
    near(num(si, "chi_m"), CHI, 1e-15 * CHI, "chi_m");
    near(num(si, "sigma0_Pa"), s0, 1e-15 * s0, "sigma0_Pa");
    near(num(si, "g_eq_m"), num(b.body, "g_eq") * eps, 1e-15 * eps, "g_eq_m");
    near(num(si, "sigma_max_Pa"), num(b.body, "sigma_max") * s0, 1e-15 * s0, "sigma_max_Pa");
    near(num(si, "dgamma_eff_J_m2"), num(b.body, "dgamma_eff") * 0.05, 1e-16, "dgamma_eff");
    near(num(si, "m0_m2"), 0.5 * eps * eps, 1e-12 * eps * eps, "m0_m2");
    /* C in SI: C_SI = C̃ ε²/χ^(6-2D) */
    snprintf(req, sizeof req,
             "{'psd':{'kind':'power','D':2.5,'k1':%.17g,'k2':%.17g,'C':%.17g},'units':'SI'," MAT
             ",'tol':1e-5}",
             1 / CHI, 8 / CHI, C * eps * eps / pow(CHI, 6 - 2 * D));
    c = ask("adhesion", req);
    check_meta(&c, "pde");
    near(num(c.body, "m0"), 0.5, 1e-12, "m0 from C_SI");
    near(num(c.body, "g_eq"), num(a.body, "g_eq"), 1e-9, "g_eq from C_SI");
    /* a table in SI: k/χ, P ε²χ² */
    snprintf(req, sizeof req,
             "{'psd':{'kind':'table','k':[%.17g,%.17g],'P':[%.17g,%.17g]},'units':'SI'," MAT
             ",'tol':1e-4}",
             1 / CHI, 8 / CHI, C * eps * eps * CHI * CHI,
             C * pow(8, 2 * D - 8) * eps * eps * CHI * CHI);
    t = ask("adhesion", req);
    check_meta(&t, "pde");
    near(num(t.body, "m0"), 0.5, 1e-9, "m0 of the SI table");
    cJSON_Delete(a.body);
    cJSON_Delete(b.body);
    cJSON_Delete(c.body);
    cJSON_Delete(t.body);
}

/* Traction and pdf answers carry their arrays in SI too; a dimensionless psd with a
 * material is fine. */
static void si_arrays(void **state)
{
    answer t = ask("traction", "{'psd':" PSD "," MAT ",'g_ave':[1.5,3],'tol':1e-4}");
    answer p = ask("pdf", "{'psd':" PSD_INF "," MAT ",'g_ave':1.5,'k2':[5],'tol':1e-3}");
    const cJSON *si = get(t.body, "si"), *pp;
    const double s0 = 16 * 0.05 / (9 * sqrt(3) * 3e-10);
    check_meta(&t, "pde");
    check_meta(&p, "pde");
    near(cJSON_GetArrayItem(get(si, "g_ave_m"), 1)->valuedouble, 9e-10, 1e-24, "g_ave_m");
    near(cJSON_GetArrayItem(get(si, "sigma_Pa"), 1)->valuedouble,
         cJSON_GetArrayItem(get(t.body, "sigma"), 1)->valuedouble * s0, 1e-6, "sigma_Pa");
    near(num(get(si, "summary"), "g_eq_m"), num(get(t.body, "summary"), "g_eq") * 3e-10, 1e-24,
         "summary.g_eq_m");
    pp = cJSON_GetArrayItem(get(get(p.body, "si"), "pdfs"), 0);
    near(num(pp, "k2_per_m"), 5 / CHI, 1e-6 * 5 / CHI, "k2_per_m");
    assert_int_equal(cJSON_GetArraySize(get(pp, "g_m")),
                     cJSON_GetArraySize(get(cJSON_GetArrayItem(get(p.body, "pdfs"), 0), "g")));
    cJSON_Delete(t.body);
    cJSON_Delete(p.body);
}

/* The SI errors of every kind of answer are the dimensionless errors times their scale: gaps
 * x ε, tractions x σ0, energies x Δγ; a PDF's L1 error has no unit. The scales are taken from
 * the answer's own si (ε = 3√3 χσ0/E*, Δγ = 9√3 εσ0/16, from χ = 3ε²E* /(16Δγ) and
 * σ0 = 16Δγ/(9√3ε)) and checked against the material asked for, so a conversion against the
 * wrong scale, or an error left out, fails. */
typedef struct {
    double eps, s0, dg; /* ε (m), σ0 (Pa), Δγ (J/m²) */
} si_scales;

static si_scales scales_of(const cJSON *si)
{
    si_scales k;
    k.s0 = num(si, "sigma0_Pa");
    k.eps = 3 * sqrt(3) * num(si, "chi_m") * k.s0 / num(si, "E_star_Pa");
    k.dg = 9 * sqrt(3) * k.eps * k.s0 / 16;
    near(k.eps, 3e-10, 1e-14 * 3e-10, "epsilon from the si scales");
    near(k.dg, 0.05, 1e-14 * 0.05, "dgamma from the si scales");
    return k;
}

/* One SI error against the dimensionless one times scale (relative 1e-14: a few roundings). */
static void si_err_is(const cJSON *si_err, const char *si_name, const cJSON *err, const char *name,
                      double scale)
{
    double want = num(err, name) * scale;
    char what[80];
    snprintf(what, sizeof what, "si error %s = error %s x scale", si_name, name);
    near(num(si_err, si_name), want, 1e-14 * fabs(want), what);
}

/* The four adhesion errors of an SI error object. */
static void si_summary_errs(const cJSON *si_err, const cJSON *err, si_scales k)
{
    static const char *const si_names[] = {"g_eq_m", "sigma_max_Pa", "g_at_max_m",
                                           "dgamma_eff_J_m2"};
    const double f[] = {k.eps, k.s0, k.eps, k.dg};
    assert_int_equal(cJSON_GetArraySize(si_err), 4);
    for (int i = 0; i < 4; i++)
        si_err_is(si_err, si_names[i], err, summary_fields[i], f[i]);
}

static void si_errors(void **state)
{
    answer a = ask("adhesion", "{'psd':" PSD "," MAT ",'tol':1e-4}");
    answer c = ask("contact", "{'psd':" PSD_INF "," MAT ",'R':1e-6,'tol':1e-4}");
    answer t = ask("traction", "{'psd':" PSD "," MAT ",'g_ave':[1.5,2,3],'tol':1e-4}");
    answer p = ask("pdf", "{'psd':" PSD_INF "," MAT ",'g_ave':1.5,'k2':[5,null],'tol':1e-3}");
    answer w = ask("sweep", "{'psd':" PSD "," MAT ",'tol':1e-3,'vary':'D','values':[2.3,2.6]}");
    const cJSON *si, *se;
    si_scales k;
    check_meta(&a, "pde");
    check_meta(&c, "pde");
    check_meta(&t, "pde");
    check_meta(&p, "pde");
    check_meta(&w, "pde");
    for (int n = 0; n < 2; n++) { /* adhesion and contact: si.error beside si's values */
        const cJSON *b = n ? c.body : a.body;
        si = get(b, "si");
        si_summary_errs(get(si, "error"), get(b, "error"), scales_of(si));
    }
    si = get(t.body, "si"); /* traction: si.error = {sigma_Pa: [...], summary: {...}} */
    k = scales_of(si);
    se = get(si, "error");
    assert_int_equal(cJSON_GetArraySize(get(se, "sigma_Pa")), 3);
    for (int i = 0; i < 3; i++) {
        double want = cJSON_GetArrayItem(get(get(t.body, "error"), "sigma"), i)->valuedouble * k.s0;
        near(cJSON_GetArrayItem(get(se, "sigma_Pa"), i)->valuedouble, want, 1e-14 * want,
             "traction si.error.sigma_Pa[i]");
    }
    si_summary_errs(get(se, "summary"), get(get(t.body, "error"), "summary"), k);
    si = get(p.body, "si"); /* pdf: si.error.pdfs[i] = {phi_l1, sigma_Pa} */
    k = scales_of(si);
    se = get(get(si, "error"), "pdfs");
    assert_int_equal(cJSON_GetArraySize(se), 2);
    for (int i = 0; i < 2; i++) {
        const cJSON *e = cJSON_GetArrayItem(get(get(p.body, "error"), "pdfs"), i);
        const cJSON *s = cJSON_GetArrayItem(se, i);
        assert_int_equal(cJSON_GetArraySize(s), 2);
        si_err_is(s, "sigma_Pa", e, "sigma", k.s0);
        si_err_is(s, "phi_l1", e, "phi_l1", 1);
    }
    si = get(w.body, "si"); /* sweep: each si.results[i] has its own error, as results[i] */
    k = scales_of(si);
    assert_int_equal(cJSON_GetArraySize(get(si, "results")), 2);
    for (int i = 0; i < 2; i++)
        si_summary_errs(get(cJSON_GetArrayItem(get(si, "results"), i), "error"),
                        get(cJSON_GetArrayItem(get(w.body, "results"), i), "error"), k);
    cJSON_Delete(a.body);
    cJSON_Delete(c.body);
    cJSON_Delete(t.body);
    cJSON_Delete(p.body);
    cJSON_Delete(w.body);
}

static void contact_answer(void **state)
{
    answer a = ask("contact", "{'psd':" PSD_INF ",'material':{'E1':2e9,'nu1':0.5,'E2':2e9,"
                              "'nu2':0.5," DG_EPS "},'R':1e-6,'tol':1e-4}");
    const cJSON *po, *err, *epo;
    const double R = 1e-6, dg = 0.05;
    double d, lam;
    check_meta(&a, "pde");
    check_summary(a.body, get(a.body, "error"));
    near(num(get(a.body, "si"), "E_star_Pa"), 2e9 / 1.5, 1e-3, "E* of two bodies");
    po = get(a.body, "pull_off_N");
    err = get(a.body, "error");
    epo = get(err, "pull_off_N");
    d = num(a.body, "dgamma_eff");
    near(num(po, "jkr_smooth"), 1.5 * M_PI * R * dg, 1e-20, "jkr_smooth");
    near(num(po, "jkr"), 1.5 * M_PI * R * dg * d, 1e-20, "jkr");
    near(num(po, "dmt"), 2 * M_PI * R * dg * d, 1e-20, "dmt");
    near(num(epo, "jkr"), 1.5 * M_PI * R * dg * num(err, "dgamma_eff"), 1e-22, "error.jkr");
    assert_true(num(po, "maugis_dugdale") >= num(po, "jkr") &&
                num(po, "maugis_dugdale") <= num(po, "dmt"));
    assert_true(num(epo, "maugis_dugdale") >= 0);
    assert_true(num(get(a.body, "tabor"), "smooth") > 0);
    assert_true(num(get(a.body, "tabor"), "effective") > 0);
    lam = num(a.body, "maugis_lambda");
    assert_string_equal(str(a.body, "regime"), lam > 5 ? "jkr" : lam < 0.1 ? "dmt" : "transition");
    assert_true(num(err, "maugis_lambda") >= 0);
    cJSON_Delete(a.body);
}

/* Fig. 5: at equal m0 the rougher spectrum (larger D) keeps less adhesion, and both tend
 * to the flat values as m0 -> 0. */
static void fig5_trends(void **state)
{
    answer a = ask("sweep", "{'psd':{'kind':'power','D':2.05,'k1':0.5,'m0':1},'tol':1e-4,"
                            "'vary':'m0','values':[1e-4,0.1,1,10]}");
    answer b = ask("sweep", "{'psd':{'kind':'power','D':2.5,'k1':0.5,'m0':1},'tol':1e-4,"
                            "'vary':'m0','values':[1e-4,0.1,1,10]}");
    const cJSON *ra = get(a.body, "results"), *rb = get(b.body, "results");
    check_meta(&a, "pde");
    check_meta(&b, "pde");
    for (int i = 0; i < 4; i++) {
        const cJSON *x = cJSON_GetArrayItem(ra, i), *y = cJSON_GetArrayItem(rb, i);
        if (i == 0) {
            near(num(x, "dgamma_eff"), 1, 1e-3, "D=2.05 dgamma_eff at m0=1e-4");
            near(num(y, "dgamma_eff"), 1, 1e-3, "D=2.5 dgamma_eff at m0=1e-4");
            near(num(x, "sigma_max"), 1, 1e-3, "D=2.05 sigma_max at m0=1e-4");
            near(num(y, "sigma_max"), 1, 1e-3, "D=2.5 sigma_max at m0=1e-4");
            continue;
        }
        if (!(num(y, "dgamma_eff") < num(x, "dgamma_eff") &&
              num(y, "sigma_max") < num(x, "sigma_max")))
            fail_msg("m0 index %d: D=2.5 gives %.17g, %.17g; D=2.05 gives %.17g, %.17g", i,
                     num(y, "dgamma_eff"), num(y, "sigma_max"), num(x, "dgamma_eff"),
                     num(x, "sigma_max"));
    }
    cJSON_Delete(a.body);
    cJSON_Delete(b.body);
}

/* A sweep on several threads answers exactly what the sequential one does, in SI too. */
static void sweep_threads_agree(void **state)
{
    const char *req = "{'psd':" PSD_SI ",'units':'SI'," MAT ",'tol':1e-3,'vary':'D',"
                      "'values':[2.2,2.4,2.6,2.8]}";
    char *out[2];
    for (int k = 0; k < 2; k++) {
        ljgap__limits l;
        answer a;
        ljgap__limits_default(&l);
        l.sweep_threads = k ? 4 : 1;
        ljgap__handler_set_limits(&l);
        a = ask("sweep", req);
        check_meta(&a, "pde");
        assert_int_equal(cJSON_GetArraySize(get(get(a.body, "si"), "results")), 4);
        cJSON_DeleteItemFromObjectCaseSensitive(a.body, "meta");
        out[k] = cJSON_PrintUnformatted(a.body);
        cJSON_Delete(a.body);
    }
    ljgap__limits l;
    ljgap__limits_default(&l);
    ljgap__handler_set_limits(&l);
    assert_string_equal(out[0], out[1]);
    free(out[0]);
    free(out[1]);
}

/* ---- thread safety ---- */

#define N_THREADS 4
static const char *const mixed[] = {
    "{\"psd\":{\"kind\":\"power\",\"D\":2.5,\"k1\":1,\"k2\":2,\"m0\":1e-3},\"tol\":1e-3}",
    "{\"psd\":{\"kind\":\"power\",\"D\":3.5,\"k1\":0.2,\"m0\":-1},\"tol\":9}",
    "{\"psd\":",
};

/* Each thread answers every request of mixed[] and keeps the bodies without meta. */
static void *worker(void *arg)
{
    char **out = arg;
    for (size_t i = 0; i < sizeof mixed / sizeof mixed[0]; i++) {
        ljgap__reply r;
        cJSON *body;
        ljgap__handle("adhesion", mixed[i], strlen(mixed[i]), &r);
        body = cJSON_Parse(r.body);
        cJSON_DeleteItemFromObjectCaseSensitive(body, "meta");
        out[i] = cJSON_PrintUnformatted(body);
        cJSON_Delete(body);
        ljgap__reply_free(&r);
    }
    return NULL;
}

static void concurrent_answers_agree(void **state)
{
    enum { NM = sizeof mixed / sizeof mixed[0] };
    pthread_t t[N_THREADS];
    char *out[N_THREADS][NM];
    for (int i = 0; i < N_THREADS; i++)
        assert_int_equal(pthread_create(&t[i], NULL, worker, out[i]), 0);
    for (int i = 0; i < N_THREADS; i++)
        assert_int_equal(pthread_join(t[i], NULL), 0);
    for (int i = 0; i < N_THREADS; i++)
        for (int m = 0; m < NM; m++) {
            assert_non_null(out[i][m]);
            assert_string_equal(out[i][m], out[0][m]);
        }
    for (int i = 0; i < N_THREADS; i++)
        for (int m = 0; m < NM; m++)
            free(out[i][m]);
}

int main(void)
{
    static const struct CMUnitTest others[] = {
        cmocka_unit_test(k1_message_explains_k0),
        cmocka_unit_test(table_too_long),
        cmocka_unit_test(sweep_too_many_values),
        cmocka_unit_test(all_errors_collected),
        cmocka_unit_test(errors_capped),
        cmocka_unit_test(malformed_json),
        cmocka_unit_test(body_not_nul_terminated),
        cmocka_unit_test(unknown_endpoint),
        cmocka_unit_test(time_cap),
        cmocka_unit_test(cancelled),
        cmocka_unit_test(outside_model),
        cmocka_unit_test(out_of_memory),
        cmocka_unit_test(adhesion_smooth_limit),
        cmocka_unit_test(adhesion_fig4),
        cmocka_unit_test(traction_matches_adhesion),
        cmocka_unit_test(pdf_invariants),
        cmocka_unit_test(sweep_replaces_level),
        cmocka_unit_test(sweep_k1_keeps_level),
        cmocka_unit_test(ignored_field_warns),
        cmocka_unit_test(fixed_vmax_request),
        cmocka_unit_test(concurrent_answers_agree),
        cmocka_unit_test(si_matches_dimensionless),
        cmocka_unit_test(si_arrays),
        cmocka_unit_test(si_errors),
        cmocka_unit_test(contact_answer),
        cmocka_unit_test(fig5_trends),
        cmocka_unit_test(sweep_threads_agree),
    };
    enum { NR = sizeof rules / sizeof rules[0], NO = sizeof others / sizeof others[0] };
    struct CMUnitTest tests[NR + NO];
    for (size_t i = 0; i < NR; i++)
        tests[i] = (struct CMUnitTest){
            .name = rules[i].name, .test_func = rule_test, .initial_state = (void *)&rules[i]};
    memcpy(tests + NR, others, sizeof others);
    gsl_set_error_handler_off();
    return _cmocka_run_group_tests("handler", tests, NR + NO, NULL, NULL);
}
