/* units.c -- SI <-> the dimensionless units of theory.md §1.
 *
 * The Lennard-Jones length ε and the elastic length χ = 3ε²E* /(16Δγ) are the units of gaps
 * and of wavelengths; σ0 = 16Δγ/(9√3ε) of (9) is the unit of traction, so that the flat work
 * of separation ∫σ dg = Δγ becomes 9√3/16 in units of σ0ε. The PSD transforms as a density
 * of a squared length over a 2-D wavevector: P̃S(k̃) = PS(k)/(ε²χ²). For the power law (6),
 * PS = C k^(2D-8) on [k1,k2] in SI, P̃S(k̃) = PS(k̃/χ)/(ε²χ²) gives C̃ = C χ^(6-2D)/ε², and
 * the variance m0 = 2π∫k PS dk (22) becomes m̃0 = m0/ε², so h_rms = √m0 is in units of ε.
 * Composite moduli: 1/E* = (1-ν1²)/E1 + (1-ν2²)/E2 (theory.md §6).
 *
 * The SI forms of whole results (ljgap__si_*: a summary, traction points, a PDF) are built here
 * from those conversions, so an answer's SI numbers come from one place: gaps x ε, tractions
 * x σ0, energies x Δγ (Δγeff is in units of Δγ), variances x ε², wavenumbers / χ, densities
 * of the gap / ε; an error converts with its value (a density's L1 error ∫|δΦ|dg is a pure
 * number and stays as it is).
 *
 * Pure arithmetic: no allocation, no JSON, no state.
 */
#include "ljgap_units.h"

#include <math.h>

int ljgap_units_E_star(double E1, double nu1, double E2, double nu2, double *E_star)
{
    double inv;
    if (!(E1 > 0 && E2 > 0 && isfinite(E1) && isfinite(E2))) return LJGAP_EINVAL;
    if (!(nu1 > -1 && nu1 <= 0.5 && nu2 > -1 && nu2 <= 0.5)) return LJGAP_EINVAL;
    inv = (1 - nu1 * nu1) / E1 + (1 - nu2 * nu2) / E2;
    if (!(inv > 0 && isfinite(1 / inv))) return LJGAP_EINVAL;
    *E_star = 1 / inv;
    return LJGAP_OK;
}

int ljgap_material_set(ljgap_material *m, double E_star, double dgamma, double epsilon)
{
    if (!(E_star > 0 && dgamma > 0 && epsilon > 0)) return LJGAP_EINVAL;
    if (!(isfinite(E_star) && isfinite(dgamma) && isfinite(epsilon))) return LJGAP_EINVAL;
    m->E_star = E_star;
    m->dgamma = dgamma;
    m->epsilon = epsilon;
    return LJGAP_OK;
}

double ljgap_units_chi(const ljgap_material *m)
{
    return 3 * m->epsilon * m->epsilon * m->E_star / (16 * m->dgamma);
}

double ljgap_units_sigma0(const ljgap_material *m)
{
    return 16 * m->dgamma / (9 * sqrt(3.0) * m->epsilon);
}

double ljgap_units_k_to_dimless(const ljgap_material *m, double k)
{
    return k * ljgap_units_chi(m);
}

double ljgap_units_k_to_si(const ljgap_material *m, double kt)
{
    return kt / ljgap_units_chi(m);
}

double ljgap_units_P_to_dimless(const ljgap_material *m, double P)
{
    double chi = ljgap_units_chi(m);
    return P / (m->epsilon * m->epsilon * chi * chi);
}

double ljgap_units_P_to_si(const ljgap_material *m, double Pt)
{
    double chi = ljgap_units_chi(m);
    return Pt * (m->epsilon * m->epsilon * chi * chi);
}

double ljgap_units_C_to_dimless(const ljgap_material *m, double C, double D)
{
    return C * pow(ljgap_units_chi(m), 6 - 2 * D) / (m->epsilon * m->epsilon);
}

double ljgap_units_C_to_si(const ljgap_material *m, double Ct, double D)
{
    return Ct * (m->epsilon * m->epsilon) / pow(ljgap_units_chi(m), 6 - 2 * D);
}

double ljgap_units_len_to_dimless(const ljgap_material *m, double x)
{
    return x / m->epsilon;
}

double ljgap_units_len_to_si(const ljgap_material *m, double xt)
{
    return xt * m->epsilon;
}

double ljgap_units_var_to_dimless(const ljgap_material *m, double v)
{
    return v / (m->epsilon * m->epsilon);
}

double ljgap_units_var_to_si(const ljgap_material *m, double vt)
{
    return vt * (m->epsilon * m->epsilon);
}

/* An estimate times a positive scale. */
static ljgap_est est_scaled(ljgap_est e, double f)
{
    return (ljgap_est){e.value * f, e.err * f};
}

void ljgap_si_scales_of(const ljgap_material *m, ljgap_si_scales *out)
{
    out->chi_m = ljgap_units_chi(m);
    out->sigma0_Pa = ljgap_units_sigma0(m);
    out->E_star_Pa = m->E_star;
}

void ljgap_si_summary_of(const ljgap_material *m, const ljgap_summary *s, ljgap_si_summary *out)
{
    double s0 = ljgap_units_sigma0(m);
    out->g_eq_m = est_scaled(s->g_eq, m->epsilon);
    out->sigma_max_Pa = est_scaled(s->sigma_max, s0);
    out->g_at_max_m = est_scaled(s->g_at_max, m->epsilon);
    out->dgamma_eff_J_m2 = est_scaled(s->dgamma_eff, m->dgamma);
    out->m0_m2 = ljgap_units_var_to_si(m, s->m0);
}

void ljgap_si_points_of(const ljgap_material *m, const double *g_ave, const ljgap_est *sigma,
                        size_t n, ljgap_si_point *out)
{
    double s0 = ljgap_units_sigma0(m);
    for (size_t i = 0; i < n; i++) {
        out[i].g_ave_m = ljgap_units_len_to_si(m, g_ave[i]);
        out[i].sigma_Pa = est_scaled(sigma[i], s0);
    }
}

void ljgap_si_pdf_of(const ljgap_material *m, const ljgap_pdf *p, ljgap_si_pdf *out)
{
    out->k2_per_m = isinf(p->k2) ? p->k2 : ljgap_units_k_to_si(m, p->k2);
    for (size_t k = 0; k < p->n; k++) {
        out->g_m[k] = ljgap_units_len_to_si(m, p->g[k]);
        out->phi_per_m[k] = p->phi[k] / m->epsilon;
    }
    out->phi_l1 = p->phi_err; /* (1/ε) x ε: the L1 norm over the gap has no unit */
    out->sigma_Pa = est_scaled(p->sigma, ljgap_units_sigma0(m));
}
