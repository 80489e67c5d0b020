/* test_model.c -- the answers' "model" (server/api/validity.c): where the theory holds, from
 * the validity map, and GET /v1/validity's answer.
 *
 * - Inside the map and within 5 %: the model carries the map's values (the same as
 *   ljgap_validity_at, an independent call into the core) and the answer has no warning.
 * - Inside and beyond 5 %: a warning naming the hybrid (k_split). Fig. 4's adhesion (m0 = 0.5,
 *   k2 = ∞) warns.
 * - Outside (D = 2.05): inside false with the reason, and a warning only where the nearest
 *   point is beyond 5 %.
 * - SI: si.model is the model; a request in SI units gets the same model as the
 *   dimensionless one.
 * - traction, pdf and contact carry the model; a sweep carries one per value and one warning
 *   naming the values over 5 %; a table PSD states its method.
 * - GET /v1/validity: every row of the table, with the axes and "how", and meta.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "handler.h"
#include "ljgap_validity.h"
#include "validity/validity.h"

#include <cjson/cJSON.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAT "'material':{'E_star':1e9,'dgamma':0.05,'epsilon':3e-10}"
/* the dimensionless PSD D 2.5, k1 1, k2 8, m0 M in SI with MAT (χ = 3.375e-10 m, ε = 3e-10 m) */
#define PSD_SI(hrms)                                                                               \
    "{'kind':'power','D':2.5,'k1':2962962962.962963,'k2':23703703703.703704,'h_rms':" hrms "}"

static cJSON *ask(const char *endpoint, const char *request)
{
    char *s = strdup(request);
    ljgap__reply r;
    assert_non_null(s);
    for (char *c = s; *c; c++)
        if (*c == '\'') *c = '"';
    ljgap__handle(endpoint, s, strlen(s), &r);
    if (r.status != 200) fail_msg("%s: status %d: %s", endpoint, r.status, r.body);
    cJSON *a = cJSON_Parse(r.body);
    assert_non_null(a);
    ljgap__reply_free(&r);
    free(s);
    return a;
}

static const cJSON *get(const cJSON *o, const char *name)
{
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(o, name);
    if (!it) fail_msg("field %s is missing", name);
    return it;
}

static const cJSON *warnings(const cJSON *a)
{
    return get(get(a, "meta"), "warnings");
}

/* the warning containing what, or NULL */
static const char *warning_with(const cJSON *a, const char *what)
{
    const cJSON *w;
    cJSON_ArrayForEach(w, warnings(a)) if (strstr(w->valuestring, what)) return w->valuestring;
    return NULL;
}

/* model's vs_discrete against the core's lookup at (D, m0, k1 1, k2) */
static void model_is(const cJSON *model, double D, double m0, double k2, int inside)
{
    ljgap_validity v;
    assert_int_equal(ljgap_validity_at(D, m0, 1, k2, &v), LJGAP_OK);
    assert_int_equal(v.inside, inside);
    assert_string_equal(get(model, "source")->valuestring, "validity map");
    assert_int_equal(cJSON_IsTrue(get(model, "inside")), inside);
    for (int q = 0; q < LJGAP_V_N; q++) {
        const char *name = ljgap_validity_quantities[q];
        double r = get(get(model, "vs_discrete"), name)->valuedouble;
        double e = get(get(model, "vs_discrete_err"), name)->valuedouble;
        if (!(fabs(r - v.rel[q]) <= 5e-7 && fabs(e - v.err[q]) <= 5e-7)) /* 6 decimals */
            fail_msg("%s: %g ± %g, the map %g ± %g", name, r, e, v.rel[q], v.err[q]);
    }
    if (!inside) assert_true(strlen(get(model, "reason")->valuestring) > 0);
}

