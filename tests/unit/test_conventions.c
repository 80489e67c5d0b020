/* test_conventions.c -- the PSD normalisation of docs/theory.md §7, checked numerically.
 *
 * ljgap's k is the angular wavenumber (2π/wavelength) and its isotropic PSD P obeys
 * ∫∫ P(|k|) d²k = 2π ∫ k P(k) dk = m0 = h_rms² (the paper's (22), Persson's C(q)). A power law
 * P = C k^(2D-8) on [k1, k2] is integrated here in each convention the documentation gives a
 * conversion for, by quadrature independent of the core's analytic variance, and each must give
 * the same h_rms²:
 *   - the 2-D wavevector plane itself, in Cartesian coordinates (not the radial formula);
 *   - SurfaceTopography / contact.engineering: the same angular q, C_ST(q) = (2π)² P(q), with
 *     (2π)^-2 ∫∫ C_ST d²q = h_rms²;
 *   - 1/λ wavenumbers f = k/2π: S(f) = (2π)² P(2πf) with ∫∫ S d²f = h_rms², and for the power
 *     law S = C_f f^(2D-8) with C_f = (2π)^(2D-6) C;
 *   - a random periodic surface of side L built from P on the lattice q = (2π/L)(i, j) (each
 *     wavevector the amplitude √P·2π/L and a random phase, as core/sim/sim.c does): its height
 *     variance, measured from the heights, is the lattice sum, which tends to m0 as L grows;
 *   - the dimensionless form P̃(k̃) = P(k)/(ε²χ²), k̃ = χk, for which m̃0 = m0/ε².
 * The tolerances are the quadratures' own error estimates (GSL) times 10, or the stated
 * discretisation bound.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "ljgap.h"
#include "ljgap_units.h"

#include <fftw3.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_integration.h>
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* The spectrum of the checks: D = 2.3, [k1, k2] = [2, 40] (1/m, say), C = 0.37. */
#define D_ 2.3
#define K1 2.0
#define K2 40.0
#define C_ 0.37

static double P(double k)
{
    return k >= K1 && k <= K2 ? C_ * pow(k, 2 * D_ - 8) : 0;
}

/* m0 from the core's analytic variance of the same power law. */
static double core_m0(void)
{
    ljgap_psd psd;
    assert_int_equal(ljgap_psd_power(&psd, D_, K1, K2, LJGAP_LEVEL_C, C_), LJGAP_OK);
    assert_true(fabs(ljgap_psd_eval(&psd, 7.0) - P(7.0)) <= 1e-14 * P(7.0));
    return psd.m0;
}

typedef double (*fn1)(double, void *);

/* ∫_a^b f by GSL's adaptive Gauss-Kronrod; *err its estimate. */
static double quad(fn1 f, void *p, double a, double b, double *err)
{
    gsl_integration_workspace *w = gsl_integration_workspace_alloc(1000);
    gsl_function F = {f, p};
    double v = 0;
    assert_non_null(w);
    assert_int_equal(gsl_integration_qag(&F, a, b, 0, 1e-12, 1000, GSL_INTEG_GAUSS61, w, &v, err),
                     GSL_SUCCESS);
    gsl_integration_workspace_free(w);
    return v;
}

static void near(double got, double want, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol))
        fail_msg("%s: %.17g, want %.17g (tolerance %.3g)", what, got, want, tol);
}

/* ---- ljgap's own convention: 2π ∫ k P dk ---- */

static double radial(double k, void *p)
{
    (void)p;
    return 2 * M_PI * k * P(k);
}

static void test_radial(void **state)
{
    double err, v = quad(radial, NULL, K1, K2, &err);
    (void)state;
    near(v, core_m0(), 10 * err + 1e-13, "2π∫kP dk against the core's m0");
}

/* ---- the wavevector plane in Cartesian coordinates: ∫∫ P(|k|) dkx dky ---- */

static double inner(double kx, void *q)
{
    double ky = *(double *)q;
    return P(hypot(kx, ky));
}

/* ∫ P(|k|) dkx over kx >= 0 at this ky: the annulus' part of the row. */
static double row(double ky, void *p)
{
    double err;
    double a = ky < K1 ? sqrt(K1 * K1 - ky * ky) : 0, b = sqrt(K2 * K2 - ky * ky);
    gsl_integration_workspace *w = gsl_integration_workspace_alloc(1000);
    gsl_function F = {inner, &ky};
    double v = 0;
    (void)p;
    assert_non_null(w);
    gsl_integration_qag(&F, a, b, 0, 1e-13, 1000, GSL_INTEG_GAUSS61, w, &v, &err);
    gsl_integration_workspace_free(w);
    return v;
}

static void test_plane(void **state)
{
    double err1, err2, v;
    (void)state;
    /* four quadrants alike; the rows split where the annulus' inner edge ends */
    v = 4 * (quad(row, NULL, 0, K1, &err1) + quad(row, NULL, K1, K2, &err2));
    near(v, core_m0(), 1e-8 * v, "∫∫P d²k over the plane against 2π∫kP dk");
}

/* ---- SurfaceTopography / contact.engineering: C_ST(q) = (2π)² P(q), same angular q ---- */

static double st(double q, void *p)
{
    (void)p;
    double C_ST = 4 * M_PI * M_PI * P(q);
    return 2 * M_PI * q * C_ST / (4 * M_PI * M_PI); /* (2π)^-2 ∫∫ C_ST d²q, radially */
}

