/* test_sim.c -- the discrete numerical model (core/sim/sim.c, theory.md §5).
 *
 * Surface: the realized variance is the lattice sum m0_grid (match_m0 = 0) or m0 (match_m0 =
 * 1) to round-off, and m0_grid -> m0 as L grows. Solver: the residual target is met at every
 * gap, and tightening it moves sigma by no more than the error estimate says. Independent
 * checks: a flat surface gives the Lennard-Jones law sigma(g_ave) (compression included); small
 * roughness away from contact gives the statistical theory (PDE) within the combined error
 * plus the lattice's own second-order term; with 2*pi/L < k0 the flat state snaps (jump
 * flagged, the outward branch differs), with 2*pi/L > k0 never. Seeds, cancel, the time cap,
 * progress and bad inputs.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "check.h"
#include "ljgap_sim.h"
#include "simcheck.h"

#include <gsl/gsl_errno.h>
#include <string.h>

static void variance(void **state)
{
    ljgap_psd p = fig6_psd(0.218, 8.0);
    const double g = 3.0;
    for (int match = 0; match < 2; match++) {
        ljgap_sim_opts o = sim_opts(32, 3, 0.0);
        o.match_m0 = match;
        ljgap_sim_result r;
        assert_int_equal(run(&p, &o, &g, 1, &r), LJGAP_OK);
        double want = match ? p.m0 : r.m0_grid;
        for (int i = 0; i < 3; i++)
            assert_close(r.m0_realized[i], want, 1e-12 * want);
        assert_close(r.m0_target, p.m0, 0.0);
        ljgap_sim_result_free(&r);
    }
    /* the lattice sum converges to m0 as L resolves the band (a narrower band keeps n small) */
    ljgap_psd q = fig6_psd(0.1, 4.0);
    double prev = INFINITY;
    for (int m = 1; m <= 16; m *= 2) {
        ljgap_sim_opts o = sim_opts(8 * m, 1, 0.0);
        o.L = 2 * M_PI * m;
        ljgap_sim_result r;
        assert_int_equal(run(&q, &o, &g, 1, &r), LJGAP_OK);
        double dev = fabs(r.m0_grid / q.m0 - 1.0);
        assert_true(dev < prev);
        prev = dev;
        ljgap_sim_result_free(&r);
    }
    assert_true(prev < 0.03);
}

/* The residual target holds everywhere, and a 1e4 times tighter target moves sigma by no
 * more than the looser run's own error estimate (its residual part). */
static void residual_met(void **state)
{
    ljgap_psd p = fig6_psd(0.3, 8.0);
    double g[12];
    for (int i = 0; i < 12; i++)
        g[i] = 0.8 + 0.2 * i;
    ljgap_sim_result loose, tight;
    ljgap_sim_opts o = sim_opts(32, 1, 0.0);
    o.tol = 1e-5;
    assert_int_equal(run(&p, &o, g, 12, &loose), LJGAP_OK);
    o.tol = 1e-9;
    assert_int_equal(run(&p, &o, g, 12, &tight), LJGAP_OK);
    for (int i = 0; i < 12; i++) {
        assert_true(loose.residual[i] <= 1e-5);
        assert_true(tight.residual[i] <= 1e-9);
        assert_true(loose.sigma_err[i] > 0.0);
        assert_close(loose.sigma[i], tight.sigma[i], loose.sigma_err[i] + tight.sigma_err[i]);
    }
    ljgap_sim_result_free(&loose);
    ljgap_sim_result_free(&tight);
}

/* No roughness: every point sits at g_ave and the mean traction is the law itself. */
static void flat_is_lj(void **state)
{
    ljgap_psd p = fig6_psd(1e-14, 8.0);
    double g[8] = {3.0, 2.0, 1.5, 1.2, 1.1, 1.0, 0.9, 0.8};
    ljgap_sim_result r;
    ljgap_sim_opts o = sim_opts(16, 1, 0.0);
    assert_int_equal(run(&p, &o, g, 8, &r), LJGAP_OK);
    for (int i = 0; i < 8; i++) {
        double want = ljgap_sigma(g[i]);
        assert_close(r.sigma[i], want, 1e-9 * fmax(1.0, fabs(want)));
        assert_int_equal(r.jump[i], 0);
    }
    ljgap_sim_result_free(&r);
}

