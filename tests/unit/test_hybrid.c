/* test_hybrid.c -- the hybrid model (core/sim/sim.c with opts.k_split, core/sim/simlaw.c) and the runs'
 * threads.
 *
 * The fine band's tabulated law against the PDE at points between its nodes, within the
 * law's own error estimate; its derivative and potential against differences of its values.
 * Both limits: k_split = k1 is the theory alone (a flat grid at every mean gap: ljgap_traction
 * of the whole PSD, also with k2 = ∞), k_split >= k2 the plain model to the last bit.
 * Validation at a small size: the Fig. 6 spectrum at m0 = 0.1 with k_split = 3 on a 32-point
 * grid meets the 128-point full model within 0.05 sigma0 where the theory alone is 0.1 off.
 * Threads: the same numbers with 1, 2 and 3 threads, progress counted over all of them. Bad
 * inputs.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "check.h"
#include "ljgap_sim.h"
#include "simcheck.h"
#include "simlaw.h"

#include <gsl/gsl_errno.h>
#include <string.h>

static void theory(const ljgap_psd *p, const double *g, size_t n, ljgap_est *out,
                   ljgap_summary *sum)
{
    ljgap_opts o;
    ljgap_opts_default(&o);
    ljgap_warnings w = {0};
    assert_int_equal(ljgap_traction(p, &o, g, n, out, sum, &w), LJGAP_OK);
}

/* The law of the band (3, 8] between its nodes, against the PDE itself; its slope and
 * potential against differences; the same band given as a table gives the same law. */
static void law_matches_pde(void **state)
{
    ljgap_psd p = fig6_psd(0.1, 8.0), fine, tab;
    assert_int_equal(ljgap_psd_above(&fine, &p, 3.0), LJGAP_OK);
    assert_close(fine.m0, ljgap_psd_var(&p, 3.0, 8.0), 1e-15);
    ljgap_opts o;
    ljgap_opts_default(&o);
    ljgap_warnings w = {0};
    sim_law law;
    assert_int_equal(sim_law_fine(&law, &fine, &o, &w), LJGAP_OK);
    enum { M = 300 };
    double g[M];
    ljgap_est pde[M];
    for (int i = 0; i < M; i++) /* never on a node: nodes are uniform in ln g */
        g[i] = 0.46 * pow(7.9 / 0.46, (i + 0.37) / M);
    theory(&fine, g, M, pde, NULL);
    double worst = 0.0;
    for (int i = 0; i < M; i++) {
        double s, ds, sp, sm, d;
        sim_law_eval(&law, g[i], &s, &ds, NULL);
        double e = sim_law_err(&law, g[i]);
        assert_true(e > 0.0);
        assert_close(s, pde[i].value, e + pde[i].err);
        worst = fmax(worst, fabs(s - pde[i].value) / fmax(1.0, fabs(s)));
        double h = 1e-5 * g[i];
        sim_law_eval(&law, g[i] + h, &sp, &d, NULL);
        sim_law_eval(&law, g[i] - h, &sm, &d, NULL);
        assert_close(ds, (sp - sm) / (2 * h), 1e-6 * fmax(1.0, fabs(ds)));
        double dw = -(sim_law_work(&law, g[i] + h) - sim_law_work(&law, g[i] - h)) / (2 * h);
        assert_close(dw, s, 1e-6 * fmax(1.0, fabs(s)));
    }
    assert_true(worst < 1e-5);
    /* the fine band changes the law (the check is not empty) */
    double s, ds;
    sim_law_eval(&law, 1.1, &s, &ds, NULL);
    assert_true(fabs(s - ljgap_sigma(1.1)) > 0.1);
    /* continuous where the table hands over to the far field */
    double a, b, da, db;
    sim_law_eval(&law, law.g_hi * (1 - 1e-12), &a, &da, NULL);
    sim_law_eval(&law, law.g_hi * (1 + 1e-12), &b, &db, NULL);
    assert_close(a, b, law.e_hi + 1e-12);
    assert_close(sim_law_work(&law, law.g_hi * (1 - 1e-12)),
                 sim_law_work(&law, law.g_hi * (1 + 1e-12)), 1e-12);
    assert_true(law.s_min < 0.0 && law.s_min > -2.598076211353316 * ljgap_k0());
    /* the band as a table (a power law is exact under log-log interpolation) */
    double k[3] = {1.0, 2.5, 8.0}, P[3];
    for (int i = 0; i < 3; i++)
        P[i] = ljgap_psd_eval(&p, k[i]);
    ljgap_psd t;
    assert_int_equal(ljgap_psd_table(&t, k, P, 3, 0, 0.0), LJGAP_OK);
    assert_int_equal(ljgap_psd_above(&tab, &t, 3.0), LJGAP_OK);
    assert_close(tab.m0, fine.m0, 1e-12 * fine.m0);
    assert_close(tab.k1, 3.0, 0.0);
    sim_law lt;
    assert_int_equal(sim_law_fine(&lt, &tab, &o, &w), LJGAP_OK);
    for (int i = 0; i < M; i += 7) {
        double x, y, dx;
        sim_law_eval(&law, g[i], &x, &dx, NULL);
        sim_law_eval(&lt, g[i], &y, &dx, NULL);
        assert_close(x, y, sim_law_err(&law, g[i]) + sim_law_err(&lt, g[i]));
    }
    sim_law_free(&lt);
    sim_law_free(&law);
    sim_law_free(NULL);
    ljgap_psd_free(&tab);
    ljgap_psd_free(&t);
}

