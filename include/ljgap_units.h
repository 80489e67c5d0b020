/* ljgap_units.h -- physical units and the hybrid JKR contact model (theory.md §1 and §6).
 *
 * The core works in the dimensionless units of theory.md §1. A material (effective modulus
 * E*, flat-surface work of adhesion Δγ, Lennard-Jones length ε) fixes the scales:
 *   χ = 3ε²E* /(16Δγ)   (length, m)         k̃ = χk,  g̃ = g/ε
 *   σ0 = 16Δγ/(9√3ε)   (stress, Pa, eq. 9)  P̃S(k̃) = PS(k)/(ε²χ²)
 * PSD convention: k is the angular wavenumber (2π/wavelength, rad/m) and the isotropic 2-D PSD
 * is normalised so that ∫∫PS d²k = 2π∫k PS(k) dk = m0 = h_rms² ((22); Persson's C(q)).
 * SurfaceTopography/contact.engineering's C(q) at the same q is (2π)² PS; tools on 1/λ
 * wavenumbers f = k/2π with ∫∫S d²f = h_rms² have S(f) = (2π)² PS(2πf) (docs/theory.md §7;
 * docs/topography.md for height maps).
 * Conversion functions are pure arithmetic; they know nothing of JSON.
 */
#ifndef LJGAP_UNITS_H
#define LJGAP_UNITS_H

#include "ljgap.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A material in SI units. */
typedef struct {
    double E_star;  /* effective modulus E* (Pa), > 0 */
    double dgamma;  /* flat-surface work of adhesion Δγ (J/m²), > 0 */
    double epsilon; /* Lennard-Jones length ε (m), > 0 */
} ljgap_material;

/* E* of two elastic half-spaces: 1/E* = (1-ν1²)/E1 + (1-ν2²)/E2. Returns LJGAP_EINVAL
 * (*E_star untouched) unless E1, E2 > 0 and ν1, ν2 lie in (-1, 0.5]. */
int ljgap_units_E_star(double E1, double nu1, double E2, double nu2, double *E_star);
/* Fills m; LJGAP_EINVAL unless every value is finite and > 0. */
int ljgap_material_set(ljgap_material *m, double E_star, double dgamma, double epsilon);

double ljgap_units_chi(const ljgap_material *m);    /* χ = 3ε²E* /(16Δγ), m */
double ljgap_units_sigma0(const ljgap_material *m); /* σ0 = 16Δγ/(9√3ε), Pa */

/* Wavenumber (1/m) <-> k̃ = χk. */
double ljgap_units_k_to_dimless(const ljgap_material *m, double k);
double ljgap_units_k_to_si(const ljgap_material *m, double kt);
/* PSD value (m⁴) <-> P̃S = PS/(ε²χ²). */
double ljgap_units_P_to_dimless(const ljgap_material *m, double P);
double ljgap_units_P_to_si(const ljgap_material *m, double Pt);
/* Power-law prefactor of PS = C k^(2D-8) (C in m^(2D-4)) <-> C̃ = C χ^(6-2D)/ε². */
double ljgap_units_C_to_dimless(const ljgap_material *m, double C, double D);
double ljgap_units_C_to_si(const ljgap_material *m, double Ct, double D);
/* Lengths (gaps, h_rms; m) <-> units of ε; variances (m²) <-> units of ε². */
double ljgap_units_len_to_dimless(const ljgap_material *m, double x);
double ljgap_units_len_to_si(const ljgap_material *m, double xt);
double ljgap_units_var_to_dimless(const ljgap_material *m, double v);
double ljgap_units_var_to_si(const ljgap_material *m, double vt);

/* ---- answers in SI: one call per kind of result, into a struct ----
 * The handler serialises these as the "si" object of an answer (and the CSV form is written
 * from that JSON), so every SI number of every answer is converted here and nowhere else.
 * Errors convert with their values: every computed quantity is an ljgap_est (or, for a PDF's
 * density, an L1 error), serialised as the si object's "error"; the scales and the inputs
 * (χ, σ0, E*, the gaps asked for, m0) are exact and carry none. A contact answer's SI form is
 * its summary's (the pull-off forces of ljgap_contact are in N already). */

/* The scales a material sets. */
typedef struct {
    double chi_m;     /* the elastic length χ (m) */
    double sigma0_Pa; /* the traction scale σ0 of (9) (Pa) */
    double E_star_Pa; /* the effective modulus E* (Pa) */
} ljgap_si_scales;
void ljgap_si_scales_of(const ljgap_material *m, ljgap_si_scales *out);