/* Small roughness away from contact: sigma = sigma(g) + ½σ''(g) Vg + O(m0²), where Vg is the
 * f²-weighted gap variance. The theory takes Vg over the continuum band (packet variance
 * (17)), the model over its lattice; the test forms the lattice sum itself and allows the
 * difference of the two second-order terms, the O(m0²) remainder, and both error estimates. */
static void small_roughness_vs_theory(void **state)
{
    const double m0 = 0.004, L = 8 * M_PI;
    ljgap_psd p = fig6_psd(m0, 8.0);
    double g[3] = {2.0, 2.5, 3.0};
    ljgap_sim_result r;
    ljgap_sim_opts o = sim_opts(64, 2, 0.0);
    o.L = L;
    assert_int_equal(run(&p, &o, g, 3, &r), LJGAP_OK);
    ljgap_opts to;
    ljgap_opts_default(&to);
    ljgap_est th[3];
    ljgap_warnings w = {0};
    assert_int_equal(ljgap_traction(&p, &to, g, 3, th, NULL, &w), LJGAP_OK);
    double dq = 2 * M_PI / L;
    for (int i = 0; i < 3; i++) {
        double vlat = 0.0, mgrid = 0.0;
        for (int a = -40; a <= 40; a++)
            for (int b = -40; b <= 40; b++) {
                double k = dq * hypot(a, b), P = ljgap_psd_eval(&p, k) * dq * dq;
                if (P > 0) vlat += P * pow(ljgap_f(g[i], k), 2), mgrid += P;
            }
        vlat *= m0 / mgrid;
        double vcon = ljgap_packet_var(&p, g[i], p.k1, p.k2);
        /* second and fourth derivatives of the law by central differences */
        double h = 1e-2, x = g[i], s0 = ljgap_sigma(x);
        double s1p = ljgap_sigma(x + h), s1m = ljgap_sigma(x - h);
        double s2p = ljgap_sigma(x + 2 * h), s2m = ljgap_sigma(x - 2 * h);
        double d2 = (s1p - 2 * s0 + s1m) / (h * h);
        double d4 = (s2p - 4 * s1p + 6 * s0 - 4 * s1m + s2m) / (h * h * h * h);
        double lattice = 0.5 * fabs(d2) * fabs(vlat - vcon);
        double quartic = 0.125 * fabs(d4) * 3 * vcon * vcon; /* the whole O(m0^2) term */
        double second = fabs(r.sigma[i] - s0);               /* size of the O(m0) effect */
        double tol = lattice + quartic + 2 * (r.sigma_err[i] + th[i].err);
        assert_close(r.sigma[i], th[i].value, tol);
        /* the check is not empty: the roughness effect is much larger than the tolerance */
        assert_true(second > 3 * tol);
    }
    ljgap_sim_result_free(&r);
}

static void seeds(void **state)
{
    ljgap_psd p = fig6_psd(0.218, 8.0);
    double g[2] = {1.5, 2.0};
    ljgap_sim_result a, b, c;
    ljgap_sim_opts o = sim_opts(16, 2, 0.0);
    assert_int_equal(run(&p, &o, g, 2, &a), LJGAP_OK);
    assert_int_equal(run(&p, &o, g, 2, &b), LJGAP_OK);
    o.seed = 7;
    assert_int_equal(run(&p, &o, g, 2, &c), LJGAP_OK);
    for (int i = 0; i < 2; i++) {
        assert_true(a.sigma[i] == b.sigma[i]);
        assert_true(fabs(a.sigma[i] - c.sigma[i]) > 1e-6);
    }
    ljgap_sim_result_free(&a);
    ljgap_sim_result_free(&b);
    ljgap_sim_result_free(&c);
}