/* k_split = k1: nothing on the grid, every point at the mean gap: the theory of the whole PSD
 * (finite and infinite k2), with the law's error estimate. */
static void theory_alone(void **state)
{
    double g[5] = {1.0, 1.2, 1.5, 2.0, 3.0};
    for (int inf = 0; inf < 2; inf++) {
        ljgap_psd p = fig6_psd(0.218, inf ? INFINITY : 8.0);
        ljgap_est th[5];
        ljgap_summary sum;
        theory(&p, g, 5, th, &sum);
        ljgap_sim_result r;
        ljgap_sim_opts o = sim_opts(8, 2, 1.0);
        assert_int_equal(run(&p, &o, g, 5, &r), LJGAP_OK);
        for (int i = 0; i < 5; i++) {
            assert_true(r.sigma_err[i] > 0.0);
            assert_close(r.sigma[i], th[i].value, r.sigma_err[i] + th[i].err);
            assert_true(r.sigma_std[i] == 0.0);
        }
        assert_true(r.m0_realized[0] == 0.0 && r.m0_grid == 0.0);
        assert_close(r.m0_fine, p.m0, 1e-15);
        assert_close(r.k_split, 1.0, 0.0);
        assert_close(r.fine.g_eq.value, sum.g_eq.value, r.fine.g_eq.err + sum.g_eq.err);
        assert_close(r.fine.dgamma_eff.value, sum.dgamma_eff.value,
                     r.fine.dgamma_eff.err + sum.dgamma_eff.err);
        assert_close(r.fine.sigma_max.value, sum.sigma_max.value,
                     r.fine.sigma_max.err + sum.sigma_max.err);
        assert_close(r.m0_fine, r.fine.m0, 1e-12 * p.m0);
        assert_true(r.law_err > 0.0);
        ljgap_sim_result_free(&r);
    }
}

/* k_split >= k2: no fine band; the plain model to the last bit, and the fine law is the
 * Lennard-Jones law's own (g_eq 1, sigma_max 1, dgamma_eff 1). */
static void plain_limit(void **state)
{
    ljgap_psd p = fig6_psd(0.218, 8.0);
    double g[4] = {1.1, 1.5, 2.0, 3.0};
    ljgap_sim_result plain, hyb;
    ljgap_sim_opts o = sim_opts(32, 2, 0.0);
    assert_int_equal(run(&p, &o, g, 4, &plain), LJGAP_OK);
    for (int k = 0; k < 2; k++) {
        o.k_split = k ? 20.0 : 8.0;
        assert_int_equal(run(&p, &o, g, 4, &hyb), LJGAP_OK);
        assert_memory_equal(plain.sigma, hyb.sigma, sizeof g);
        assert_memory_equal(plain.sigma_err, hyb.sigma_err, sizeof g);
        assert_memory_equal(plain.m0_realized, hyb.m0_realized, 2 * sizeof(double));
        assert_true(hyb.m0_fine == 0.0 && hyb.law_err == 0.0 && hyb.k_split == o.k_split);
        assert_true(hyb.fine.g_eq.value == 1.0 && hyb.fine.sigma_max.value == 1.0 &&
                    hyb.fine.dgamma_eff.value == 1.0);
        ljgap_sim_result_free(&hyb);
    }
    ljgap_sim_result_free(&plain);
}

/* The Fig. 6 spectrum at m0 = 0.1, k_split = 3: a 32-point hybrid against the 128-point full
 * model, both on the raw lattice (match_m0 = 0: with matching, the full model scales its fine
 * waves with its coarse ones, see the README), the same coarse surfaces (common seeds). */
static void validation_small(void **state)
{
    ljgap_psd p = fig6_psd(0.1, 8.0);
    double g[10] = {0.9, 1.0, 1.1, 1.2, 1.4, 1.6, 1.8, 2.0, 2.5, 3.0};
    ljgap_sim_result full, hyb;
    ljgap_sim_opts o = sim_opts(128, 4, 0.0);
    o.match_m0 = 0;
    o.threads = 2;
    assert_int_equal(run(&p, &o, g, 10, &full), LJGAP_OK);
    o.n = 32;
    o.k_split = 3.0;
    assert_int_equal(run(&p, &o, g, 10, &hyb), LJGAP_OK);
    ljgap_est th[10];
    theory(&p, g, 10, th, NULL);
    double dh = 0.0, dt = 0.0;
    for (int i = 0; i < 10; i++) {
        dh = fmax(dh, fabs(hyb.sigma[i] - full.sigma[i]));
        dt = fmax(dt, fabs(th[i].value - full.sigma[i]));
    }
    if (!(dh <= 0.05 && dt >= 0.1 && dh < 0.3 * dt))
        fail_msg("max |hybrid - full| = %.4f, max |theory - full| = %.4f", dh, dt);
    ljgap_sim_result_free(&full);
    ljgap_sim_result_free(&hyb);
}

