/* test_units.c -- physical units (theory.md §1) and the hybrid JKR contact model (§6).
 *
 * Conversions: SI -> dimensionless -> SI round trips to a few ulps, the PSD transform is
 * consistent with the power-law prefactor (P̃S(k̃) = PS(k̃/χ)/(ε²χ²)) and with the variance
 * (m̃0 = m0/ε²), and E* of two bodies. Contact: Maugis-Dugdale tends to JKR (1.5) as λ -> ∞
 * and to DMT (2) as λ -> 0 to 1e-3, decreases monotonically in between, and the forces of
 * ljgap_contact_compute follow their formulas, with λ = 1.16μ for the smooth law. The SI forms
 * of whole results (ljgap__si_*) give the numbers the server answered before they existed (the
 * handler then converted field by field): the Fig. 4 spectrum's adhesion, traction and PDF with
 * E* = 1 GPa, Δγ = 0.05 J/m², ε = 0.3 nm; errors scale with their values, and the PDF's L1
 * error of the density, a pure number, is unchanged.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "ljgap_units.h"

#include <float.h>
#include <gsl/gsl_errno.h>
#include <math.h>

static void near_rel(double got, double want, double rel, const char *what)
{
    if (!(fabs(got - want) <= rel * fabs(want)))
        fail_msg("%s: got %.17g, want %.17g within relative %.3g", what, got, want, rel);
}

/* A PDMS-like and a glass-like pair: E* ~ 1 MPa .. 50 GPa, Δγ ~ 50 mJ/m², ε = 0.3 nm. */
static const double mats[][3] = {{1e6, 0.05, 3e-10}, {5e10, 0.1, 2e-10}, {2e8, 1e-3, 5e-10}};

static void chi_sigma0_definitions(void **state)
{
    ljgap_material m;
    assert_int_equal(ljgap_material_set(&m, 1e9, 0.05, 3e-10), LJGAP_OK);
    near_rel(ljgap_units_chi(&m), 3 * 9e-20 * 1e9 / (16 * 0.05), 1e-15, "chi");
    near_rel(ljgap_units_sigma0(&m), 16 * 0.05 / (9 * sqrt(3) * 3e-10), 1e-15, "sigma0");
    /* the flat work of separation is Δγ: (9√3/16) σ0 ε */
    near_rel(ljgap_flat_work() * ljgap_units_sigma0(&m) * m.epsilon, m.dgamma, 1e-15, "work");
}

static void round_trips(void **state)
{
    const double rel = 4 * DBL_EPSILON;
    for (size_t i = 0; i < sizeof mats / sizeof mats[0]; i++) {
        ljgap_material m;
        assert_int_equal(ljgap_material_set(&m, mats[i][0], mats[i][1], mats[i][2]), LJGAP_OK);
        for (double x = 1e-12; x < 1e12; x *= 37.3) {
            near_rel(ljgap_units_k_to_si(&m, ljgap_units_k_to_dimless(&m, x)), x, rel, "k");
            near_rel(ljgap_units_P_to_si(&m, ljgap_units_P_to_dimless(&m, x)), x, rel, "P");
            near_rel(ljgap_units_len_to_si(&m, ljgap_units_len_to_dimless(&m, x)), x, rel, "g");
            near_rel(ljgap_units_var_to_si(&m, ljgap_units_var_to_dimless(&m, x)), x, rel, "m0");
            for (double D = 2.05; D < 3; D += 0.2)
                near_rel(ljgap_units_C_to_si(&m, ljgap_units_C_to_dimless(&m, x, D), D), x,
                         16 * DBL_EPSILON, "C");
        }
    }
}

