/* simlaw.h -- the interface law of the discrete model (core/sim/sim.c): the Lennard-Jones law (8),
 * (9), or, for the hybrid model (the paper's Section 6), the statistical mean traction of the
 * band of roughness the grid does not carry, tabulated once per run. Internal to the core;
 * tests and benchmarks use it directly.
 *
 *   sim_law law;
 *   sim_law_fine(&law, &fine_band, &opts, &warnings);   // or sim_law_lj(&law)
 *   sim_law_eval(&law, g, &sigma, &dsigma, &work);  sim_law_work(&law, g);  sim_law_err(&law, g);
 *   sim_law_free(&law);
 */
#ifndef LJGAP_SIMLAW_H
#define LJGAP_SIMLAW_H

#include "ljgap.h"

#define SIMLAW_G_LO 0.45 /* lowest node of the table (deep compression: sigma ~ -3900) */
#define SIMLAW_G_HI 8.0  /* highest node, at least (more for a rough band: see simlaw.c) */
#define SIMLAW_DT 0.004  /* node spacing in ln g */

typedef struct {
    int tabulated;     /* 0: the Lennard-Jones law itself (nothing below but s_min is used) */
    double m0;         /* variance of the fine band */
    size_t n;          /* table nodes, odd */
    double t0, dt;     /* node i is g_i = exp(t0 + i dt) */
    double g_lo, g_hi; /* first and last node */
    double *g;         /* owned block of 9n: the nodes, then d, dd, I, e and c */
    double *d;         /* δ_i = σ̄(g_i) - σ(g_i): what the fine band changes at node i */
    double *dd;        /* dδ/dg at node i (fourth-order differences in ln g) */
    double *I;         /* ∫_{g_i}^{g_hi} δ dg of the interpolant (exact) */
    double *e;         /* estimated absolute error of σ̄ at node i: the PDE's estimate plus
                        * the interpolation's (from a table of half the nodes) */
    double *c;         /* cell i's cubic δ = c0 + c1 x + c2 x² + c3 x³, x = g - g_i, at c[4i] */
    size_t *bin;       /* owned: the cell of g_lo + b/inv_bw, bins no wider than any cell */
    size_t nbin;
    double inv_bw;
    double D_hi;       /* ∫_{g_hi}^∞ δ dg, with σ̄ = E[σ(g+X)], X ~ N(0, m0) beyond g_hi */
    double e_hi;       /* error beyond g_hi: the table's mismatch with that form at g_hi */
    double s_min;      /* smallest dσ̄/dg (exact for Lennard-Jones: -(3√3/2) k0; for a table
                        * the smallest of 4 samples per cell) */
    ljgap_summary sum; /* the tabulated law's g_eq, σ̄max, g_at_max, Δγeff with errors */
} sim_law;

/* The Lennard-Jones law. */
void sim_law_lj(sim_law *law);
/* The statistical mean traction σ̄(g) of the band `fine` (ljgap_traction, options o: PDE at
 * o->tol, o's time cap and cancel flag), on SIMLAW_G_LO <= g <= g_hi, as the Lennard-Jones law
 * plus a C1 piecewise cubic δ (Hermite, nodes uniform in ln g, slopes from fourth-order
 * differences), E[σ(g+X)] beyond g_hi. Returns ljgap_traction's status (law untouched on
 * failure) or LJGAP_ENOMEM. */
int sim_law_fine(sim_law *law, const ljgap_psd *fine, const ljgap_opts *o, ljgap_warnings *w);
void sim_law_free(sim_law *law); /* NULL and the Lennard-Jones law are fine */

/* σ̄(g), dσ̄/dg and, when work is not NULL, ∫_g^∞ σ̄ dg' (the law's potential: its derivative is
 * -σ̄; exact for the interpolant), g > 0. Below g_lo δ continues linearly (C1). */
void sim_law_eval(const sim_law *law, double g, double *sigma, double *dsigma, double *work);
double sim_law_work(const sim_law *law, double g); /* the potential alone */
/* Estimated absolute error of σ̄(g) (0 for Lennard-Jones). */
double sim_law_err(const sim_law *law, double g);

#endif
