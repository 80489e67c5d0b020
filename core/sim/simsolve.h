/* simsolve.h -- one realization of the discrete model (core/sim/simsolve.c): the workspace, the
 * random surface, and the equilibrium at a prescribed mean gap. core/sim/sim.c runs the
 * realizations (on threads) and gathers the result. Internal to the core.
 *
 *   sim_shared sh = {...};                    // plans, law, options: shared, read-only
 *   sim_ws w;  sim_ws_alloc(&w, &sh);
 *   sim_ws_surface(&w, &band, seed, &m0_grid);
 *   sim_ws_start(&w, g_top, &gcur);
 *   sim_ws_goto(&w, &gcur, g, &point);  ...   // continuation from gap to gap
 *   sim_ws_free(&w);
 */
#ifndef LJGAP_SIMSOLVE_H
#define LJGAP_SIMSOLVE_H

#include "ljgap_sim.h"
#include "core.h" /* ljgap__now */
#include "simlaw.h"

#include <fftw3.h>
#include <stdatomic.h>

#define SIM_A 2.598076211353315940 /* 3√3/2 */

/* What every realization of a run shares (read-only while they run, except abort). */
typedef struct {
    int n;                   /* grid points per side */
    double L, dq;            /* side, lattice spacing in q */
    fftw_plan fwd, bwd;      /* n x n r2c and c2r, executed on each workspace's arrays */
    const sim_law *law;      /* the interface law */
    const ljgap_sim_opts *o; /* tol, max_iter, cancel */
    double deadline;         /* ljgap__now() value of the time cap */
    atomic_int *abort;       /* nonzero: stop with that status (another realization failed) */
} sim_shared;

/* The band the grid carries: lattice wavevectors with k1 <= |q| <= k_top, amplitudes from psd,
 * each realization scaled to carry m0 exactly when match (m0 = 0: a flat surface). */
typedef struct {
    const ljgap_psd *psd;
    double k_top;
    double m0;
    int match;
} sim_band;

typedef struct {
    const sim_shared *sh;
    size_t N, nc;  /* real points, complex (half-spectrum) points */
    double *kappa; /* stiffness (3√3/2)|q| per complex index (0 at q = 0) */
    double *h, *u, *Ku, *g, *sig, *s, *G, *d, *Kd, *r, *p, *Kp, *ubak;
    double *W; /* the law's potential ∫_g^∞ σ at the current gaps (the line search's energy) */
    fftw_complex *c, *c2; /* scratch spectra */
    fftw_complex *P;      /* conjugate-gradient direction, in Fourier space */
    long iter;            /* Hessian products at the current requested gap */
    int negcurv;          /* negative curvature met since last cleared */
} sim_ws;

/* The answer at one mean gap. */
typedef struct {
    double sigma;    /* <σ> */
    double residual; /* rms G / max(1, rms σ) */
    double srms_s;   /* rms of σ' (for the error estimate) */
    double law_err;  /* mean estimated error of the law over the grid (0 for Lennard-Jones) */
    double law_max;  /* largest of it */
    double g_min;    /* smallest local gap */
} sim_point;

#define SIM_STALL 16 /* internal status: the line search or the step control failed */

int sim_ws_alloc(sim_ws *w, const sim_shared *sh);
void sim_ws_free(sim_ws *w);
/* One realization into w->h (random phases from seed; see simsolve.c). Writes the unscaled
 * lattice variance. LJGAP_EINVAL when the lattice carries none of a nonzero band. */
int sim_ws_surface(sim_ws *w, const sim_band *b, unsigned long seed, double *m0_grid);
/* A flat elastic surface at a mean gap where every local gap is at least 1.5 (or g_top). */
void sim_ws_start(sim_ws *w, double g_top, double *gcur);
/* Moves the solution from mean gap *gcur to gt in feasible substeps; pt holds the answer at gt.
 * LJGAP_OK, LJGAP_EFAIL (stalled), or a stop status (cancel, time cap, abort). */
int sim_ws_goto(sim_ws *w, double *gcur, double gt, sim_point *pt);

#endif