/* C̃ must give the same PSD as converting PS pointwise, and the same variance. */
static void power_law_consistent(void **state)
{
    ljgap_material m;
    const double D = 2.3, C = 1e-30, k1 = 1e6, k2 = 1e9; /* SI: PS = C k^(2D-8) */
    ljgap_psd p;
    double chi, m0_si;
    assert_int_equal(ljgap_material_set(&m, 1e9, 0.05, 3e-10), LJGAP_OK);
    chi = ljgap_units_chi(&m);
    assert_int_equal(ljgap_psd_power(&p, D, k1 * chi, k2 * chi, LJGAP_LEVEL_C,
                                     ljgap_units_C_to_dimless(&m, C, D)),
                     LJGAP_OK);
    for (double k = k1; k <= k2; k *= 3.7)
        near_rel(ljgap_psd_eval(&p, ljgap_units_k_to_dimless(&m, k)),
                 ljgap_units_P_to_dimless(&m, C * pow(k, 2 * D - 8)), 1e-12, "P~");
    /* m0 = 2π∫k C k^(2D-8) dk in closed form */
    m0_si = 2 * M_PI * C * (pow(k2, 2 * D - 6) - pow(k1, 2 * D - 6)) / (2 * D - 6);
    near_rel(p.m0, ljgap_units_var_to_dimless(&m, m0_si), 1e-12, "m0");
    ljgap_psd_free(&p);
}

static void composite_modulus(void **state)
{
    double E;
    assert_int_equal(ljgap_units_E_star(2e9, 0.5, 2e9, 0.5, &E), LJGAP_OK);
    near_rel(E, 1e9 / 0.75, 1e-15, "E* equal bodies");
    assert_int_equal(ljgap_units_E_star(1e6, 0.5, 1e300, 0.3, &E), LJGAP_OK);
    near_rel(E, 1e6 / 0.75, 1e-12, "E* rigid counterface");
    E = -1;
    assert_int_equal(ljgap_units_E_star(0, 0.3, 1e9, 0.3, &E), LJGAP_EINVAL);
    assert_int_equal(ljgap_units_E_star(1e9, -1, 1e9, 0.3, &E), LJGAP_EINVAL);
    assert_int_equal(ljgap_units_E_star(1e9, 0.3, 1e9, 0.51, &E), LJGAP_EINVAL);
    assert_true(E == -1);
    assert_int_equal(ljgap_units_E_star(1e9, -0.99, 1e9, 0.5, &E), LJGAP_OK);
    ljgap_material m;
    assert_int_equal(ljgap_material_set(&m, 1e9, 0, 1e-10), LJGAP_EINVAL);
    assert_int_equal(ljgap_material_set(&m, 1e9, 0.1, -1e-10), LJGAP_EINVAL);
    assert_int_equal(ljgap_material_set(&m, INFINITY, 0.1, 1e-10), LJGAP_EINVAL);
}

/* Numbers of POST /v1/adhesion, /v1/traction and /v1/pdf with the material above, for the PSD
 * {"kind":"power","D":2.5,"k1":1,"m0":0.5}: the dimensionless answer in, its si object out. */
