/* curve.c -- from a mean traction curve to the adhesion summary (theory.md §1 "outputs").
 *
 * Given sigma_bar(g_ave)/sigma0 sampled on increasing gaps, the paper's Section 4 reads off:
 *   g_eq        the equilibrium mean gap, sigma_bar = 0, left of the tensile maximum;
 *   sigma_max   the largest mean traction (the pull-off traction), and g_at_max where it is;
 *   dgamma_eff  the work of separation from g_eq to infinity (the shaded area of Fig. 4),
 *               over the flat value 9√3/16.
 * The root and the maximum are found on a local interpolating polynomial of degree 9 (so
 * neither is tied to a grid point, and the interpolation error is far below the solvers'),
 * the area on a cubic spline (fourth-order accurate on smooth data) from the root to the last
 * sample, and beyond it as E[∫_{G+X}^∞ sigma] with X ~ N(0, m0_tail): far from the wall the gap
 * transfer is f ≈ 1 and the mean traction is the blurred L-J law.
 */
#include "ljgap.h"
#include "core.h" /* the core's internals */

#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>
#include <gsl/gsl_spline.h>
#include <math.h>

/* The natural spline's end condition (u'' = 0) is wrong by O(h^2) at the window's first
 * node, and that error falls by 2 - √3 ≈ 0.27 per node inwards: 12 nodes put it below 1.5e-7
 * of its size at the root. With 4 it left a term that jumps with the root's place between
 * the nodes, ~6e-8 in g_eq of Fig. 4, which no refinement removes. */
#define SPLINE_LEAD 12
/* Nodes of the local interpolant for the root and the maximum (degree LOCAL_N - 1). Its error
 * also jumps with the root's or maximum's place between the nodes, so it must stay far below
 * the solvers' discretisation error: with six nodes the location of a sharp maximum (m0 = 0.1)
 * was off by 1.8e-6 at the PDE's level 1, which Richardson extrapolation carried into its
 * level-2 value as 5e-7 (its estimate said 1.7e-7). With ten, the error falls by h^10. */
#define LOCAL_N 10

/* The polynomial through LOCAL_N consecutive samples, in Newton form. */
typedef struct {
    double x[LOCAL_N]; /* nodes */
    double c[LOCAL_N]; /* divided differences */
} local_poly;

/* The interpolant through the samples i0 .. i0 + LOCAL_N - 1, i0 clamped to the data. */
static void local_make(local_poly *P, const double *g, const double *u, size_t n, long i0)
{
    if (i0 > (long)n - LOCAL_N) i0 = (long)n - LOCAL_N;
    if (i0 < 0) i0 = 0;
    for (int a = 0; a < LOCAL_N; a++) {
        P->x[a] = g[i0 + a];
        P->c[a] = u[i0 + a];
    }
    for (int k = 1; k < LOCAL_N; k++)
        for (int a = LOCAL_N - 1; a >= k; a--)
            P->c[a] = (P->c[a] - P->c[a - 1]) / (P->x[a] - P->x[a - k]);
}

/* The interpolant's value (deriv 0) or derivative (deriv 1) at t. */
static double local_eval(const local_poly *P, double t, int deriv)
{
    double p = P->c[LOCAL_N - 1], dp = 0;
    for (int a = LOCAL_N - 2; a >= 0; a--) {
        dp = dp * (t - P->x[a]) + p;
        p = p * (t - P->x[a]) + P->c[a];
    }
    return deriv ? dp : p;
}

static double local_value(double t, void *p)
{
    return local_eval(p, t, 0);
}

static double local_slope(double t, void *p)
{
    return local_eval(p, t, 1);
}

static double spline_slope(double t, void *p)
{
    return gsl_spline_eval_deriv(p, t, NULL);
}

/* Root of F in [a,b] (a sign change is known to be there). */
static double brent_root(gsl_function F, double a, double b)
{
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

int ljgap__curve_summary(const double *g, const double *u, size_t n, double m0_tail,
                        ljgap_summary *out, ljgap_warnings *w)
{
    out->m0 = m0_tail;
    out->k0 = ljgap_k0();
    out->g_eq = out->sigma_max = out->g_at_max = out->dgamma_eff = (ljgap_est){NAN, 0};
    if (n < LOCAL_N) return LJGAP_EFAIL;
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
    /* the root: on the local interpolant through the nodes around [g_j, g_j+1] */
    local_poly P;
    local_make(&P, g, u, n, (long)j - LOCAL_N / 2 + 1);
    double geq = u[j] == 0 ? g[j] : brent_root((gsl_function){local_value, &P}, g[j], g[j + 1]);
    /* the maximum: zero of the local interpolant's derivative, with nodes centred on the side
     * of the largest sample where it lies (of the spline's if that has no sign change) */
    int st = LJGAP_EFAIL;
    size_t s0 = j >= SPLINE_LEAD ? j - SPLINE_LEAD : 0, m = n - s0;
    gsl_spline *sp = gsl_spline_alloc(gsl_interp_cspline, m);
    if (!sp || gsl_spline_init(sp, g + s0, u + s0, m) != GSL_SUCCESS) goto end;
    local_make(&P, g, u, n, (long)im - LOCAL_N / 2 + (u[im + 1] >= u[im - 1]));
    double a = g[im - 1], b = g[im + 1], gm = g[im];
    if (local_slope(a, &P) > 0 && local_slope(b, &P) < 0)
        gm = brent_root((gsl_function){local_slope, &P}, a, b);
    else if (a >= g[s0] && spline_slope(a, sp) > 0 && spline_slope(b, sp) < 0)
        gm = brent_root((gsl_function){spline_slope, sp}, a, b);
    double smax = local_value(gm, &P);
    if (smax < u[im]) smax = u[im], gm = g[im];

    double G = g[n - 1];
    /* the area: the spline's integral (its window starts SPLINE_LEAD nodes left of the root,
     * away from the steep wall values) */
    double area = gsl_spline_eval_integ(sp, geq, G, NULL);
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
    gsl_spline_free(sp);
    return st;
}
