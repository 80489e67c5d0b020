/* test_levels.c -- the single-level entry points the error-against-time benchmark uses
 * (bench/errtime.c): ljgap__pde_pdf_at_level and ljgap__paper_summary_at / _pdf_at.
 *
 * A single level must be exactly what the drivers compute at that level (the paper's) or
 * converge at the scheme's order to what the driver returns (the PDE's), and keep the
 * scheme's invariants (mass and mean of the PDF). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>

#include "../../core/paper.h"
#include "../../core/pde.h"
#include "ljgap.h"

#include "check.h"

/* Fig. 2 spectrum: D = 2.5, k1 = 1, C = 1/(4π), cut at k2. */
static ljgap_psd fig_psd(double k2)
{
    ljgap_psd p;
    assert_int_equal(ljgap_psd_power(&p, 2.5, 1.0, k2, LJGAP_LEVEL_C, 0.25 / M_PI), LJGAP_OK);
    return p;
}

/* PDE levels: mass 1 and mean g_ave (the scheme's invariants), second-order convergence of
 * the PDF's traction, and the limit within a level difference of the public solver's answer. */
static void test_pde_pdf_levels(void **state)
{
    (void)state;
    ljgap_psd p = fig_psd(5.0);
    double s[5];
    for (int L = 0; L < 5; L++) {
        ljgap_pdf out;
        assert_int_equal(ljgap__pde_pdf_at_level(&p, 0.98, 5.0, 0.5, 8.0, L, &out), LJGAP_OK);
        assert_close(out.mass, 1.0, 1e-12);
        assert_close(out.mean, 0.98, 1e-12);
        double l1 = 0; /* the density integrates to the mass on the cell widths */
        for (size_t i = 1; i < out.n; i++)
            l1 += 0.5 * (out.phi[i] + out.phi[i - 1]) * (out.g[i] - out.g[i - 1]);
        assert_close(l1, 1.0, 1e-3);
        s[L] = out.sigma.value;
        ljgap_pdf_release(&out, 1);
    }
    double order = log2(fabs(s[3] - s[2]) / fabs(s[4] - s[3]));
    print_message("pde pdf sigma by level: %.10f %.10f %.10f %.10f %.10f, order %.3f\n", s[0], s[1],
                  s[2], s[3], s[4], order);
    assert_true(order > 1.8 && order < 2.3);
    ljgap_opts o;
    ljgap_opts_default(&o);
    ljgap_pdf ref;
    double k2 = 5.0;
    assert_int_equal(ljgap_pdf_compute(&p, &o, 0.98, &k2, 1, NULL, &ref, NULL), LJGAP_OK);
    assert_close(s[4], ref.sigma.value, 2.0 * fabs(s[4] - s[3]));
    ljgap_pdf_release(&ref, 1);
    ljgap_pdf out;
    assert_int_equal(ljgap__pde_pdf_at_level(&p, 0.4, 5.0, 0.5, 8.0, 0, &out), LJGAP_EINVAL);
}

/* With tol = 1 the paper's drivers run Vmax and Vmax/2 and report the latter: a single level
 * at Vmax/2 is the same computation. */
static void test_paper_single_level_is_the_driver_level(void **state)
{
    (void)state;
    ljgap_opts o;
    ljgap_opts_default(&o);
    o.method = LJGAP_METHOD_PAPER;
    o.vmax = 0.04;
    o.tol = 1.0;
    ljgap_psd p = fig_psd(5.0);
    ljgap_summary a, b;
    assert_int_equal(ljgap_traction(&p, &o, NULL, 0, NULL, &a, NULL), LJGAP_OK);
    assert_int_equal(ljgap__paper_summary_at(&p, &o, 0.02, &b), LJGAP_OK);
    assert_close(b.g_eq.value, a.g_eq.value, 1e-14);
    assert_close(b.sigma_max.value, a.sigma_max.value, 1e-14);
    assert_close(b.g_at_max.value, a.g_at_max.value, 1e-14);
    assert_close(b.dgamma_eff.value, a.dgamma_eff.value, 1e-14);
    assert_true(b.dgamma_eff.err == 0.0);

    double k2 = 5.0, grid[3] = {0.6, 3.0, 241};
    ljgap_pdf x, y;
    assert_int_equal(ljgap_pdf_compute(&p, &o, 0.98, &k2, 1, grid, &x, NULL), LJGAP_OK);
    assert_int_equal(ljgap__paper_pdf_at(&p, &o, 0.02, 0.98, k2, grid, &y), LJGAP_OK);
    assert_int_equal(x.n, y.n);
    for (size_t i = 0; i < x.n; i++)
        assert_close(y.phi[i], x.phi[i], 1e-12);
    assert_close(y.sigma.value, x.sigma.value, 1e-12);
    ljgap_pdf_release(&x, 1);
    ljgap_pdf_release(&y, 1);
    assert_int_equal(ljgap__paper_summary_at(&p, &o, -1.0, &b), LJGAP_EINVAL);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pde_pdf_levels),
        cmocka_unit_test(test_paper_single_level_is_the_driver_level),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
