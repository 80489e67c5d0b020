/* test_problems.c -- the problem types (server/api/problems.c) against openapi.json, and their pages.
 *
 * Linked with the daemon's embedded copy of server/openapi.json: the set of types it lists
 * must be exactly the table's (/problems/SLUG), each page must render with its title and text,
 * the index must link every type, an unknown type is a 404 problem. The handler's own
 * problems must carry types from the table, with its status and title.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "handler.h"
#include "problems.h"

#include <cjson/cJSON.h>
#include <gsl/gsl_errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const char ljgapd_openapi[];

static void test_openapi_lists_the_table(void **state)
{
    cJSON *doc = cJSON_Parse(ljgapd_openapi), *e;
    const cJSON *types;
    (void)state;
    assert_non_null(doc);
    types = cJSON_GetObjectItemCaseSensitive(
        cJSON_GetObjectItemCaseSensitive(
            cJSON_GetObjectItemCaseSensitive(
                cJSON_GetObjectItemCaseSensitive(
                    cJSON_GetObjectItemCaseSensitive(
                        cJSON_GetObjectItemCaseSensitive(doc, "components"), "schemas"),
                    "Problem"),
                "properties"),
            "type"),
        "enum");
    assert_true(cJSON_IsArray(types));
    cJSON_ArrayForEach(e, types)
    {
        const char *t = cJSON_GetStringValue(e);
        assert_non_null(t);
        if (strncmp(t, LJGAP_PROBLEM_BASE, strlen(LJGAP_PROBLEM_BASE)) != 0 ||
            !ljgap__problem_find(t + strlen(LJGAP_PROBLEM_BASE)))
            fail_msg("openapi.json lists %s, which the table of problems.c has not", t);
    }
    for (size_t i = 0; ljgap__problem_at(i); i++) {
        char t[80];
        int found = 0;
        snprintf(t, sizeof t, LJGAP_PROBLEM_BASE "%s", ljgap__problem_at(i)->slug);
        cJSON_ArrayForEach(e, types) found |= strcmp(cJSON_GetStringValue(e), t) == 0;
        if (!found) fail_msg("openapi.json does not list %s", t);
    }
    cJSON_Delete(doc);
}

static void test_pages(void **state)
{
    ljgap__reply r;
    (void)state;
    for (size_t i = 0; ljgap__problem_at(i); i++) {
        const ljgap__problem_doc *d = ljgap__problem_at(i);
        assert_true(d->status >= 400 && d->status <= 599);
        ljgap__problem_page(d->slug, &r);
        assert_int_equal(r.status, 200);
        assert_string_equal(r.content_type, "text/html; charset=utf-8");
        assert_int_equal(r.len, strlen(r.body));
        assert_non_null(strstr(r.body, d->title));
        assert_non_null(strstr(r.body, d->meaning));
        assert_non_null(strstr(r.body, d->fix));
        assert_non_null(strstr(r.body, "<!DOCTYPE html>"));
        assert_null(strstr(r.body, "<script")); /* nothing inline: the CSP is default-src 'self' */
        assert_null(strstr(r.body, "style="));
        ljgap__reply_free(&r);
    }
    ljgap__problem_page("", &r);
    assert_int_equal(r.status, 200);
    for (size_t i = 0; ljgap__problem_at(i); i++) {
        char link[100];
        snprintf(link, sizeof link, "href=\"/problems/%s\"", ljgap__problem_at(i)->slug);
        assert_non_null(strstr(r.body, link));
    }
    ljgap__reply_free(&r);
    ljgap__problem_page("no-such-type", &r);
    assert_int_equal(r.status, 404);
    assert_string_equal(r.content_type, "application/problem+json");
    assert_non_null(strstr(r.body, "\"type\":\"/problems/not-found\""));
    ljgap__reply_free(&r);
}

/* The handler's problems: type from the table, with the table's status and title. */
static void test_handler_types(void **state)
{
    static const struct {
        const char *endpoint, *accept, *body;
    } cases[] = {
        {"adhesion", NULL, "{"},         /* 400 */
        {"nope", NULL, "{}"},            /* 404 */
        {"adhesion", "image/png", "{}"}, /* 406 */
        {"adhesion", NULL,
         "{\"psd\":{\"kind\":\"power\",\"D\":2.5,\"k1\":0.3,\"m0\":1}}"}, /* 422 */
    };
    (void)state;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ljgap__reply r;
        cJSON *doc;
        const char *type;
        const ljgap__problem_doc *d;
        ljgap__call call = {.accept = cases[i].accept};
        ljgap__handle_call(cases[i].endpoint, cases[i].body, strlen(cases[i].body), &call, &r);
        doc = cJSON_Parse(r.body);
        type = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(doc, "type"));
        assert_non_null(type);
        assert_true(strncmp(type, LJGAP_PROBLEM_BASE, strlen(LJGAP_PROBLEM_BASE)) == 0);
        d = ljgap__problem_find(type + strlen(LJGAP_PROBLEM_BASE));
        assert_non_null(d);
        assert_int_equal(r.status, d->status);
        assert_string_equal(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(doc, "title")),
                            d->title);
        cJSON_Delete(doc);
        ljgap__reply_free(&r);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_openapi_lists_the_table),
        cmocka_unit_test(test_pages),
        cmocka_unit_test(test_handler_types),
    };
    gsl_set_error_handler_off();
    return cmocka_run_group_tests(tests, NULL, NULL);
}
