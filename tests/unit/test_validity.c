/* test_validity.c -- the validity map as the answers read it (core/validity.c and the table
 * bench/validity_table.sh generated, core/validity_table.c).
 *
 * - At every point of the table the lookup gives the table's values exactly, inside the map.
 * - Between two neighbouring points along any axis (k2/k1, D, m0) the values are monotone and
 *   stay between the two ends; midway in D (and in ln m0) they are the mean of the ends.
 * - Outside the map (D, k2/k1 below, m0 above, k1 not 1) inside is 0 with a reason naming the
 *   cause, and the values are the nearest point's; m0 below the map gives its smallest m0's
 *   values as a bound, inside.
 * - The k2/k1 = 8 rows agree with an independent computation of the same relative differences:
 *   bench/theory_map.sh's own awk, bench/results/theory_map_rel.csv (from the main map alone).
 * - The k2/k1 = 16 and 32 rows are the L = 4π runs tied to the main map by the L bias at 8,
 *   rel_k(4π) - rel_8(4π) + rel_8(8π), computed here from the bench's CSVs.
 * - The L bias carried from 8 to 32 holds: the discrete model at k2/k1 = 32 on L = 8π (three
 *   cases) gives the table's k2/k1 = 32 differences within the table's error and its own.
 * - A table PSD sampled from a power law has that power law's D, m0 and ends; a table with a
 *   knee (D 2.2 then 2.9) is not power-law-like.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "check.h"
#include "ljgap_validity.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double k2_of(const ljgap_validity_row *r)
{
    return r->k2_over_k1; /* k1 = 1: k2 = k2/k1, INFINITY for the continuum */
}

static void exact_at_points(void **state)
{
    (void)state;
    assert_true(ljgap_validity_nrows >= 27);
    for (size_t i = 0; i < ljgap_validity_nrows; i++) {
        const ljgap_validity_row *r = &ljgap_validity_rows[i];
        ljgap_validity v;
        assert_int_equal(ljgap_validity_at(r->D, r->m0, 1.0, k2_of(r), &v), LJGAP_OK);
        if (!v.inside) fail_msg("row %zu: outside: %s", i, v.reason);
        assert_false(v.bound);
        for (int q = 0; q < LJGAP_V_N; q++) {
            assert_close(v.rel[q], r->rel[q], 1e-12);
            assert_close(v.err[q], r->err[q], 1e-12);
            assert_true(r->err[q] >= 0);
        }
    }
}

/* The row at (k, D, m0), or NULL. */
static const ljgap_validity_row *row_at(double k, double D, double m0)
{
    for (size_t i = 0; i < ljgap_validity_nrows; i++) {
        const ljgap_validity_row *r = &ljgap_validity_rows[i];
        if (r->k2_over_k1 == k && r->D == D && r->m0 == m0) return r;
    }
    return NULL;
}

/* Walks from a to b (rows differing on one axis) at 41 points of x(t): monotone, between. */
static void walk(const ljgap_validity_row *a, const ljgap_validity_row *b, int axis)
{
    double prev[LJGAP_V_N];
    for (int s = 0; s <= 40; s++) {
        double t = s / 40.0, D = a->D, m0 = a->m0, k = a->k2_over_k1;
        if (axis == 0) {
            /* from k2/k1 = a to b (b may be ∞): through 1/k2 */
            double xa = 1 / a->k2_over_k1, xb = 1 / b->k2_over_k1, x = xa + t * (xb - xa);
            k = x > 0 ? 1 / x : INFINITY;
        } else if (axis == 1)
            D = a->D + t * (b->D - a->D);
        else
            m0 = exp(log(a->m0) + t * (log(b->m0) - log(a->m0)));
        ljgap_validity v;
        assert_int_equal(ljgap_validity_at(D, m0, 1.0, k, &v), LJGAP_OK);
        if (!v.inside) fail_msg("outside at D %g m0 %g k %g: %s", D, m0, k, v.reason);
        for (int q = 0; q < LJGAP_V_N; q++) {
            double lo = fmin(a->rel[q], b->rel[q]) - 1e-12, hi = fmax(a->rel[q], b->rel[q]) + 1e-12;
            if (v.rel[q] < lo || v.rel[q] > hi)
                fail_msg("q %d at t %g: %.9g not within [%.9g, %.9g]", q, t, v.rel[q], lo, hi);
            if (s > 0) {
                double up = b->rel[q] >= a->rel[q] ? 1 : -1;
                if (up * (v.rel[q] - prev[q]) < -1e-12)
                    fail_msg("q %d not monotone at t %g: %.12g after %.12g", q, t, v.rel[q],
                             prev[q]);
            }
            prev[q] = v.rel[q];
            if (s == 20 && axis > 0) /* midway in D, in ln m0: the mean of the ends */
                assert_close(v.rel[q], (a->rel[q] + b->rel[q]) / 2, 1e-12);
        }
    }
}

