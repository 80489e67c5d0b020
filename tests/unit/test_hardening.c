/* test_hardening.c -- regression tests for what the fuzzer and the bad-input probes found.
 *
 *   - Maugis-Dugdale pull-off (core/contact.c) on a dense λ grid from 1e-14 to 1e3: it used to
 *     fail (EFAIL) for about 1 λ in 20 below 1e-4, where the load is flat to round-off around
 *     its minimum and Brent's bracket is not strict. Checked against the model's limits,
 *     independent of the solver: DMT P̄ = 2 as λ -> 0, JKR P̄ = 1.5 as λ -> ∞ (Maugis 1992),
 *     1.5 <= P̄ <= 2 and P̄ non-increasing in λ, within the returned error estimates.
 *   - the contact answer at every corner of the accepted material box (E*, Δγ, ε) and sphere
 *     radius R, for a mild and a rough PSD: 200 with every number finite (no "not a finite
 *     number" warning), where R = 1e-311 or ε = 1e-76 used to give NaN Tabor parameters or a
 *     NaN error; and one step outside each bound is 422 at that field's pointer.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "handler.h"
#include "ljgap_units.h"

#include <cjson/cJSON.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

static void md_dense_grid(void **state)
{
    double prev = 2, prev_err = 0;
    const int n = 4000;
    for (int i = 0; i <= n; i++) {
        double lam = pow(10, -14 + 17.0 * i / n);
        ljgap_est p;
        int st = ljgap_md_pulloff(lam, &p);
        if (st != LJGAP_OK) fail_msg("lambda = %.17g: status %d", lam, st);
        if (!(p.err >= 0 && p.err < 1e-6))
            fail_msg("lambda = %.17g: error estimate %.3g", lam, p.err);
        if (!(p.value >= 1.5 - p.err - 1e-12 && p.value <= 2 + p.err + 1e-12)) /* round-off */
            fail_msg("lambda = %.17g: P = %.17g outside [1.5, 2]", lam, p.value);
        if (!(p.value <= prev + p.err + prev_err + 1e-12))
            fail_msg("lambda = %.17g: P = %.17g above %.17g at the smaller lambda", lam, p.value,
                     prev);
        if (lam < 1e-8 && !(fabs(p.value - 2) <= 1e-6))
            fail_msg("lambda = %.17g: P = %.17g, not the DMT limit 2", lam, p.value);
        if (lam > 300 && !(fabs(p.value - 1.5) <= 1e-4))
            fail_msg("lambda = %.17g: P = %.17g, not the JKR limit 1.5", lam, p.value);
        prev = p.value;
        prev_err = p.err;
    }
}

/* Asks the handler for a contact answer; returns its status, *finite set when 200 carried no
 * warning of a non-finite number; *pointer receives the first error's pointer otherwise. */
static int contact(const char *psd, double E, double dg, double eps, double R, int *finite,
                   char *pointer, size_t size)
{
    char body[600];
    ljgap__reply r;
    cJSON *doc, *w, *e;
    int status;
    snprintf(body, sizeof body,
             "{\"psd\":%s,\"tol\":1e-3,\"material\":{\"E_star\":%.17g,\"dgamma\":%.17g,"
             "\"epsilon\":%.17g},\"R\":%.17g}",
             psd, E, dg, eps, R);
    ljgap__handle("contact", body, strlen(body), &r);
    status = r.status;
    doc = cJSON_Parse(r.body);
    assert_non_null(doc);
    w = cJSON_GetObjectItem(cJSON_GetObjectItem(doc, "meta"), "warnings");
    *finite = 1;
    cJSON_ArrayForEach(e, w)
    {
        if (strstr(e->valuestring, "not a finite")) *finite = 0;
    }
    e = cJSON_GetArrayItem(cJSON_GetObjectItem(doc, "errors"), 0);
    snprintf(pointer, size, "%s",
             e ? cJSON_GetObjectItem(e, "pointer")->valuestring : "(no errors[])");
    if (status != 200 && status != 422) fail_msg("status %d: %.300s", status, r.body);
    cJSON_Delete(doc);
    ljgap__reply_free(&r);
    return status;
}

static const char *const psds[] = {
    "{\"kind\":\"power\",\"D\":2.5,\"k1\":1,\"k2\":8,\"C\":0.0796}",
    "{\"kind\":\"power\",\"D\":2.9,\"k1\":0.5,\"k2\":100,\"m0\":5}",
};
/* the accepted box (server/request.c): E*, Δγ, ε, R, each {low, high} */
static const double box[4][2] = {{1e3, 1e13}, {1e-6, 1e3}, {1e-12, 1e-6}, {1e-12, 1e6}};
static const char *const box_ptr[4] = {"/material/E_star", "/material/dgamma", "/material/epsilon",
                                       "/R"};

static void contact_box_corners(void **state)
{
    char ptr[200];
    for (size_t p = 0; p < 2; p++)
        for (int c = 0; c < 16; c++) {
            double v[4];
            int finite;
            for (int k = 0; k < 4; k++)
                v[k] = box[k][(c >> k) & 1];
            if (contact(psds[p], v[0], v[1], v[2], v[3], &finite, ptr, sizeof ptr) != 200 ||
                !finite)
                fail_msg("corner E* = %g, dgamma = %g, epsilon = %g, R = %g, psd %zu: not a "
                         "finite 200 answer (%s)",
                         v[0], v[1], v[2], v[3], p, ptr);
        }
}

static void contact_box_outside(void **state)
{
    char ptr[200];
    for (int k = 0; k < 4; k++)
        for (int side = 0; side < 2; side++) {
            double v[4] = {1e9, 0.05, 3e-10, 1e-6};
            int finite;
            v[k] = box[k][side] * (side ? 1.01 : 0.99);
            int st = contact(psds[0], v[0], v[1], v[2], v[3], &finite, ptr, sizeof ptr);
            if (st != 422 || strcmp(ptr, box_ptr[k]) != 0)
                fail_msg("%s = %g: status %d at %s, want 422 at %s", box_ptr[k], v[k], st, ptr,
                         box_ptr[k]);
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(md_dense_grid),
        cmocka_unit_test(contact_box_corners),
        cmocka_unit_test(contact_box_outside),
    };
    gsl_set_error_handler_off();
    return cmocka_run_group_tests(tests, NULL, NULL);
}