static void si_forms(void **state)
{
    const double rel = 2 * DBL_EPSILON;
    ljgap_material m;
    ljgap_si_scales sc;
    ljgap_si_summary ss;
    ljgap_summary sum = {{2.602798507198556, 5.96630730230933e-07},
                         {0.10126109828607611, 1.3493469705558971e-08},
                         {3.0591550788790745, 2.019459440130416e-06},
                         {0.2014985192758613, 3.3700599001793665e-08},
                         0.5,
                         0.4697841169402636};
    const double g[2] = {2, 3};
    const ljgap_est sigma[2] = {{-1.117185516572449, 1.3434712484027487e-07},
                                {0.1003680791475834, 2.1142970448440024e-07}};
    ljgap_si_point pt[2];
    double pg[3] = {0.6, 1.1, 1.6},
           pphi[3] = {-2.5076949299505563e-160, 0.578894102600608, 0.0695624929126073};
    double g_m[3], phi_m[3];
    ljgap_pdf pdf = {5, 3, pg, pphi, 1, 0.98, {-2.275523875019925, 5.026745078154477e-08}, 3e-9};
    ljgap_si_pdf sp = {.g_m = g_m, .phi_per_m = phi_m};

    assert_int_equal(ljgap_material_set(&m, 1e9, 0.05, 3e-10), LJGAP_OK);
    ljgap_si_scales_of(&m, &sc);
    near_rel(sc.chi_m, 3.375e-10, rel, "chi_m");
    near_rel(sc.sigma0_Pa, 171066746.4265558, rel, "sigma0_Pa");
    near_rel(sc.E_star_Pa, 1e9, 0, "E_star_Pa");

    ljgap_si_summary_of(&m, &sum, &ss);
    near_rel(ss.g_eq_m.value, 7.808395521595668e-10, rel, "g_eq_m");
    near_rel(ss.sigma_max_Pa.value, 17322406.623378728, rel, "sigma_max_Pa");
    near_rel(ss.g_at_max_m.value, 9.177465236637223e-10, rel, "g_at_max_m");
    near_rel(ss.dgamma_eff_J_m2.value, 0.010074925963793065, rel, "dgamma_eff_J_m2");
    near_rel(ss.m0_m2, 4.5e-20, rel, "m0_m2");
    near_rel(ss.g_eq_m.err, sum.g_eq.err * 3e-10, rel, "g_eq_m err");
    near_rel(ss.sigma_max_Pa.err, sum.sigma_max.err * sc.sigma0_Pa, rel, "sigma_max_Pa err");
    near_rel(ss.g_at_max_m.err, sum.g_at_max.err * 3e-10, rel, "g_at_max_m err");
    near_rel(ss.dgamma_eff_J_m2.err, sum.dgamma_eff.err * 0.05, rel, "dgamma_eff err");

    ljgap_si_points_of(&m, g, sigma, 2, pt);
    near_rel(pt[0].g_ave_m, 6e-10, rel, "g_ave_m[0]");
    near_rel(pt[1].g_ave_m, 9e-10, rel, "g_ave_m[1]");
    near_rel(pt[0].sigma_Pa.value, -191113291.4749199, rel, "sigma_Pa[0]");
    near_rel(pt[1].sigma_Pa.value, 17169640.744860135, rel, "sigma_Pa[1]");
    near_rel(pt[1].sigma_Pa.err, sigma[1].err * sc.sigma0_Pa, rel, "sigma_Pa[1] err");

    ljgap_si_pdf_of(&m, &pdf, &sp);
    near_rel(sp.k2_per_m, 14814814814.814816, rel, "k2_per_m");
    near_rel(g_m[0], 1.8e-10, rel, "g_m[0]");
    near_rel(g_m[2], 4.8e-10, rel, "g_m[2]");
    near_rel(phi_m[0], -8.35898309983519e-151, rel, "phi_per_m[0]");
    near_rel(phi_m[1], 1929647008.6686938, rel, "phi_per_m[1]");
    near_rel(phi_m[2], 231874976.37535763, rel, "phi_per_m[2]");
    near_rel(sp.sigma_Pa.value, -389266465.7156072, rel, "pdf sigma_Pa");
    near_rel(sp.sigma_Pa.err, pdf.sigma.err * sc.sigma0_Pa, rel, "pdf sigma_Pa err");
    near_rel(sp.phi_l1, pdf.phi_err, 0, "pdf phi_l1: the L1 norm has no unit");
    pdf.k2 = INFINITY; /* the whole PSD: the cut-off stays infinite (null in JSON) */
    ljgap_si_pdf_of(&m, &pdf, &sp);
    assert_true(isinf(sp.k2_per_m) && sp.k2_per_m > 0);
}

static void md_limits(void **state)
{
    ljgap_est P;
    assert_int_equal(ljgap_md_pulloff(1e4, &P), LJGAP_OK);
    near_rel(P.value, 1.5, 1e-3 / 1.5, "MD, lambda -> inf (JKR)");
    assert_int_equal(ljgap_md_pulloff(1e-4, &P), LJGAP_OK);
    near_rel(P.value, 2, 1e-3 / 2, "MD, lambda -> 0 (DMT)");
    assert_int_equal(ljgap_md_pulloff(0, &P), LJGAP_OK);
    near_rel(P.value, 2, 0, "MD, lambda = 0");
    assert_int_equal(ljgap_md_pulloff(-1, &P), LJGAP_EINVAL);
    assert_int_equal(ljgap_md_pulloff(NAN, &P), LJGAP_EINVAL);
}

/* Between the limits the pull-off falls from 2 to 1.5 as λ grows (Maugis 1992, Fig. 5),
 * passing ≈ 1.6-1.7 at λ = 1. */