/* One realization has no spread to estimate an error from: the answer says so. */
static void one_realization_warns(void **state)
{
    ljgap_psd p = fig6_psd(0.218, 8.0);
    double g = 2.0;
    ljgap_sim_result r;
    for (int R = 1; R <= 2; R++) {
        ljgap_sim_opts o = sim_opts(16, R, 0.0);
        ljgap_warnings w = {0};
        assert_int_equal(ljgap_sim_run(&p, &o, &g, 1, &r, &w), LJGAP_OK);
        int said = 0;
        for (int i = 0; i < w.n; i++)
            said |= strstr(w.msg[i], "one realization") != NULL;
        assert_int_equal(said, R == 1);
        assert_true(R == 1 ? r.sigma_std[0] == 0.0 : r.sigma_std[0] > 0.0);
        ljgap_sim_result_free(&r);
    }
}

/* 2*pi/L < k0: the flat state loses stability near g = 1.72 (where 3g^-4 - 9g^-10 = 2*pi/L),
 * the inward sweep jumps there and the outward branch differs; far from it both agree. With
 * the default L the energy is convex: no jump, one branch. */
static void hysteresis(void **state)
{
    ljgap_psd p;
    assert_int_equal(ljgap_psd_power(&p, 2.2, 1.0, 2.0, LJGAP_LEVEL_M0, 1e-4), LJGAP_OK);
    double g[17];
    for (int i = 0; i < 17; i++)
        g[i] = 2.2 - 0.075 * i; /* 2.2 .. 1.0 */
    ljgap_sim_result r;
    ljgap_sim_opts o = sim_opts(32, 1, 0.0);
    o.L = 20.0;
    assert_int_equal(run(&p, &o, g, 17, &r), LJGAP_OK);
    int jumps = 0, first = -1;
    double maxdiff = 0.0;
    for (int i = 0; i < 17; i++) {
        if (r.jump[i] && first < 0) first = i;
        jumps += r.jump[i];
        maxdiff = fmax(maxdiff, fabs(r.sigma[i] - r.sigma_out[i]));
    }
    assert_true(jumps > 0);
    assert_true(g[first] < 1.73 && g[first] > 1.6);
    assert_true(maxdiff > 1e-3);
    assert_close(r.sigma[0], r.sigma_out[0], 1e-9);
    assert_close(r.sigma[16], r.sigma_out[16], 1e-9);
    ljgap_sim_result_free(&r);
    o.L = 0.0;
    assert_int_equal(run(&p, &o, g, 17, &r), LJGAP_OK);
    for (int i = 0; i < 17; i++) {
        assert_int_equal(r.jump[i], 0);
        assert_true(r.sigma[i] == r.sigma_out[i]);
    }
    ljgap_sim_result_free(&r);
}

static void control(void **state)
{
    ljgap_psd p = fig6_psd(0.218, 8.0);
    double g[4] = {3.0, 2.0, 1.5, 1.0};
    ljgap_sim_result r;
    ljgap_warnings w = {0};
    ljgap_sim_opts o = sim_opts(16, 2, 0.0);
    prog_ctx pc = {0};
    o.progress = on_progress;
    o.progress_ctx = &pc;
    assert_int_equal(ljgap_sim_run(&p, &o, g, 4, &r, &w), LJGAP_OK);
    assert_int_equal(pc.calls, 8);
    assert_int_equal(pc.backwards, 0);
    assert_close(pc.last, 1.0, 1e-15);
    ljgap_sim_result_free(&r);
    /* cancelled from the progress callback, and before the start */
    volatile int cancel = 0;
    prog_ctx pc2 = {.cancel = &cancel};
    o.progress_ctx = &pc2;
    o.cancel = &cancel;
    assert_int_equal(ljgap_sim_run(&p, &o, g, 4, &r, &w), LJGAP_ECANCEL);
    assert_null(r.sigma);
    assert_int_equal(pc2.calls, 1);
    assert_int_equal(ljgap_sim_run(&p, &o, g, 4, &r, &w), LJGAP_ECANCEL);
    /* the time cap */
    o.cancel = NULL;
    o.progress = NULL;
    o.n = 64;
    o.max_seconds = 1e-6;
    assert_int_equal(ljgap_sim_run(&p, &o, g, 4, &r, &w), LJGAP_ECAP);
    assert_null(r.sigma);
    ljgap_sim_result_free(&r);
    ljgap_sim_result_free(NULL);
}