static void test_surface_topography(void **state)
{
    double err, v = quad(st, NULL, K1, K2, &err);
    (void)state;
    near(v, core_m0(), 10 * err + 1e-13, "(2π)^-2 ∫∫ C_ST d²q");
}

/* ---- 1/λ wavenumbers: f = k/2π, S(f) = (2π)² P(2πf) ---- */

static double S(double f)
{
    return 4 * M_PI * M_PI * P(2 * M_PI * f);
}

static double freq(double f, void *p)
{
    (void)p;
    return 2 * M_PI * f * S(f); /* ∫∫ S d²f, radially */
}

static void test_inverse_wavelength(void **state)
{
    double err, v = quad(freq, NULL, K1 / (2 * M_PI), K2 / (2 * M_PI), &err);
    double Cf = pow(2 * M_PI, 2 * D_ - 6) * C_, f = 3.3;
    (void)state;
    near(v, core_m0(), 10 * err + 1e-13, "∫∫ S d²f with S(f) = (2π)² P(2πf)");
    near(S(f), Cf * pow(f, 2 * D_ - 8), 1e-14 * S(f), "S = C_f f^(2D-8), C_f = (2π)^(2D-6) C");
}

/* ---- a random periodic surface on the lattice q = (2π/L)(i, j) ---- */

/* The height variance measured from a realization of side L on n x n points, and the lattice
 * sum Σ P(|q|) (2π/L)² it must equal. */
static void surface(double L, int n, double *var, double *lattice)
{
    fftw_complex *c = fftw_alloc_complex((size_t)n * n);
    fftw_plan plan = fftw_plan_dft_2d(n, n, c, c, FFTW_BACKWARD, FFTW_ESTIMATE);
    gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
    double dq = 2 * M_PI / L, sum = 0, s2 = 0;
    assert_non_null(c);
    assert_non_null(rng);
    for (int i = 0; i < n * n; i++)
        c[i][0] = c[i][1] = 0;
    /* amplitudes √P(|q|) dq with random phases, Hermitian so that the heights are real */
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            int qi = i <= n / 2 ? i : i - n, qj = j <= n / 2 ? j : j - n;
            int mi = (n - i) % n, mj = (n - j) % n;
            double a = sqrt(P(dq * hypot(qi, qj))) * dq, ph;
            if (a == 0 || i * n + j > mi * n + mj || abs(qi) == n / 2 || abs(qj) == n / 2)
                continue; /* each pair once; no Nyquist lines (P is zero there below) */
            ph = 2 * M_PI * gsl_rng_uniform(rng);
            c[i * n + j][0] = a * cos(ph);
            c[i * n + j][1] = a * sin(ph);
            c[mi * n + mj][0] = a * cos(ph);
            c[mi * n + mj][1] = -a * sin(ph);
            sum += (i * n + j == mi * n + mj ? 1 : 2) * a * a;
        }
    fftw_execute(plan);
    for (int i = 0; i < n * n; i++)
        s2 += c[i][0] * c[i][0];
    *var = s2 / ((double)n * n);
    *lattice = sum;
    fftw_destroy_plan(plan);
    fftw_free(c);
    gsl_rng_free(rng);
}

static void test_surface(void **state)
{
    double m0 = core_m0(), var, lattice, prev = INFINITY;
    (void)state;
    /* the grid resolves k2: pi n / L > K2 */
    for (double L = 4 * M_PI; L <= 32 * M_PI; L *= 2) {
        int n = 2 * (int)ceil(K2 * L / (2 * M_PI)) + 4;
        surface(L, n, &var, &lattice);
        near(var, lattice, 1e-12 * lattice, "height variance of the realization = lattice sum");
        /* the lattice sum is a Riemann sum of ∫∫ P d²k: its error shrinks as L grows */
        assert_true(fabs(lattice - m0) < prev);
        prev = fabs(lattice - m0);
    }
    near(lattice, m0, 0.02 * m0, "lattice sum at L = 32π within 2 % of m0");
}

/* ---- the dimensionless form: P̃ = P/(ε²χ²) at k̃ = χk gives m̃0 = m0/ε² ---- */

static double dimless(double kt, void *p)
{
    const ljgap_material *m = p;
    double k = ljgap_units_k_to_si(m, kt);
    return 2 * M_PI * kt * ljgap_units_P_to_dimless(m, P(k));
}

static void test_dimensionless(void **state)
{
    ljgap_material m;
    double err, v;
    (void)state;
    /* a material for which K1..K2 (read as 1/m) lies at k̃ of order 1 */
    assert_int_equal(ljgap_material_set(&m, 1e9, 0.05, 0.4), LJGAP_OK);
    v = quad(dimless, &m, ljgap_units_k_to_dimless(&m, K1), ljgap_units_k_to_dimless(&m, K2), &err);
    near(v, ljgap_units_var_to_dimless(&m, core_m0()), 10 * err + 1e-13, "m̃0 = m0/ε²");
    near(ljgap_units_C_to_dimless(&m, C_, D_) * pow(ljgap_units_k_to_dimless(&m, 7.0), 2 * D_ - 8),
         ljgap_units_P_to_dimless(&m, P(7.0)), 1e-12 * ljgap_units_P_to_dimless(&m, P(7.0)),
         "C̃ k̃^(2D-8) = P̃");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_radial),
        cmocka_unit_test(test_plane),
        cmocka_unit_test(test_surface_topography),
        cmocka_unit_test(test_inverse_wavelength),
        cmocka_unit_test(test_surface),
        cmocka_unit_test(test_dimensionless),
    };
    gsl_set_error_handler_off();
    return cmocka_run_group_tests(tests, NULL, NULL);
}