static void monotone_between(void **state)
{
    (void)state;
    size_t pairs = 0;
    for (size_t i = 0; i < ljgap_validity_nrows; i++) {
        const ljgap_validity_row *a = &ljgap_validity_rows[i], *best[3] = {NULL, NULL, NULL};
        /* the next point along each axis */
        for (size_t j = 0; j < ljgap_validity_nrows; j++) {
            const ljgap_validity_row *b = &ljgap_validity_rows[j];
            if (b->D == a->D && b->m0 == a->m0 && b->k2_over_k1 > a->k2_over_k1 &&
                (!best[0] || b->k2_over_k1 < best[0]->k2_over_k1))
                best[0] = b;
            if (b->k2_over_k1 == a->k2_over_k1 && b->m0 == a->m0 && b->D > a->D &&
                (!best[1] || b->D < best[1]->D))
                best[1] = b;
            if (b->k2_over_k1 == a->k2_over_k1 && b->D == a->D && b->m0 > a->m0 &&
                (!best[2] || b->m0 < best[2]->m0))
                best[2] = b;
        }
        for (int ax = 0; ax < 3; ax++)
            if (best[ax]) walk(a, best[ax], ax), pairs++;
    }
    assert_true(pairs >= 18 + 24); /* 3 D x 9 m0 at least: 18 pairs in D, 24 in m0 */
}

static void outside_reasons(void **state)
{
    (void)state;
    ljgap_validity v;
    const ljgap_validity_row *near = row_at(8, 2.2, 0.1);
    assert_non_null(near);
    assert_int_equal(ljgap_validity_at(2.1, 0.1, 1, 8, &v), LJGAP_OK);
    assert_false(v.inside);
    assert_non_null(strstr(v.reason, "D = 2.1"));
    assert_close(v.at_D, 2.2, 0);
    assert_close(v.rel[LJGAP_V_DGAMMA_EFF], near->rel[LJGAP_V_DGAMMA_EFF], 1e-12);

    assert_int_equal(ljgap_validity_at(2.5, 0.1, 1, 5, &v), LJGAP_OK);
    assert_false(v.inside);
    assert_non_null(strstr(v.reason, "below the map's smallest"));

    assert_int_equal(ljgap_validity_at(2.5, 2.0, 1, 8, &v), LJGAP_OK);
    assert_false(v.inside);
    assert_non_null(strstr(v.reason, "m0 = 2 is above"));

    assert_int_equal(ljgap_validity_at(2.5, 0.1, 0.5, 4, &v), LJGAP_OK); /* k2/k1 = 8 */
    assert_false(v.inside);
    assert_non_null(strstr(v.reason, "k1 = 0.5"));

    /* below the smallest m0: the smallest m0's values, as a bound, inside */
    const ljgap_validity_row *m = row_at(8, 2.5, 0.01);
    assert_non_null(m);
    assert_int_equal(ljgap_validity_at(2.5, 1e-4, 1, 8, &v), LJGAP_OK);
    assert_true(v.inside);
    assert_true(v.bound);
    for (int q = 0; q < LJGAP_V_N; q++)
        assert_close(v.rel[q], m->rel[q], 1e-12);

    /* not numbers */
    assert_int_equal(ljgap_validity_at(NAN, 0.1, 1, 8, &v), LJGAP_EINVAL);
    assert_int_equal(ljgap_validity_at(2.5, -1, 1, 8, &v), LJGAP_EINVAL);
    assert_int_equal(ljgap_validity_at(2.5, 0.1, 1, 1, &v), LJGAP_EINVAL);
    assert_int_equal(ljgap_validity_at(2.5, 0.1, INFINITY, INFINITY, &v), LJGAP_EINVAL);
}

/* The k2/k1 = 8 rows at the main map's m0 against theory_map.sh's relative differences. */
static void agrees_with_bench(void **state)
{
    (void)state;
    FILE *f = fopen("bench/results/theory_map_rel.csv", "r");
    char line[512];
    int n = 0;
    assert_non_null(f);
    while (fgets(line, sizeof line, f)) {
        double D, m0, disc, derr, rel;
        char q[32];
        if (sscanf(line, "%lf,%lf,%31[^,],%lf,%lf,%lf", &D, &m0, q, &disc, &derr, &rel) != 6)
            continue;
        int qi = !strcmp(q, "g_eq")         ? 0
                 : !strcmp(q, "sigma_max")  ? 1
                 : !strcmp(q, "dgamma_eff") ? 2
                                            : -1;
        if (qi < 0) continue;
        const ljgap_validity_row *r = row_at(8, D, m0);
        assert_non_null(r);
        assert_close(r->rel[qi], rel, 1e-5); /* both printed to 5-6 decimals */
        assert_true(r->err[qi] >= derr / fabs(disc) * 0.5);
        n++;
    }
    fclose(f);
    assert_int_equal(n, 3 * 3 * 7);
}

