/* test_mc.c -- Monte Carlo of the Itô process: limits, a thin band, the martingale, the
 * time-step bias, and agreement with the paper's iteration. Tolerances come from the
 * returned error estimates. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "../../core/mc.h"
#include "core.h" /* ljgap__now */
#include "ljgap.h"

#include "check.h"

static ljgap_opts mc_opts(long samples)
{
    ljgap_opts o;
    ljgap_opts_default(&o);
    o.method = LJGAP_METHOD_MC;
    o.samples = samples;
    o.max_seconds = 30;
    return o;
}

static void print_warnings(const ljgap_warnings *w)
{
    for (int i = 0; i < w->n; i++)
        printf("  warning: %s\n", w->msg[i]);
}

/* Mean and variance of a histogram PDF (Sheppard's correction for the bins). */
static void pdf_moments(const ljgap_pdf *p, double *mean, double *var)
{
    double dg = p->g[1] - p->g[0], m = 0, v = 0;
    for (size_t i = 0; i < p->n; i++)
        m += p->g[i] * p->phi[i] * dg;
    for (size_t i = 0; i < p->n; i++)
        v += (p->g[i] - m) * (p->g[i] - m) * p->phi[i] * dg;
    *mean = m;
    *var = v - dg * dg / 12.0;
}

/* (1) m0 -> 0: sigma_bar -> sigma(g_ave). */
static void test_tiny_m0(void **state)
{
    (void)state;
    ljgap_psd psd;
    assert_int_equal(ljgap_psd_power(&psd, 2.5, 1.0, 5.0, LJGAP_LEVEL_M0, 1e-6), LJGAP_OK);
    ljgap_opts o = mc_opts(4096);
    const double g[3] = {1.0, 1.3, 2.0};
    ljgap_est s[3];
    ljgap_warnings w = {0};
    assert_int_equal(ljgap_traction(&psd, &o, g, 3, s, NULL, &w), LJGAP_OK);
    print_warnings(&w);
    for (int i = 0; i < 3; i++) {
        /* bias of the smoothing: sigma'' m0 f^2/2 with f <= 3 here */
        double h = 1e-3,
               d2 = (ljgap_sigma(g[i] + h) - 2 * ljgap_sigma(g[i]) + ljgap_sigma(g[i] - h)) /
                    (h * h);
        assert_true(s[i].err > 0);
        assert_close(s[i].value, ljgap_sigma(g[i]), 4 * s[i].err + fabs(d2) * 1e-6 * 9 / 2);
    }
}

/* (2) a thin band: G - g_ave is Gaussian with the packet variance (17). */
static void test_thin_band(void **state)
{
    (void)state;
    ljgap_psd psd;
    assert_int_equal(ljgap_psd_power(&psd, 2.5, 1.0, 5.0, LJGAP_LEVEL_C, 0.25 / M_PI), LJGAP_OK);
    const double g0 = 3.0, k2 = 1.02; /* f ≈ 1 and flat: (16) is exact */
    double V = ljgap_packet_var(&psd, g0, 1.0, k2), sd = sqrt(V);
    ljgap_opts o = mc_opts(40000);
    const double grid[3] = {g0 - 7 * sd, g0 + 7 * sd, 1401};
    ljgap_pdf p;
    ljgap_warnings w = {0};
    assert_int_equal(ljgap_pdf_compute(&psd, &o, g0, &k2, 1, grid, &p, &w), LJGAP_OK);
    print_warnings(&w);
    double mean, var;
    pdf_moments(&p, &mean, &var);
    double se = V * sqrt(2.0 / (double)o.samples);
    printf("  variance %.6g vs (17) %.6g (se %.2g), mass %.6f\n", var, V, se, p.mass);
    assert_close(var, V, 4 * se);
    assert_close(p.mass, 1.0, 1e-3);
    ljgap_pdf_release(&p, 1);
}

/* (5) G is a martingale: the mean end gap is g_ave; the PDF has unit mass. */
static void test_martingale(void **state)
{
    (void)state;
    ljgap_psd psd;
    assert_int_equal(ljgap_psd_power(&psd, 2.5, 1.0, INFINITY, LJGAP_LEVEL_C, 0.25 / M_PI),
                     LJGAP_OK);
    ljgap_opts o = mc_opts(20000);
    const double k2[2] = {5.0, INFINITY};
    ljgap_pdf p[2];
    ljgap_warnings w = {0};
    assert_int_equal(ljgap_pdf_compute(&psd, &o, 0.98, k2, 2, NULL, p, &w), LJGAP_OK);
    print_warnings(&w);
    for (int s = 0; s < 2; s++) {
        double mean, var;
        pdf_moments(&p[s], &mean, &var);
        double se = sqrt(var / (double)o.samples);
        printf("  k2 = %g: mean %.6f (se %.2g), sigma %.5f +- %.2g, phi L1 err %.3g\n", k2[s],
               p[s].mean, se, p[s].sigma.value, p[s].sigma.err, p[s].phi_err);
        assert_close(p[s].mean, 0.98, 4 * se);
        assert_close(p[s].mass, 1.0, 1e-12);
        assert_true(p[s].phi_err > 0 && p[s].phi_err < 1);
    }
    ljgap_pdf_release(p, 2);
}