static void bad_inputs(void **state)
{
    ljgap_psd p = fig6_psd(0.218, 8.0), inf;
    assert_int_equal(ljgap_psd_power(&inf, 2.2, 1.0, INFINITY, LJGAP_LEVEL_M0, 0.2), LJGAP_OK);
    double g[2] = {1.5, 2.0}, bad_g[2] = {1.5, NAN};
    ljgap_sim_result r;
    struct {
        const char *what, *says;
        int field, value;
    } ints[] = {{"odd n", "n must be even", 0, 33},   {"small n", "n must be even", 0, 4},
                {"big n", "n must be even", 0, 1024}, {"R = 0", "realizations", 1, 0},
                {"R = 17", "realizations", 1, 17},    {"n too coarse", "n >= 16", 0, 8}};
    for (size_t i = 0; i < sizeof ints / sizeof ints[0]; i++) {
        ljgap_sim_opts o = sim_opts(32, 2, 0.0);
        *(ints[i].field == 0 ? &o.n : &o.realizations) = ints[i].value;
        ljgap_warnings w = {0};
        assert_int_equal(ljgap_sim_run(&p, &o, g, 2, &r, &w), LJGAP_EINVAL);
        assert_true(w.n >= 1);
        if (!strstr(w.msg[0], ints[i].says)) fail_msg("%s: %s", ints[i].what, w.msg[0]);
    }
    ljgap_sim_opts o = sim_opts(32, 2, 0.0);
    ljgap_warnings w = {0};
    assert_int_equal(ljgap_sim_run(&inf, &o, g, 2, &r, &w), LJGAP_EINVAL);
    assert_int_equal(ljgap_sim_run(NULL, &o, g, 2, &r, &w), LJGAP_EINVAL);
    assert_int_equal(ljgap_sim_run(&p, NULL, g, 2, &r, &w), LJGAP_EINVAL);
    assert_int_equal(ljgap_sim_run(&p, &o, g, 0, &r, &w), LJGAP_EINVAL);
    assert_int_equal(ljgap_sim_run(&p, &o, NULL, 2, &r, &w), LJGAP_EINVAL);
    assert_int_equal(ljgap_sim_run(&p, &o, bad_g, 2, &r, &w), LJGAP_EINVAL);
    assert_int_equal(ljgap_sim_run(&p, &o, g, LJGAP_SIM_GAPS_MAX + 1, &r, &w), LJGAP_EINVAL);
    assert_int_equal(ljgap_sim_run(&p, &o, g, 2, NULL, &w), LJGAP_EINVAL);
    o.L = 3.0; /* shorter than 2*pi/k1 */
    assert_int_equal(ljgap_sim_run(&p, &o, g, 2, &r, &w), LJGAP_EINVAL);
    o.L = 0.0;
    o.tol = 0.0;
    assert_int_equal(ljgap_sim_run(&p, &o, g, 2, &r, &w), LJGAP_EINVAL);
    o.tol = 1e-8;
    o.max_seconds = NAN;
    assert_int_equal(ljgap_sim_run(&p, &o, g, 2, &r, &w), LJGAP_EINVAL);
    assert_null(r.sigma);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(variance),   cmocka_unit_test(residual_met),
        cmocka_unit_test(flat_is_lj), cmocka_unit_test(small_roughness_vs_theory),
        cmocka_unit_test(seeds),      cmocka_unit_test(one_realization_warns),
        cmocka_unit_test(hysteresis), cmocka_unit_test(control),
        cmocka_unit_test(bad_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
