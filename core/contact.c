/* contact.c -- the hybrid JKR model: a sphere of radius R on the rough surface (theory.md §6).
 *
 * The paper's Section 6 replaces the flat-surface law by the mean traction law of the rough
 * surface: its work of separation Δγeff and its strength σ̄max feed the classical sphere
 * contact models. With w = Δγeff (J/m²):
 *   JKR  P = 1.5πRw (load control; with w = Δγ for the smooth sphere),
 *   DMT  P = 2πRw,
 *   Maugis-Dugdale (Maugis 1992, in the notation of Johnson & Greenwood, J. Colloid
 *   Interface Sci. 192 (1997) 326): a Dugdale zone of stress σD = σ̄max σ0 between the
 *   contact radius a and c = m a. With K = 4E* /3, Ā = a (K/(πwR²))^(1/3), P̄ = P/(πwR) and
 *     λ = 2σD (R/(πwK²))^(1/3)  (= σD (9R/(2πwE*²))^(1/3)),
 *   the zone size m solves
 *     (λĀ²/2)[√(m²-1) + (m²-2) atan√(m²-1)] + (4λ²Ā/3)[√(m²-1) atan√(m²-1) - m + 1] = 1
 *   and the load is P̄ = Ā³ - λĀ²[√(m²-1) + m² atan√(m²-1)].
 *   Under load control the pull-off is -min over Ā of P̄: 1.5 as λ -> ∞ (JKR), 2 as λ -> 0
 *   (DMT). We solve for s = √(m²-1) (Brent, gsl_root) on a log grid of Ā, then refine the
 *   grid minimum with gsl_min (Brent); when the grid minimum sits at the smallest Ā the
 *   curve decreases towards Ā -> 0 and its value there is the pull-off.
 * Tabor's parameter (7): μ = (RΔγ²/(E*²ε³))^(1/3) for the smooth law; for the mean law the
 * range ε is replaced by the one that keeps the Lennard-Jones ratio of work to strength,
 * ε Δγeff/σ̄max (dimensionless Δγeff, σ̄max), so μeff = μ σ̄max Δγeff^(-1/3). For the
 * Lennard-Jones law λ = 1.16μ. Regime: Johnson & Greenwood's adhesion map puts JKR above
 * λ ≈ 5 and DMT below λ ≈ 0.1 (LJGAP_LAMBDA_JKR, LJGAP_LAMBDA_DMT); between, only
 * Maugis-Dugdale applies.
 */
#include "ljgap_units.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_min.h>
#include <gsl/gsl_roots.h>
#include <math.h>

#define MD_A_LO 1e-6 /* smallest contact radius Ā of the grid */
#define MD_A_HI 4.0  /* largest (the JKR pull-off is at Ā = 1.5^(1/3)) */
#define MD_GRID 240  /* log-spaced grid points */
#define MD_ITER 200  /* iteration cap of each Brent solve */
#define MD_ROOT_REL 1e-14
#define MD_MIN_REL 1e-9

/* s + (s²-1) atan s, by its series s³·4/3 - ... where the difference cancels. */
static double md_g1(double s)
{
    if (s < 1e-2) {
        double s2 = s * s;
        double diff = s * s2 * (1.0 / 3 - s2 * (1.0 / 5 - s2 * (1.0 / 7 - s2 / 9)));
        return diff + s2 * atan(s);
    }
    return s + (s * s - 1) * atan(s);
}

/* s atan s - (m - 1) with m = √(1+s²). */
static double md_g2(double s)
{
    return s * atan(s) - s * s / (sqrt(1 + s * s) + 1);
}

typedef struct {
    double A, lambda;
} md_par;

static double md_eq(double s, void *p)
{
    const md_par *q = p;
    return q->lambda * q->A * q->A / 2 * md_g1(s) +
           4 * q->lambda * q->lambda * q->A / 3 * md_g2(s) - 1;
}

/* The zone size s = √(m²-1) at contact radius A; NAN when the solve fails. md_eq increases
 * with s from -1 at s = 0, so the root is unique. */
static double md_s(double A, double lambda)
{
    md_par p = {A, lambda};
    gsl_function F = {md_eq, &p};
    double lo = 1, hi = 1, s = NAN;
    gsl_root_fsolver *r;
    if (md_eq(1, &p) < 0) {
        while (md_eq(hi, &p) < 0 && hi < 1e150)
            lo = hi, hi *= 2;
    } else {
        while (md_eq(lo, &p) > 0 && lo > 1e-150)
            hi = lo, lo /= 2;
    }
    if (md_eq(lo, &p) > 0 || md_eq(hi, &p) < 0) return NAN;
    if (md_eq(lo, &p) == 0) return lo;
    if (md_eq(hi, &p) == 0) return hi;
    if (!(r = gsl_root_fsolver_alloc(gsl_root_fsolver_brent))) return NAN;
    gsl_root_fsolver_set(r, &F, lo, hi);
    for (int i = 0; i < MD_ITER; i++) {
        if (gsl_root_fsolver_iterate(r)) break;
        lo = gsl_root_fsolver_x_lower(r);
        hi = gsl_root_fsolver_x_upper(r);
        s = gsl_root_fsolver_root(r);
        if (gsl_root_test_interval(lo, hi, 0, MD_ROOT_REL) == GSL_SUCCESS) break;
    }
    gsl_root_fsolver_free(r);
    return s;
}

/* P̄(Ā) on the Maugis-Dugdale curve. */
static double md_load(double A, void *p)
{
    double lambda = *(const double *)p, s = md_s(A, lambda);
    return A * A * A - lambda * A * A * (s + (1 + s * s) * atan(s));
}