static void inside_no_warning(void **state)
{
    (void)state;
    cJSON *a = ask("adhesion", "{'psd':{'kind':'power','D':2.5,'k1':1,'k2':8,'m0':0.02}}");
    model_is(get(a, "model"), 2.5, 0.02, 8, 1);
    assert_int_equal(cJSON_GetArraySize(warnings(a)), 0);
    cJSON_Delete(a);
}

static void inside_warns(void **state)
{
    (void)state;
    cJSON *a = ask("adhesion", "{'psd':{'kind':'power','D':2.5,'k1':1,'k2':8,'m0':0.2}}");
    const char *w;
    model_is(get(a, "model"), 2.5, 0.2, 8, 1);
    w = warning_with(a, "k_split");
    assert_non_null(w);
    assert_non_null(strstr(w, "the theory differs from the discrete model by"));
    assert_true(strlen(w) < LJGAP_WARN_LEN);
    cJSON_Delete(a);
}

static void fig4_warns(void **state)
{
    (void)state;
    char req[200];
    snprintf(req, sizeof req, "{'psd':{'kind':'power','D':2.5,'k1':1,'C':%.17g}}", 1 / (4 * M_PI));
    cJSON *a = ask("adhesion", req);
    const cJSON *m = get(a, "model");
    assert_true(cJSON_IsNull(get(m, "k2_over_k1")));
    model_is(m, 2.5, get(m, "m0")->valuedouble, INFINITY, cJSON_IsTrue(get(m, "inside")));
    assert_non_null(warning_with(a, "k_split"));
    cJSON_Delete(a);
}

static void outside(void **state)
{
    (void)state;
    cJSON *a = ask("adhesion", "{'psd':{'kind':'power','D':2.05,'k1':1,'k2':8,'m0':0.5}}");
    const cJSON *m = get(a, "model");
    model_is(m, 2.05, 0.5, 8, 0);
    assert_non_null(strstr(get(m, "reason")->valuestring, "D = 2.05"));
    assert_true(get(get(m, "at"), "D")->valuedouble == 2.2);
    assert_non_null(warning_with(a, "outside the validity map"));
    cJSON_Delete(a);
    /* outside, but the nearest point is within 5 %: said in the model, no warning */
    a = ask("adhesion", "{'psd':{'kind':'power','D':2.05,'k1':1,'k2':8,'m0':0.01}}");
    model_is(get(a, "model"), 2.05, 0.01, 8, 0);
    assert_int_equal(cJSON_GetArraySize(warnings(a)), 0);
    cJSON_Delete(a);
}

static void si_carries_model(void **state)
{
    (void)state;
    /* h_rms = √0.2 ε: m0 = 0.2, beyond 5 %; and √0.02 ε, within */
    cJSON *a = ask("adhesion", "{'psd':" PSD_SI("1.3416407864998738e-10") ",'units':'SI'," MAT "}");
    const cJSON *m = get(a, "model");
    assert_true(cJSON_Compare(m, get(get(a, "si"), "model"), 1));
    model_is(m, 2.5, 0.2, 8, 1);
    assert_non_null(warning_with(a, "k_split"));
    cJSON_Delete(a);
    a = ask("adhesion", "{'psd':" PSD_SI("4.242640687119285e-11") ",'units':'SI'," MAT "}");
    model_is(get(get(a, "si"), "model"), 2.5, 0.02, 8, 1);
    assert_int_equal(cJSON_GetArraySize(warnings(a)), 0);
    cJSON_Delete(a);
}

static void every_answer(void **state)
{
    (void)state;
    const char *psd = "{'kind':'power','D':2.2,'k1':1,'k2':8,'m0':0.1}";
    char req[400];
    snprintf(req, sizeof req, "{'psd':%s,'g_ave':[2,3]," MAT "}", psd);
    cJSON *a = ask("traction", req);
    model_is(get(a, "model"), 2.2, 0.1, 8, 1);
    assert_true(cJSON_Compare(get(a, "model"), get(get(a, "si"), "model"), 1));
    cJSON_Delete(a);
    snprintf(req, sizeof req, "{'psd':%s,'g_ave':2,'k2':[8]}", psd);
    a = ask("pdf", req);
    model_is(get(a, "model"), 2.2, 0.1, 8, 1);
    cJSON_Delete(a);
    snprintf(req, sizeof req, "{'psd':%s,'R':1e-6," MAT "}", psd);
    a = ask("contact", req);
    model_is(get(a, "model"), 2.2, 0.1, 8, 1);
    cJSON_Delete(a);
}

