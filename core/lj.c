/* lj.c -- the Lennard-Jones interface law and the gap transfer function.
 *
 * Dimensionless (theory.md §1): g = gap/epsilon, k = chi*wavenumber,
 * chi = 3 epsilon^2 Estar/(16 dgamma).
 *
 *   sigma/sigma0 = (3√3/2)(g^-3 - g^-9)                       (8),(9), tensile positive,
 *                  maximum 1 at g = 3^(1/6);
 *   ∫_1^∞ sigma/sigma0 dg = 9√3/16                            flat work of separation;
 *   f(g,k) = [1 + (9 g^-10 - 3 g^-4)/k]^-1                     (14);
 *   f has a pole where k < 3g^-4 - 9g^-10; the largest such k is
 *   k0 = (324/3125)^(1/3) at g* = (15/2)^(1/6)                 (19).
 *
 * The smoothed versions E[sigma(g+X)] (and E[sigma'(g+X)]), X ~ N(0,V), are used far from the wall,
 * where the gap transfer is f ≈ 1 and the mean traction is the Lennard-Jones law blurred by the
 * height variance. They use E[(g+X)^-p] = g^-p Σ_j C(p+2j-1, 2j) (2j-1)!! (V/g^2)^j,
 * an asymptotic series that is summed while its terms decrease.
 */
#include "ljgap.h"

#include <math.h>

#define LJ_A 2.598076211353315940 /* 3√3/2 */

double ljgap_sigma(double g)
{
    double g3 = 1.0 / (g * g * g);
    return LJ_A * (g3 - g3 * g3 * g3);
}

double ljgap_sigma_work(double g)
{
    double g2 = 1.0 / (g * g);
    double g8 = g2 * g2 * g2 * g2;
    return LJ_A * (0.5 * g2 - 0.125 * g8);
}

double ljgap_f(double g, double k)
{
    double g2 = g * g, g4 = g2 * g2, g10 = g4 * g4 * g2;
    return k / (k + 9.0 / g10 - 3.0 / g4);
}

double ljgap_k0(void)
{
    return cbrt(324.0 / 3125.0);
}

double ljgap_gstar(void)
{
    return pow(7.5, 1.0 / 6.0);
}

double ljgap_g_sigma_max(void)
{
    return pow(3.0, 1.0 / 6.0);
}

double ljgap_flat_work(void)
{
    return 9.0 * sqrt(3.0) / 16.0;
}

/* E[(g+X)^-p] g^p for X ~ N(0,V), x = V/g^2 <= 0.01. */
static double inv_power_moment(int p, double x)
{
    /* term_j = C(p+2j-1, 2j) (2j-1)!! x^j; ratio term_{j+1}/term_j =
     * (p+2j)(p+2j+1)/((2j+1)(2j+2)) * (2j+1) x = (p+2j)(p+2j+1) x/(2j+2) */
    double sum = 1.0, term = 1.0;
    for (int j = 0; j < 60; j++) {
        double next = term * (p + 2.0 * j) * (p + 2.0 * j + 1.0) * x / (2.0 * j + 2.0);
        if (fabs(next) >= fabs(term)) break; /* asymptotic series: stop at the smallest */
        sum += next;
        term = next;
        if (fabs(term) < 1e-17 * fabs(sum)) break;
    }
    return sum;
}

double ljgap_sigma_smoothed(double g, double V)
{
    if (!(g > 0) || !(V >= 0) || V > 0.01 * g * g) return NAN;
    double x = V / (g * g);
    double g3 = 1.0 / (g * g * g);
    return LJ_A * (g3 * inv_power_moment(3, x) - g3 * g3 * g3 * inv_power_moment(9, x));
}

double ljgap_dsigma_smoothed(double g, double V)
{
    if (!(g > 0) || !(V >= 0) || V > 0.01 * g * g) return NAN;
    double x = V / (g * g);
    double g2 = 1.0 / (g * g), g4 = g2 * g2, g10 = g4 * g4 * g2;
    return LJ_A * (9.0 * g10 * inv_power_moment(10, x) - 3.0 * g4 * inv_power_moment(4, x));
}

double ljgap_sigma_work_smoothed(double g, double V)
{
    if (!(g > 0) || !(V >= 0) || V > 0.01 * g * g) return NAN;
    double x = V / (g * g);
    double g2 = 1.0 / (g * g);
    double g8 = g2 * g2 * g2 * g2;
    return LJ_A * (0.5 * g2 * inv_power_moment(2, x) - 0.125 * g8 * inv_power_moment(8, x));
}