int ljgap_md_pulloff(double lambda, ljgap_est *P_bar)
{
    double A[MD_GRID], P[MD_GRID];
    size_t imin = 0;
    gsl_function F = {md_load, &lambda};
    gsl_min_fminimizer *m;
    double a, b, x;
    if (!(lambda >= 0) || !isfinite(lambda)) return LJGAP_EINVAL;
    if (lambda == 0) { /* DMT exactly */
        *P_bar = (ljgap_est){2, 0};
        return LJGAP_OK;
    }
    for (size_t i = 0; i < MD_GRID; i++) {
        A[i] = MD_A_LO * pow(MD_A_HI / MD_A_LO, (double)i / (MD_GRID - 1));
        P[i] = md_load(A[i], &lambda);
        if (!isfinite(P[i])) return LJGAP_EFAIL;
        if (P[i] < P[imin]) imin = i;
    }
    if (imin == 0) { /* decreasing towards Ā -> 0: the limit, with the last step as error */
        *P_bar = (ljgap_est){-P[0], fabs(P[1] - P[0])};
        return LJGAP_OK;
    }
    if (imin == MD_GRID - 1) return LJGAP_EFAIL; /* no minimum on the grid */
    if (!(m = gsl_min_fminimizer_alloc(gsl_min_fminimizer_brent))) return LJGAP_ENOMEM;
    if (gsl_min_fminimizer_set_with_values(m, &F, A[imin], P[imin], A[imin - 1], P[imin - 1],
                                           A[imin + 1], P[imin + 1])) {
        /* Brent needs a strict bracket; near DMT (small λ) the load is flat to round-off
         * around its minimum, so the grid's minimum is the answer, good to that spread */
        gsl_min_fminimizer_free(m);
        *P_bar = (ljgap_est){
            -P[imin], fmax(fabs(P[imin - 1] - P[imin]), fabs(P[imin + 1] - P[imin])) + 1e-13};
        return LJGAP_OK;
    }
    for (int i = 0; i < MD_ITER; i++) {
        if (gsl_min_fminimizer_iterate(m)) break;
        a = gsl_min_fminimizer_x_lower(m);
        b = gsl_min_fminimizer_x_upper(m);
        if (gsl_min_test_interval(a, b, 0, MD_MIN_REL) == GSL_SUCCESS) break;
    }
    x = gsl_min_fminimizer_x_minimum(m);
    a = gsl_min_fminimizer_x_lower(m);
    b = gsl_min_fminimizer_x_upper(m);
    *P_bar = (ljgap_est){-gsl_min_fminimizer_f_minimum(m),
                         fmax(fabs(md_load(a, &lambda) - md_load(x, &lambda)),
                              fabs(md_load(b, &lambda) - md_load(x, &lambda))) +
                             1e-13};
    gsl_min_fminimizer_free(m);
    return isfinite(P_bar->value) ? LJGAP_OK : LJGAP_EFAIL;
}

const char *ljgap_regime_name(ljgap_regime r)
{
    switch (r) {
    case LJGAP_REGIME_DMT:
        return "dmt";
    case LJGAP_REGIME_JKR:
        return "jkr";
    default:
        return "transition";
    }
}

int ljgap_contact_compute(const ljgap_material *m, double R, const ljgap_summary *sum,
                          ljgap_contact *out)
{
    double d = sum->dgamma_eff.value, dd = sum->dgamma_eff.err;
    double s = sum->sigma_max.value, ds = sum->sigma_max.err;
    double w = d * m->dgamma, sigD = s * ljgap_units_sigma0(m), K = 4 * m->E_star / 3;
    double lam, rel, h, dP;
    ljgap_est Pb, Pp, Pm;
    int st;
    if (!(R > 0 && isfinite(R) && d > 0 && s > 0 && isfinite(d) && isfinite(s)))
        return LJGAP_EINVAL;
    lam = 2 * sigD * cbrt(R / (M_PI * w * K * K));
    rel = ds / s + dd / (3 * d); /* relative error of λ and of μeff */
    if ((st = ljgap_md_pulloff(lam, &Pb))) return st;
    /* dP̄/dλ by a central difference, for the linear error propagation */
    h = 1e-3 * lam;
    if ((st = ljgap_md_pulloff(lam + h, &Pp)) || (st = ljgap_md_pulloff(lam - h, &Pm))) return st;
    dP = (Pp.value - Pm.value) / (2 * h);
    out->jkr_smooth = (ljgap_est){1.5 * M_PI * R * m->dgamma, 0};
    out->jkr = (ljgap_est){1.5 * M_PI * R * w, 1.5 * M_PI * R * m->dgamma * dd};
    out->dmt = (ljgap_est){2 * M_PI * R * w, 2 * M_PI * R * m->dgamma * dd};
    /* P = P̄(λ) πRw: dP = πR[P̄ Δγ dd + w |P̄'| λ rel] + πRw err(P̄) */
    out->md =
        (ljgap_est){Pb.value * M_PI * R * w,
                    M_PI * R * (Pb.value * m->dgamma * dd + w * fabs(dP) * lam * rel + w * Pb.err)};
    out->tabor_smooth =
        cbrt(R * m->dgamma * m->dgamma / (m->E_star * m->E_star * pow(m->epsilon, 3)));
    out->tabor_eff.value = out->tabor_smooth * s / cbrt(d);
    out->tabor_eff.err = out->tabor_eff.value * rel;
    out->lambda = (ljgap_est){lam, lam * rel};
    out->regime = lam > LJGAP_LAMBDA_JKR   ? LJGAP_REGIME_JKR
                  : lam < LJGAP_LAMBDA_DMT ? LJGAP_REGIME_DMT
                                           : LJGAP_REGIME_TRANSITION;
    return LJGAP_OK;
}