static void sweep_per_value(void **state)
{
    (void)state;
    cJSON *a = ask("sweep", "{'psd':{'kind':'power','D':2.5,'k1':1,'k2':8,'m0':0.1},"
                            "'vary':'m0','values':[0.01,0.2,0.5]," MAT "}");
    const cJSON *res = get(a, "results"), *sir = get(get(a, "si"), "results");
    const double m0[] = {0.01, 0.2, 0.5};
    const char *w;
    for (int i = 0; i < 3; i++) {
        model_is(get(cJSON_GetArrayItem(res, i), "model"), 2.5, m0[i], 8, 1);
        assert_true(cJSON_Compare(get(cJSON_GetArrayItem(res, i), "model"),
                                  get(cJSON_GetArrayItem(sir, i), "model"), 1));
    }
    w = warning_with(a, "k_split");
    assert_non_null(w);
    assert_non_null(strstr(w, "values[1, 2]"));
    cJSON_Delete(a);
}

static void table_method(void **state)
{
    (void)state;
    cJSON *a = ask("adhesion", "{'psd':{'kind':'table','k':[1,2,4,8],"
                               "'P':[0.01,0.00125,0.00015625,0.0000195312]}}");
    const cJSON *m = get(a, "model");
    assert_non_null(strstr(get(m, "method")->valuestring, "variance-weighted"));
    /* P ∝ k^-3: 2D - 8 = -3, D = 2.5 */
    assert_true(fabs(get(m, "D")->valuedouble - 2.5) < 1e-6);
    cJSON_Delete(a);
}

static void get_validity(void **state)
{
    (void)state;
    ljgap__reply r;
    ljgap__validity_reply(&r);
    assert_int_equal(r.status, 200);
    cJSON *a = cJSON_Parse(r.body);
    assert_non_null(a);
    const cJSON *map = get(a, "map"), *rows = get(map, "rows");
    assert_int_equal(cJSON_GetArraySize(rows), (int)ljgap_validity_nrows);
    for (size_t i = 0; i < ljgap_validity_nrows; i++) {
        const cJSON *o = cJSON_GetArrayItem(rows, (int)i);
        const ljgap_validity_row *w = &ljgap_validity_rows[i];
        assert_true(get(o, "D")->valuedouble == w->D && get(o, "m0")->valuedouble == w->m0);
        for (int q = 0; q < LJGAP_V_N; q++)
            assert_true(get(get(o, "vs_discrete"), ljgap_validity_quantities[q])->valuedouble ==
                        w->rel[q]);
    }
    assert_int_equal(cJSON_GetArraySize(get(map, "D")), 3);
    assert_true(cJSON_GetArraySize(get(map, "m0")) >= 9);
    assert_true(strlen(get(get(a, "how"), "command")->valuestring) > 0);
    assert_string_equal(get(get(a, "meta"), "method")->valuestring, "validity map");
    cJSON_Delete(a);
    ljgap__reply_free(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(inside_no_warning), cmocka_unit_test(inside_warns),
        cmocka_unit_test(fig4_warns),        cmocka_unit_test(outside),
        cmocka_unit_test(si_carries_model),  cmocka_unit_test(every_answer),
        cmocka_unit_test(sweep_per_value),   cmocka_unit_test(table_method),
        cmocka_unit_test(get_validity),
    };
    gsl_set_error_handler_off();
    return cmocka_run_group_tests(tests, NULL, NULL);
}