/* The adhesion summary in SI. */
typedef struct {
    ljgap_est g_eq_m;          /* equilibrium mean gap (m) */
    ljgap_est sigma_max_Pa;    /* pull-off traction (Pa) */
    ljgap_est g_at_max_m;      /* mean gap of the traction maximum (m) */
    ljgap_est dgamma_eff_J_m2; /* effective work of adhesion (J/m²) */
    double m0_m2;              /* height variance (m²) */
} ljgap_si_summary;
void ljgap_si_summary_of(const ljgap_material *m, const ljgap_summary *s, ljgap_si_summary *out);

/* One point of a traction curve in SI. */
typedef struct {
    double g_ave_m;     /* mean gap (m) */
    ljgap_est sigma_Pa; /* mean traction (Pa) */
} ljgap_si_point;
/* The n points (g_ave[i] in ε, sigma[i] in σ0) into out[0..n). */
void ljgap_si_points_of(const ljgap_material *m, const double *g_ave, const ljgap_est *sigma,
                        size_t n, ljgap_si_point *out);

/* A gap PDF in SI; g_m and phi_per_m are the caller's arrays of the PDF's n points. */
typedef struct {
    double k2_per_m;    /* its cut-off (1/m; INFINITY stays INFINITY) */
    double *g_m;        /* the gaps (m) */
    double *phi_per_m;  /* the density at each (1/m) */
    double phi_l1;      /* the estimated L1 error ∫|δΦ|dg of the density: a pure number, the
                           same for phi_per_m over g_m as for Φ over g̃ (ljgap_pdf.phi_err) */
    ljgap_est sigma_Pa; /* its mean traction (Pa) */
} ljgap_si_pdf;
/* Fills out from p; out->g_m and out->phi_per_m must hold p->n values. */
void ljgap_si_pdf_of(const ljgap_material *m, const ljgap_pdf *p, ljgap_si_pdf *out);

/* ---- contact.c: a sphere of radius R on the rough flat (theory.md §6) ---- */

/* Pull-off load of the Maugis-Dugdale model under load control, in units of πwR (w the
 * work of adhesion): the minimum over the contact radius of the load. Tends to 1.5 (JKR) as
 * lambda -> ∞ and to 2 (DMT) as lambda -> 0. lambda >= 0; the result carries the solver's
 * error estimate. */
int ljgap_md_pulloff(double lambda, ljgap_est *P_bar);

/* Johnson-Greenwood (1997) adhesion map boundaries used for the regime. */
#define LJGAP_LAMBDA_JKR 5.0 /* lambda above: JKR applies */
#define LJGAP_LAMBDA_DMT 0.1 /* lambda below: DMT applies */

typedef enum {
    LJGAP_REGIME_DMT = 0,
    LJGAP_REGIME_TRANSITION = 1,
    LJGAP_REGIME_JKR = 2
} ljgap_regime;
const char *ljgap_regime_name(ljgap_regime r); /* "dmt", "transition", "jkr" */

/* The hybrid JKR model of a sphere on the rough surface. */
typedef struct {
    ljgap_est jkr_smooth; /* 1.5πRΔγ (N): the smooth sphere */
    ljgap_est jkr;        /* 1.5πRΔγeff (N): the paper's Section 6 */
    ljgap_est dmt;        /* 2πRΔγeff (N) */
    ljgap_est md;         /* Maugis-Dugdale with σ̄max, Δγeff (N) */
    double tabor_smooth;  /* μ = (RΔγ²/(E*²ε³))^(1/3) of (7) */
    ljgap_est tabor_eff;  /* μ with Δγeff and the range ε Δγeff/σ̄max of the mean law */
    ljgap_est lambda;     /* Maugis' λ with σ̄max σ0 and Δγeff */
    ljgap_regime regime;  /* from lambda and the LJGAP_LAMBDA_* boundaries */
} ljgap_contact;

/* Contact of a sphere of radius R (m) with the rough surface whose adhesion summary (in
 * dimensionless units) is sum; errors of sum propagate linearly. LJGAP_EINVAL unless R > 0
 * and sum's sigma_max, dgamma_eff are finite and > 0. */
int ljgap_contact_compute(const ljgap_material *m, double R, const ljgap_summary *sum,
                          ljgap_contact *out);

#ifdef __cplusplus
}
#endif
#endif