/* theory_map_k2.csv's relative difference of label k2_K at D, m0 for each quantity */
typedef struct {
    char label[16];
    double D, m0, th[3], ds[3];
} k2run;

static size_t read_k2(k2run *r, size_t max)
{
    FILE *f = fopen("bench/results/theory_map_k2.csv", "r");
    char line[512], model[32];
    size_t n = 0;
    assert_non_null(f);
    while (fgets(line, sizeof line, f) && n < max) {
        k2run x;
        double v[8];
        if (sscanf(line,
                   "%15[^,],%lf,%lf,%31[^,],%*[^,],%*[^,],%*[^,],%*[^,],%*[^,],%lf,%lf,%lf,%lf,%lf,"
                   "%lf,%lf,%lf",
                   x.label, &x.D, &x.m0, model, &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6],
                   &v[7]) != 12)
            continue;
        size_t i = 0;
        while (i < n && !(!strcmp(r[i].label, x.label) && r[i].D == x.D && r[i].m0 == x.m0))
            i++;
        if (i == n) r[n++] = x;
        double *dst = !strcmp(model, "theory") ? r[i].th : r[i].ds;
        dst[0] = v[0], dst[1] = v[2], dst[2] = v[6];
    }
    fclose(f);
    return n;
}

static const k2run *find_k2(const k2run *r, size_t n, const char *label, double D, double m0)
{
    for (size_t i = 0; i < n; i++)
        if (!strcmp(r[i].label, label) && r[i].D == D && r[i].m0 == m0) return &r[i];
    return NULL;
}

static void tied_by_L_bias(void **state)
{
    (void)state;
    static k2run runs[200];
    size_t n = read_k2(runs, 200), checked = 0;
    for (size_t i = 0; i < ljgap_validity_nrows; i++) {
        const ljgap_validity_row *r = &ljgap_validity_rows[i], *main8;
        char label[16];
        if (r->k2_over_k1 == 8) continue;
        if (isinf(r->k2_over_k1)) { /* the continuum: a + b (1/k)^p through 8 and 16 (or 16, 32) */
            int has32 = row_at(32, r->D, r->m0) != NULL;
            double lo = has32 ? 16 : 8, hi = has32 ? 32 : 16, p = 2 * (3 - r->D);
            char l1[16], l2[16];
            snprintf(l1, sizeof l1, "k2_%g", lo);
            snprintf(l2, sizeof l2, "k2_%g", hi);
            const k2run *a = find_k2(runs, n, l1, r->D, r->m0),
                        *b = find_k2(runs, n, l2, r->D, r->m0),
                        *e = find_k2(runs, n, "k2_8", r->D, r->m0);
            main8 = row_at(8, r->D, r->m0);
            assert_non_null(a);
            assert_non_null(b);
            for (int q = 0; q < LJGAP_V_N; q++) {
                double ra = a->th[q] / a->ds[q] - 1, rb = b->th[q] / b->ds[q] - 1;
                double sa = pow(lo, -p), sb = pow(hi, -p), slope = (ra - rb) / (sa - sb);
                double bias = main8->rel[q] - (e->th[q] / e->ds[q] - 1);
                assert_close(r->rel[q], rb - slope * sb + bias, 3e-5);
                assert_true(r->err[q] >= fabs(r->rel[q] - rb - bias) - 3e-5 || has32);
            }
            checked++;
            continue;
        }
        snprintf(label, sizeof label, "k2_%g", r->k2_over_k1);
        const k2run *k = find_k2(runs, n, label, r->D, r->m0),
                    *e = find_k2(runs, n, "k2_8", r->D, r->m0);
        main8 = row_at(8, r->D, r->m0);
        assert_non_null(k);
        assert_non_null(e);
        assert_non_null(main8);
        if (main8->L_bias[0] == 0 && main8->L_bias[1] == 0) continue;
        for (int q = 0; q < LJGAP_V_N; q++) {
            double want = (k->th[q] / k->ds[q] - 1) - (e->th[q] / e->ds[q] - 1) + main8->rel[q];
            /* main8->rel is the 8π value where the main map has the point; else 4π + bias */
            assert_close(r->rel[q], want, 2e-5);
        }
        checked++;
    }
    size_t levels = 0;
    for (size_t i = 0; i < ljgap_validity_nrows; i++)
        levels += ljgap_validity_rows[i].k2_over_k1 == 16;
    assert_true(levels == 0 || checked >= 27);
}