/* 1, 2 and 3 threads (3 realizations): the same numbers, the progress of all of them. */
static void threads_same(void **state)
{
    ljgap_psd p = fig6_psd(0.218, 8.0);
    double g[3] = {3.0, 1.5, 1.1};
    for (int hybrid = 0; hybrid < 2; hybrid++) {
        ljgap_sim_result r[3];
        for (int t = 0; t < 3; t++) {
            ljgap_sim_opts o = sim_opts(32, 3, hybrid ? 4.0 : 0.0);
            prog_ctx pc = {0};
            o.threads = t + 1;
            o.progress = on_progress;
            o.progress_ctx = &pc;
            assert_int_equal(run(&p, &o, g, 3, &r[t]), LJGAP_OK);
            assert_int_equal(pc.calls, 9);
            assert_int_equal(pc.backwards, 0);
            assert_close(pc.last, 1.0, 1e-15);
        }
        for (int t = 1; t < 3; t++) {
            assert_memory_equal(r[0].sigma_each, r[t].sigma_each, 9 * sizeof(double));
            assert_memory_equal(r[0].sigma_err, r[t].sigma_err, 3 * sizeof(double));
            assert_memory_equal(r[0].m0_realized, r[t].m0_realized, 3 * sizeof(double));
        }
        /* the realizations differ, and each is one of the mean's terms */
        assert_true(r[0].sigma_each[1] != r[0].sigma_each[4]);
        assert_close(r[0].sigma[1],
                     (r[0].sigma_each[1] + r[0].sigma_each[4] + r[0].sigma_each[7]) / 3, 1e-15);
        for (int t = 0; t < 3; t++)
            ljgap_sim_result_free(&r[t]);
    }
}

static void expect_einval(const ljgap_psd *p, const ljgap_sim_opts *o, const char *says)
{
    double g[2] = {1.5, 2.0};
    ljgap_sim_result r;
    ljgap_warnings w = {0};
    assert_int_equal(ljgap_sim_run(p, o, g, 2, &r, &w), LJGAP_EINVAL);
    assert_null(r.sigma);
    assert_true(w.n >= 1);
    if (!strstr(w.msg[0], says)) fail_msg("expected \"%s\" in: %s", says, w.msg[0]);
}

static void hybrid_inputs(void **state)
{
    ljgap_psd p = fig6_psd(0.218, 8.0), inf = fig6_psd(0.218, INFINITY), low;
    assert_int_equal(ljgap_psd_power(&low, 2.2, 0.3, 8.0, LJGAP_LEVEL_M0, 0.218), LJGAP_OK);
    ljgap_sim_opts o = sim_opts(16, 2, 0.5); /* below k1 */
    expect_einval(&p, &o, "k_split");
    o.k_split = NAN;
    expect_einval(&p, &o, "k_split");
    o.k_split = 5.0; /* the grid's Nyquist wavenumber is 8 */
    o.n = 8;
    expect_einval(&p, &o, "k_split = 5");
    o.n = 16;
    o.k_split = 0.0;
    expect_einval(&inf, &o, "band-limited"); /* the plain model needs a finite k2 */
    o.k_split = 0.4;
    expect_einval(&low, &o, "k0"); /* the law of (0.4, 8] needs k_split > k0 */
    o.k_split = 2.0;
    o.law_tol = 0.0;
    expect_einval(&p, &o, "law_tol");
    o.law_tol = 1e-6;
    o.threads = 0;
    expect_einval(&p, &o, "threads");
    o.threads = LJGAP_SIM_THREADS_MAX + 1;
    expect_einval(&p, &o, "threads");
    /* an infinite k2 is fine for the hybrid: the grid carries [1, 2] */
    o.threads = 2;
    double g[2] = {1.5, 3.0};
    ljgap_sim_result r;
    assert_int_equal(run(&inf, &o, g, 2, &r), LJGAP_OK);
    assert_close(r.m0_realized[0], ljgap_psd_cumvar(&inf, 2.0), 1e-12);
    assert_close(r.m0_fine, inf.m0 - ljgap_psd_cumvar(&inf, 2.0), 1e-12);
    assert_true(r.sigma[1] > 0.0 && r.sigma[1] < ljgap_sigma(3.0) * 1.5);
    ljgap_sim_result_free(&r);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(law_matches_pde), cmocka_unit_test(theory_alone),
        cmocka_unit_test(plain_limit),     cmocka_unit_test(validation_small),
        cmocka_unit_test(threads_same),    cmocka_unit_test(hybrid_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
