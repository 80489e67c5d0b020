/* test_cross.c -- the three methods against each other.
 *
 * The PDE (continuum limit), the paper's iteration at small Vmax (a different
 * discretisation of the same process: first order in Vmax) and Monte Carlo of the Itô
 * process (statistical error only) must agree within their own error estimates, on a benign
 * spectrum and on a stiff start (k1 = 0.5, where f reaches ~16 near g*). Both the traction
 * at single mean gaps and the gap PDF's traction are compared. The bound is a multiple of the
 * combined estimates: 3x for the deterministic pair, 4x for Monte Carlo (whose estimate is
 * the standard error plus the measured step bias). The paper's iteration starts at
 * Vmax = 1/100 so that three levels (two differences) fit in its work cap.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "ljgap.h"

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>

typedef struct {
    const char *name;
    double D, k1, k2, m0;
    double g[3];
} cross_case;

static const cross_case cases[] = {
    {"benign (Fig. 2 spectrum)", 2.5, 1.0, 5.0, 0.4, {0.98, 1.5, 2.5}},
    {"stiff", 2.5, 0.5, 2.0, 0.1, {1.0, 1.4, 2.0}},
};

static void traction(const cross_case *c, ljgap_method m, double tol, ljgap_est *out)
{
    ljgap_psd p;
    assert_int_equal(ljgap_psd_power(&p, c->D, c->k1, c->k2, LJGAP_LEVEL_M0, c->m0), LJGAP_OK);
    ljgap_opts o;
    ljgap_opts_default(&o);
    o.method = m;
    o.tol = tol;
    o.samples = 100000;
    o.seed = 7;
    if (m == LJGAP_METHOD_PAPER) { /* start coarse so that three levels fit */
        o.vmax = 0.01;
        o.max_work = 2000000000L;
    }
    ljgap_warnings w = {0};
    int st = ljgap_traction(&p, &o, c->g, 3, out, NULL, &w);
    for (int i = 0; i < w.n; i++)
        print_message("  %s: warning: %s\n", c->name, w.msg[i]);
    assert_int_equal(st, LJGAP_OK);
}

static void compare(const cross_case *c, const char *what, const ljgap_est *a, const ljgap_est *b,
                    double k)
{
    for (int i = 0; i < 3; i++) {
        double d = fabs(a[i].value - b[i].value), bound = k * (a[i].err + b[i].err);
        print_message("%s g=%.2f %s: %.10f ± %.2g vs %.10f ± %.2g (diff %.2g, bound %.2g)\n",
                      c->name, c->g[i], what, a[i].value, a[i].err, b[i].value, b[i].err, d, bound);
        if (!(d <= bound)) {
            print_error("%.17g vs %.17g\n", a[i].value, b[i].value);
            fail();
        }
    }
}

/* Every case: the PDE at tol 1e-8 against method m, within k times the combined estimates. */
static void against_pde(ljgap_method m, const char *what, double k)
{
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        ljgap_est pde[3], other[3];
        traction(&cases[c], LJGAP_METHOD_PDE, 1e-8, pde);
        traction(&cases[c], m, m == LJGAP_METHOD_PAPER ? 1e-4 : 1e-3, other);
        compare(&cases[c], what, pde, other, k);
    }
}

static void test_pde_vs_paper(void **state)
{
    (void)state;
    against_pde(LJGAP_METHOD_PAPER, "pde/paper", 3.0);
}

static void test_pde_vs_montecarlo(void **state)
{
    (void)state;
    against_pde(LJGAP_METHOD_MC, "pde/mc", 4.0);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pde_vs_paper),
        cmocka_unit_test(test_pde_vs_montecarlo),
    };
    return cmocka_run_group_tests_name("cross-method", tests, NULL, NULL);
}