/* The L bias carried from k2/k1 = 8 to 32, checked directly: the discrete model at k2/k1 = 32 on
 * L = 8π (bench/results/theory_map_conv32.csv) against the theory, within the table's error. */
static void L_bias_holds_at_32(void **state)
{
    (void)state;
    static k2run runs[200];
    size_t n = read_k2(runs, 200), checked = 0;
    FILE *f = fopen("bench/results/theory_map_conv32.csv", "r");
    char line[512], label[32], model[32];
    assert_non_null(f);
    while (fgets(line, sizeof line, f)) {
        double D, m0, v[8];
        if (sscanf(line,
                   "%31[^,],%lf,%lf,%31[^,],%*[^,],%*[^,],%*[^,],%*[^,],%*[^,],%lf,%lf,%lf,%lf,%lf,"
                   "%lf,%lf,%lf",
                   label, &D, &m0, model, &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6],
                   &v[7]) != 12 ||
            strcmp(label, "k2_32_L8pi") || strcmp(model, "discrete"))
            continue;
        const k2run *k = find_k2(runs, n, "k2_32", D, m0);
        const ljgap_validity_row *r = row_at(32, D, m0);
        assert_non_null(k);
        assert_non_null(r);
        const double d8pi[3] = {v[0], v[2], v[6]}, e8pi[3] = {v[1], v[3], v[7]};
        for (int q = 0; q < LJGAP_V_N; q++) {
            double rel = k->th[q] / d8pi[q] - 1, err = fabs(1 + rel) * e8pi[q] / fabs(d8pi[q]);
            if (!(fabs(rel - r->rel[q]) <= r->err[q] + err))
                fail_msg("D %g m0 %g q %d: L = 8π gives %.4f ± %.4f, the table %.4f ± %.4f", D, m0,
                         q, rel, err, r->rel[q], r->err[q]);
        }
        checked++;
    }
    fclose(f);
    assert_true(checked >= 2);
}

static void table_psd(void **state)
{
    (void)state;
    double k[40], P[40], D = 2.5, C = 0.02;
    ljgap_psd t, p;
    ljgap_validity v, w;
    for (int i = 0; i < 40; i++) {
        k[i] = pow(8.0, i / 39.0);
        P[i] = C * pow(k[i], 2 * D - 8);
    }
    assert_int_equal(ljgap_psd_table(&t, k, P, 40, 0, 0), LJGAP_OK);
    assert_int_equal(ljgap_psd_power(&p, D, 1, 8, LJGAP_LEVEL_C, C), LJGAP_OK);
    assert_int_equal(ljgap_validity_of_psd(&t, &v), LJGAP_OK);
    assert_int_equal(ljgap_validity_of_psd(&p, &w), LJGAP_OK);
    assert_true(v.inside && w.inside);
    assert_close(v.D, D, 1e-9);
    assert_close(v.m0, w.m0, 1e-9 * w.m0);
    assert_close(v.k2_over_k1, 8, 1e-12);
    for (int q = 0; q < LJGAP_V_N; q++)
        assert_close(v.rel[q], w.rel[q], 1e-9);
    assert_non_null(strstr(v.method, "variance-weighted"));
    ljgap_psd_free(&t);
    /* with a tail: k2 = ∞ */
    assert_int_equal(ljgap_psd_table(&t, k, P, 40, 1, 2 * D - 8), LJGAP_OK);
    assert_int_equal(ljgap_validity_of_psd(&t, &v), LJGAP_OK);
    assert_true(isinf(v.k2_over_k1));
    assert_close(v.D, D, 1e-9);
    ljgap_psd_free(&t);
    /* a knee: D 2.2 below k = 3, 2.9 above */
    for (int i = 0; i < 40; i++)
        P[i] = k[i] < 3 ? pow(k[i], 2 * 2.2 - 8) : pow(3, 2 * 2.2 - 8) * pow(k[i] / 3, 2 * 2.9 - 8);
    assert_int_equal(ljgap_psd_table(&t, k, P, 40, 0, 0), LJGAP_OK);
    assert_int_equal(ljgap_validity_of_psd(&t, &v), LJGAP_OK);
    assert_false(v.inside);
    assert_non_null(strstr(v.reason, "not power-law-like"));
    ljgap_psd_free(&t);
    ljgap_psd_free(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(exact_at_points), cmocka_unit_test(monotone_between),
        cmocka_unit_test(outside_reasons), cmocka_unit_test(agrees_with_bench),
        cmocka_unit_test(tied_by_L_bias),  cmocka_unit_test(L_bias_holds_at_32),
        cmocka_unit_test(table_psd),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
