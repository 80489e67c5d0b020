/* test_fold.c -- the folded two-lane Crank-Nicolson steps of the backward solver (fold.c)
 * against the same steps done the plain way: the explicit half by its stencil and the
 * implicit half by the Thomas algorithm in node order, on grids with random weights.
 *
 * Covered: the middle node where the lanes meet, the smallest grid (three nodes), frozen end
 * rows, infinite ends (f = 1: the last steps of an infinite tail can have ka = kb = infinity),
 * and chains of steps, where fold.c takes the explicit
 * half from the previous step's solution and right-hand side instead of the stencil (also
 * with unequal step coefficients). Each step starts both ways from the same state, so that a
 * difference is one step's, and the bound is rounding (1e-12).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "fold.h"
#include "ljgap.h"

#include <math.h>
#include <stdlib.h>

#include "check.h"

#define NMAX 41

/* A random grid: weights of the size of a geometric grid's of ratio ~1.02, each drawn from a
 * range of 25, so that the two lanes differ; A of both signs. */
typedef struct {
    size_t n;
    double A[NMAX], lo[NMAX], hi[NMAX];
} grid;

static double urand(unsigned *s)
{
    *s = *s * 1103515245u + 12345u;
    return (double)((*s >> 8) & 0xffffff) / 16777216.0;
}

static grid grid_random(size_t n, unsigned seed)
{
    grid G = {.n = n};
    for (size_t i = 0; i < n; i++) {
        double g = exp(-0.7 + 0.02 * (double)i);
        G.A[i] = 9.0 * pow(g, -10.0) - 3.0 * pow(g, -4.0) + 0.1 * (urand(&seed) - 0.5);
        int end = i == 0 || i + 1 == n;
        G.lo[i] = end ? 0 : 2500.0 * (0.2 + 5.0 * urand(&seed));
        G.hi[i] = end ? 0 : 2500.0 * (0.2 + 5.0 * urand(&seed));
    }
    return G;
}

static double fsq(double A, double k)
{
    double f = isinf(k) ? 1.0 : k / (k + A);
    return f * f;
}

/* x <- (I - ca Fa D2)^-1 (I + cb Fb D2) x, the plain way. */
static void step_plain(const grid *G, double ka, double kb, double ca, double cb, double *x)
{
    size_t n = G->n;
    double rhs[NMAX], dl[NMAX], dd[NMAX], du[NMAX];
    for (size_t i = 0; i < n; i++) {
        double d2 = 0;
        if (i > 0) d2 += G->lo[i] * (x[i - 1] - x[i]);
        if (i + 1 < n) d2 += G->hi[i] * (x[i + 1] - x[i]);
        rhs[i] = x[i] + cb * fsq(G->A[i], kb) * d2;
        double c = ca * fsq(G->A[i], ka);
        dl[i] = -c * G->lo[i];
        du[i] = -c * G->hi[i];
        dd[i] = 1.0 + c * (G->lo[i] + G->hi[i]);
    }
    for (size_t i = 1; i < n; i++) {
        double w = dl[i] / dd[i - 1];
        dd[i] -= w * du[i - 1];
        rhs[i] -= w * rhs[i - 1];
    }
    x[n - 1] = rhs[n - 1] / dd[n - 1];
    for (size_t i = n - 1; i-- > 0;)
        x[i] = (rhs[i] - du[i] * x[i + 1]) / dd[i];
}

/* A chain of steps from k = ks[0] down to ks[m] (ks[0] may be infinite), both ways. */
static void compare_chain(size_t n, unsigned seed, const double *ks, const double *cs, size_t m)
{
    grid G = grid_random(n, seed);
    double x[NMAX], xf[NMAX];
    for (size_t i = 0; i < n; i++)
        x[i] = sin(3.0 * (double)i / (double)n) + 0.3 * urand(&seed);
    ljgap__fold F;
    assert_int_equal(ljgap__fold_make(&F, n, G.A, G.lo, G.hi), LJGAP_OK);
    ljgap__fold_put(&F, x, F.x);
    for (size_t j = 0; j < m; j++) {
        step_plain(&G, ks[j + 1], ks[j], cs[j], cs[j], x);
        ljgap__fold_back(&F, ks[j + 1], ks[j], cs[j], cs[j]);
        ljgap__fold_get(&F, F.x, xf);
        for (size_t i = 0; i < n; i++)
            assert_close(xf[i], x[i], 1e-12 * (1.0 + fabs(x[i])));
        assert_true(xf[0] == x[0] && xf[n - 1] == x[n - 1]); /* frozen ends */
        for (size_t i = 0; i < n; i++)
            x[i] = xf[i]; /* the next step from the same state */
    }
    ljgap__fold_free(&F);
}

static void test_single_steps(void **state)
{
    (void)state;
    const double ks[2] = {2.0, 1.5}, cs[1] = {2e-2};
    for (size_t n = 3; n <= NMAX; n += 2)
        compare_chain(n, (unsigned)n, ks, cs, 1);
}

/* The explicit half from the previous step (equal and unequal coefficients; a ratio of 1e4
 * takes the stencil), starting with a step from infinity to infinity. */
static void test_step_chains(void **state)
{
    (void)state;
    const double ks[7] = {INFINITY, INFINITY, 40.0, 9.0, 3.0, 1.2, 0.9};
    const double cs[6] = {1e-6, 1e-2, 1e-2, 4e-3, 1e-2, 3e-2}; /* ratios 1e4, 1, 0.4, 2.5, 3 */
    compare_chain(NMAX, 7u, ks, cs, 6);
    compare_chain(5, 11u, ks, cs, 6);
    compare_chain(3, 13u, ks, cs, 6);
}

static void test_rejects_even_grids(void **state)
{
    (void)state;
    grid G = grid_random(6, 1u);
    ljgap__fold F;
    assert_int_equal(ljgap__fold_make(&F, 6, G.A, G.lo, G.hi), LJGAP_EINVAL);
    ljgap__fold_free(&F);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_single_steps),
        cmocka_unit_test(test_step_chains),
        cmocka_unit_test(test_rejects_even_grids),
    };
    return cmocka_run_group_tests_name("fold", tests, NULL, NULL);
}
