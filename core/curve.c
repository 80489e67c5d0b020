/* curve.c -- from a mean traction curve to the adhesion summary (theory.md §1 "outputs").
 *
 * Given sigma_bar(g_ave)/sigma0 sampled on increasing gaps, the paper's Section 4 reads off:
 *   g_eq        the equilibrium mean gap, sigma_bar = 0, left of the tensile maximum;
 *   sigma_max   the largest mean traction (the pull-off traction), and g_at_max where it is;
 *   dgamma_eff  the work of separation from g_eq to infinity (the shaded area of Fig. 4),
 *               over the flat value 9√3/16.
 * The curve is interpolated by a cubic spline (fourth-order accurate on smooth data), the
 * root and the maximum are found on the spline (so neither is tied to a grid point), and
 * the area beyond the last sample is E[∫_{G+X}^∞ sigma] with X ~ N(0, m0_tail): far from
 * the wall the gap transfer is f ≈ 1 and the mean traction is the blurred L-J law.
 */
#include "ljgap.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>
#include <gsl/gsl_spline.h>
#include <math.h>

typedef struct {
    gsl_spline *sp;
    gsl_interp_accel *acc;
    int deriv;             /* 0: the curve, 1: its derivative, 2: derivative of the local poly */
    const double *px, *py; /* local polynomial: POLY_N nodes */
} spline_fn;

#define POLY_N 6 /* degree-5 local interpolation for the maximum */
/* The natural spline's end condition (u'' = 0) is wrong by O(h^2) at the window's first
 * node, and that error falls by 2 - √3 ≈ 0.27 per node inwards: 12 nodes put it below 1.5e-7
 * of its size at the root. With 4 it left a term that jumps with the root's place between
 * the nodes, ~6e-8 in g_eq of Fig. 4, which no refinement removes. */
#define SPLINE_LEAD 12

/* Derivative at x of the Lagrange polynomial through (px[a], py[a]), a < POLY_N. */
static double poly_deriv(const double *px, const double *py, double x)
{
    double d = 0;
    for (int a = 0; a < POLY_N; a++) {
        double den = 1, sum = 0;
        for (int b = 0; b < POLY_N; b++)
            if (b != a) den *= px[a] - px[b];
        for (int c = 0; c < POLY_N; c++) {
            if (c == a) continue;
            double prod = 1;
            for (int b = 0; b < POLY_N; b++)
                if (b != a && b != c) prod *= x - px[b];
            sum += prod;
        }
        d += py[a] * sum / den;
    }
    return d;
}

static double spline_eval(double x, void *p)
{
    spline_fn *s = p;
    if (s->deriv == 2) return poly_deriv(s->px, s->py, x);
    return s->deriv ? gsl_spline_eval_deriv(s->sp, x, s->acc) : gsl_spline_eval(s->sp, x, s->acc);
}

/* Root of fn in [a,b] (a sign change is known to be there). */
static double brent_root(spline_fn *s, double a, double b)
{
    gsl_function F = {spline_eval, s};
    gsl_root_fsolver *r = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
    if (!r) return NAN;
    double x = 0.5 * (a + b);
    if (gsl_root_fsolver_set(r, &F, a, b) == GSL_SUCCESS) {
        for (int it = 0; it < 200; it++) {
            if (gsl_root_fsolver_iterate(r) != GSL_SUCCESS) break;
            x = gsl_root_fsolver_root(r);
            double lo = gsl_root_fsolver_x_lower(r), hi = gsl_root_fsolver_x_upper(r);
            if (gsl_root_test_interval(lo, hi, 0, 1e-15) == GSL_SUCCESS) break;
        }
    }
    gsl_root_fsolver_free(r);
    return x;
}

int ljgap_curve_summary(const double *g, const double *u, size_t n, double m0_tail,
                        ljgap_summary *out, ljgap_warnings *w)
{
    out->m0 = m0_tail;
    out->k0 = ljgap_k0();
    out->g_eq = out->sigma_max = out->g_at_max = out->dgamma_eff = (ljgap_est){NAN, 0};
    if (n < 6) return LJGAP_EFAIL;
    /* the tensile maximum: the largest sample */
    size_t im = 0;
    for (size_t i = 1; i < n; i++)
        if (u[i] > u[im]) im = i;
    if (im == 0 || im == n - 1 || !(u[im] > 0)) {
        ljgap_warn(w, "the traction curve has no interior tensile maximum on [%g, %g]", g[0],
                   g[n - 1]);
        return LJGAP_EFAIL;
    }
    /* the sign change left of it */
    size_t j = im;
    while (j > 0 && u[j - 1] > 0)
        j--;
    if (j == 0) {
        ljgap_warn(w, "the traction curve does not become compressive above g = %g", g[0]);
        return LJGAP_EFAIL;
    }
    j--; /* u[j] <= 0 < u[j+1] */
    /* spline on a window that starts SPLINE_LEAD nodes left of the root, away from the
     * steep wall values */
    size_t s0 = j >= SPLINE_LEAD ? j - SPLINE_LEAD : 0;
    size_t m = n - s0;
    int st = LJGAP_EFAIL;
    spline_fn S = {gsl_spline_alloc(gsl_interp_cspline, m), gsl_interp_accel_alloc(), 0, NULL,
                   NULL};
    if (!S.sp || !S.acc || gsl_spline_init(S.sp, g + s0, u + s0, m) != GSL_SUCCESS) goto end;

    double geq = u[j] == 0 ? g[j] : brent_root(&S, g[j], g[j + 1]);
    /* maximum: zero of the derivative near the largest sample */
    double a = g[im - 1 >= s0 ? im - 1 : s0], b = g[im + 1];
    double gm = g[im];
    S.deriv = 1;
    double da = spline_eval(a, &S), db = spline_eval(b, &S);
    if (da > 0 && db < 0) gm = brent_root(&S, a, b);
    /* The spline's derivative is only third-order accurate between nodes; the location of a
     * flat maximum inherits that. A degree-5 polynomial through the six nearest nodes
     * makes it fifth order. */
    if (im >= 3 && im + 3 < n) {
        size_t p0 = gm < g[im] ? im - 3 : im - 2;
        S.px = g + p0;
        S.py = u + p0;
        S.deriv = 2;
        if (spline_eval(a, &S) > 0 && spline_eval(b, &S) < 0) gm = brent_root(&S, a, b);
    }
    S.deriv = 0;
    double smax = spline_eval(gm, &S);
    if (smax < u[im]) smax = u[im], gm = g[im];

    double G = g[n - 1];
    double area = gsl_spline_eval_integ(S.sp, geq, G, S.acc);
    double tail = ljgap_sigma_work_smoothed(G, m0_tail);
    if (!isfinite(tail)) {
        ljgap_warn(w,
                   "the curve ends at g = %g, too close for the analytic tail with m0 = %g; "
                   "the tail uses the g^-3 law",
                   G, m0_tail);
        tail = 0.5 * u[n - 1] * G;
    }
    out->g_eq.value = geq;
    out->sigma_max.value = smax;
    out->g_at_max.value = gm;
    out->dgamma_eff.value = (area + tail) / ljgap_flat_work();
    st = (isfinite(geq) && isfinite(smax) && isfinite(gm) && isfinite(out->dgamma_eff.value))
             ? LJGAP_OK
             : LJGAP_EFAIL;
end:
    gsl_spline_free(S.sp);
    gsl_interp_accel_free(S.acc);
    return st;
}