/* The time-step bias (halving c), stiff start: below one standard error of 8192 paths. */
static void test_step_bias(void **state)
{
    (void)state;
    ljgap_psd psd;
    assert_int_equal(ljgap_psd_power(&psd, 2.5, 0.5, 2.0, LJGAP_LEVEL_M0, 0.1), LJGAP_OK);
    ljgap_opts o = mc_opts(8192);
    const double g[2] = {1.0, 1.4};
    ljgap_est a[2], b[2];
    assert_int_equal(ljgap__mc_traction(&psd, &o, LJGAP__MC_C, g, 2, a, NULL, NULL), LJGAP_OK);
    assert_int_equal(ljgap__mc_traction(&psd, &o, 0.5 * LJGAP__MC_C, g, 2, b, NULL, NULL),
                     LJGAP_OK);
    for (int i = 0; i < 2; i++) {
        printf("  g = %.2f: c %.5f +- %.2g, c/2 %.5f +- %.2g\n", g[i], a[i].value, a[i].err,
               b[i].value, b[i].err);
        assert_close(a[i].value, b[i].value, a[i].err);
    }
}

/* (3) Monte Carlo against the paper's iteration, benign and stiff starts. */
static void compare(const ljgap_psd *psd, const double *g, size_t n, long samples)
{
    ljgap_opts o = mc_opts(samples), op;
    ljgap_opts_default(&op);
    op.method = LJGAP_METHOD_PAPER;
    op.tol = 1e-4;
    op.max_work = 700000000L;
    op.max_seconds = 30;
    ljgap_est a[4], b[4];
    ljgap_warnings w = {0}, wp = {0};
    double t0 = ljgap__now();
    assert_int_equal(ljgap_traction(psd, &o, g, n, a, NULL, &w), LJGAP_OK);
    double t1 = ljgap__now();
    assert_int_equal(ljgap_traction(psd, &op, g, n, b, NULL, &wp), LJGAP_OK);
    double t2 = ljgap__now();
    print_warnings(&w);
    print_warnings(&wp);
    for (size_t i = 0; i < n; i++) {
        printf("  g = %.2f: montecarlo %.5f +- %.2g (%.1f s), paper %.5f +- %.2g (%.1f s)\n", g[i],
               a[i].value, a[i].err, t1 - t0, b[i].value, b[i].err, t2 - t1);
        assert_close(a[i].value, b[i].value, 4 * (a[i].err + b[i].err));
    }
}

static void test_vs_paper_benign(void **state)
{
    (void)state;
    ljgap_psd psd;
    assert_int_equal(ljgap_psd_power(&psd, 2.5, 1.0, 5.0, LJGAP_LEVEL_C, 0.25 / M_PI), LJGAP_OK);
    const double g[2] = {0.98, 1.5};
    compare(&psd, g, 2, 16384);
}

static void test_vs_paper_stiff(void **state)
{
    (void)state;
    ljgap_psd psd;
    assert_int_equal(ljgap_psd_power(&psd, 2.5, 0.5, 2.0, LJGAP_LEVEL_M0, 0.1), LJGAP_OK);
    const double g[2] = {1.2, 1.4};
    compare(&psd, g, 2, 16384);
}

/* The summary by batch means, and the caps. */
static void test_summary_and_caps(void **state)
{
    (void)state;
    ljgap_psd psd;
    assert_int_equal(ljgap_psd_power(&psd, 2.5, 1.0, INFINITY, LJGAP_LEVEL_C, 0.25 / M_PI),
                     LJGAP_OK);
    ljgap_opts o = mc_opts(2048);
    ljgap_summary s;
    ljgap_warnings w = {0};
    double t0 = ljgap__now();
    assert_int_equal(ljgap_traction(&psd, &o, NULL, 0, NULL, &s, &w), LJGAP_OK);
    print_warnings(&w);
    printf("  g_eq %.4f +- %.2g  sigma_max %.5f +- %.2g at %.3f +- %.2g  dgamma %.5f +- %.2g "
           "(%.1f s)\n",
           s.g_eq.value, s.g_eq.err, s.sigma_max.value, s.sigma_max.err, s.g_at_max.value,
           s.g_at_max.err, s.dgamma_eff.value, s.dgamma_eff.err, ljgap__now() - t0);
    /* theory.md §4 (Fig. 4, C = 1/(4π)) */
    assert_close(s.g_eq.value, 2.6028, 4 * s.g_eq.err);
    assert_close(s.sigma_max.value, 0.10126, 4 * s.sigma_max.err);
    assert_close(s.dgamma_eff.value, 0.20147, 4 * s.dgamma_eff.err);
    /* caps: the work cap reduces the samples with a warning */
    o.max_work = 100000L;
    ljgap_warnings w2 = {0};
    double g = 2.0;
    ljgap_est e;
    assert_int_equal(ljgap_traction(&psd, &o, &g, 1, &e, NULL, &w2), LJGAP_OK);
    assert_true(w2.n >= 1);
    print_warnings(&w2);
    o.max_work = 100;
    assert_int_equal(ljgap_traction(&psd, &o, &g, 1, &e, NULL, NULL), LJGAP_ECAP);
    volatile int cancel = 1;
    o.max_work = 400000000L;
    o.cancel = &cancel;
    assert_int_equal(ljgap_traction(&psd, &o, &g, 1, &e, NULL, NULL), LJGAP_ECANCEL);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tiny_m0),          cmocka_unit_test(test_thin_band),
        cmocka_unit_test(test_martingale),       cmocka_unit_test(test_step_bias),
        cmocka_unit_test(test_vs_paper_benign),  cmocka_unit_test(test_vs_paper_stiff),
        cmocka_unit_test(test_summary_and_caps),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