static void md_monotone(void **state)
{
    double prev = 2.0 + 1e-12;
    for (double lam = 1e-3; lam < 1e3; lam *= 1.6) {
        ljgap_est P;
        assert_int_equal(ljgap_md_pulloff(lam, &P), LJGAP_OK);
        if (!(P.value <= prev + P.err && P.value >= 1.5 - 1e-9))
            fail_msg("lambda %.17g: P %.17g after %.17g", lam, P.value, prev);
        assert_true(P.err >= 0 && P.err < 1e-6);
        prev = P.value;
    }
    ljgap_est P1;
    assert_int_equal(ljgap_md_pulloff(1, &P1), LJGAP_OK);
    assert_true(P1.value > 1.55 && P1.value < 1.75);
}

static void contact_forces(void **state)
{
    ljgap_material m;
    ljgap_summary sum = {0};
    ljgap_contact c;
    const double R = 1e-6;
    assert_int_equal(ljgap_material_set(&m, 1e9, 0.05, 3e-10), LJGAP_OK);
    sum.dgamma_eff = (ljgap_est){0.5, 1e-4};
    sum.sigma_max = (ljgap_est){0.2, 1e-4};
    assert_int_equal(ljgap_contact_compute(&m, R, &sum, &c), LJGAP_OK);
    near_rel(c.jkr_smooth.value, 1.5 * M_PI * R * 0.05, 1e-15, "jkr_smooth");
    near_rel(c.jkr.value, 1.5 * M_PI * R * 0.025, 1e-15, "jkr");
    near_rel(c.dmt.value, 2 * M_PI * R * 0.025, 1e-15, "dmt");
    near_rel(c.jkr.err, 1.5 * M_PI * R * 0.05 * 1e-4, 1e-12, "jkr err");
    assert_true(c.md.value >= c.jkr.value && c.md.value <= c.dmt.value);
    assert_true(c.md.err > 0);
    /* smooth law (dgamma_eff = sigma_max = 1): λ = 1.16μ (Johnson-Greenwood) */
    sum.dgamma_eff = (ljgap_est){1, 0};
    sum.sigma_max = (ljgap_est){1, 0};
    assert_int_equal(ljgap_contact_compute(&m, R, &sum, &c), LJGAP_OK);
    near_rel(c.lambda.value / c.tabor_smooth, 1.156, 1e-3, "lambda/mu");
    near_rel(c.tabor_eff.value, c.tabor_smooth, 1e-15, "mu_eff = mu");
    assert_string_equal(ljgap_regime_name(c.regime), c.lambda.value > 5 ? "jkr" : "transition");
    assert_int_equal(ljgap_contact_compute(&m, 0, &sum, &c), LJGAP_EINVAL);
    sum.sigma_max.value = 0;
    assert_int_equal(ljgap_contact_compute(&m, R, &sum, &c), LJGAP_EINVAL);
}

static void regimes(void **state)
{
    ljgap_material m;
    ljgap_summary sum = {0};
    ljgap_contact c;
    sum.dgamma_eff = (ljgap_est){1, 0};
    sum.sigma_max = (ljgap_est){1, 0};
    /* stiff, small sphere: DMT; soft, large sphere: JKR */
    assert_int_equal(ljgap_material_set(&m, 1e11, 0.01, 2e-10), LJGAP_OK);
    assert_int_equal(ljgap_contact_compute(&m, 1e-9, &sum, &c), LJGAP_OK);
    assert_true(c.lambda.value < LJGAP_LAMBDA_DMT);
    assert_string_equal(ljgap_regime_name(c.regime), "dmt");
    assert_int_equal(ljgap_material_set(&m, 1e6, 0.05, 3e-10), LJGAP_OK);
    assert_int_equal(ljgap_contact_compute(&m, 1e-3, &sum, &c), LJGAP_OK);
    assert_true(c.lambda.value > LJGAP_LAMBDA_JKR);
    assert_string_equal(ljgap_regime_name(c.regime), "jkr");
    near_rel(c.md.value, c.jkr.value, 0.02, "JKR regime: MD near JKR");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(chi_sigma0_definitions),
        cmocka_unit_test(round_trips),
        cmocka_unit_test(power_law_consistent),
        cmocka_unit_test(composite_modulus),
        cmocka_unit_test(si_forms),
        cmocka_unit_test(md_limits),
        cmocka_unit_test(md_monotone),
        cmocka_unit_test(contact_forces),
        cmocka_unit_test(regimes),
    };
    gsl_set_error_handler_off();
    return cmocka_run_group_tests(tests, NULL, NULL);
}
