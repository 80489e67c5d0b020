/* test_mc_bias.c -- the Monte Carlo PDF's step bias is measured and covered by its estimate.
 *
 * For the Fig. 2 spectrum at g_ave = 0.98 the paths' step control c leaves a bias in the
 * PDF's traction sigma (measured with 1e5 paths against the PDE's -2.2755238: -0.075 at
 * c = 0.3, -0.016 at the default 0.15, +0.003 at 0.075), seven standard errors at 1e6 paths
 * before ljgap__pdf_mc measured it with a second run at 2c. Same seeds in both runs, so the
 * measured bias is far less noisy than either run. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>

#include "../../core/mc.h"
#include "ljgap.h"
#include "core.h" /* the core's internals */

#include "check.h"

static void test_pdf_sigma_bias_covered(void **state)
{
    (void)state;
    ljgap_psd psd;
    assert_int_equal(ljgap_psd_power(&psd, 2.5, 1.0, 5.0, LJGAP_LEVEL_C, 0.25 / M_PI), LJGAP_OK);
    ljgap_opts o;
    ljgap_opts_default(&o);
    double k2 = 5.0;
    ljgap_pdf ref, mc, raw;
    assert_int_equal(ljgap_pdf_compute(&psd, &o, 0.98, &k2, 1, NULL, &ref, NULL), LJGAP_OK);
    o.method = LJGAP_METHOD_MC;
    o.samples = 40000;
    o.seed = 3;
    o.max_seconds = 120;
    assert_int_equal(ljgap_pdf_compute(&psd, &o, 0.98, &k2, 1, NULL, &mc, NULL), LJGAP_OK);
    /* the uncorrected run at c: same seeds as the corrected answer's first run */
    assert_int_equal(ljgap__mc_pdf(&psd, &o, LJGAP__MC_C, 0.98, &k2, 1, NULL, &raw, NULL),
                     LJGAP_OK);
    double bias = raw.sigma.value - mc.sigma.value; /* the correction b that was subtracted */
    print_message("pde %.7f; montecarlo %.5f ± %.2g (uncorrected %.5f ± %.2g, bias %.4f); L1 "
                  "estimate %.3g\n",
                  ref.sigma.value, mc.sigma.value, mc.sigma.err, raw.sigma.value, raw.sigma.err,
                  bias, mc.phi_err);
    assert_true(bias < -0.005 && bias > -0.05);        /* measured, of the size seen at 1e5 */
    assert_true(mc.sigma.err >= raw.sigma.err - bias); /* |b| is in the estimate */
    assert_close(mc.sigma.value, ref.sigma.value, 3.0 * (mc.sigma.err + ref.sigma.err));
    assert_true(mc.phi_err > raw.phi_err);
    ljgap_pdf_release(&ref, 1);
    ljgap_pdf_release(&mc, 1);
    ljgap_pdf_release(&raw, 1);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pdf_sigma_bias_covered),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
