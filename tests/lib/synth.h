/* synth.h -- synthetic periodic surfaces with a known isotropic PSD, for the topography tests
 * and benchmark (static functions: include it in one .c file).
 *
 * The conventions of core/sim/sim.c's make_surface, on a rectangular grid: an nx × ny map with
 * spacings dx, dy is one period of h(x) = Σ_q c_q e^{iq·x}, q = (2π i/Lx, 2π j/Ly) (angular),
 * c_{-q} = conj(c_q), |c_q| = √(P(|q|) Δqx Δqy) and a uniform random phase (GSL's mt19937), so
 * the realization's variance is the lattice sum Σ_q P(|q|) Δqx Δqy (of ∫∫ P d²k, the project's
 * convention) and its periodogram is P(|q|) at every wavevector. With random_amplitude the
 * squared amplitude is also drawn, exponentially with that mean: a Gaussian random surface.
 * The Nyquist lines (|i| = nx/2, |j| = ny/2) are left empty, as in sim.c.
 */
#ifndef LJGAP_TEST_SYNTH_H
#define LJGAP_TEST_SYNTH_H

#include <fftw3.h>
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* P = C k^(2D-8) on [k1, k2], 0 elsewhere. */
typedef struct {
    double C, D, k1, k2;
} synth_law;

static double synth_P(const synth_law *l, double k)
{
    return k >= l->k1 && k <= l->k2 ? l->C * pow(k, 2 * l->D - 8) : 0.0;
}

/* Moments of the realization (exact lattice sums). */
typedef struct {
    double m0; /* Σ |c_q|² = mean(h²) */
    double m2; /* Σ |q|² |c_q|² = mean(|∇h|²) */
} synth_moments;

/* The half spectrum *c ([ny][nx/2 + 1], zeroed) and *rng (GSL's mt19937 seeded with seed), for
 * a generator to fill: 0, or -1 out of memory (nothing held then). */
static int synth_begin(size_t nx, size_t ny, unsigned long seed, fftw_complex **c, gsl_rng **rng)
{
    *c = fftw_alloc_complex((nx / 2 + 1) * ny);
    *rng = gsl_rng_alloc(gsl_rng_mt19937);
    if (!*c || !*rng) {
        fftw_free(*c);
        gsl_rng_free(*rng);
        return -1;
    }
    gsl_rng_set(*rng, seed);
    memset(*c, 0, (nx / 2 + 1) * ny * sizeof **c);
    return 0;
}

/* The amplitude re + i im at wavevector (i, j) of the half plane i >= 0 (j may be negative);
 * on the column i = 0, which holds its own conjugates, also conj at (0, -j). */
static void synth_set(fftw_complex *c, size_t nx, size_t ny, long i, long j, double re, double im)
{
    size_t nxc = nx / 2 + 1, jr = (size_t)(j < 0 ? j + (long)ny : j);
    c[jr * nxc + (size_t)i][0] = re;
    c[jr * nxc + (size_t)i][1] = im;
    if (i == 0) {
        size_t jc = (size_t)((long)ny - (long)jr);
        c[jc * nxc][0] = re;
        c[jc * nxc][1] = -im;
    }
}

/* The map h from the half spectrum c (FFTW's c2r), c freed: 0, or -1 out of memory. */
static int synth_end(fftw_complex *c, double *h, size_t nx, size_t ny)
{
    fftw_plan p = fftw_plan_dft_c2r_2d((int)ny, (int)nx, c, h, FFTW_ESTIMATE);
    if (!p) {
        fftw_free(c);
        return -1;
    }
    fftw_execute(p);
    fftw_destroy_plan(p);
    fftw_free(c);
    return 0;
}

/* Fills h[j*nx + i] (nx, ny even) with one realization; returns 0, or -1 when out of memory. */
static int synth_surface(double *h, size_t nx, size_t ny, double dx, double dy, const synth_law *l,
                         unsigned long seed, int random_amplitude, synth_moments *mom)
{
    fftw_complex *c;
    gsl_rng *rng;
    double dqx = 2 * M_PI / ((double)nx * dx), dqy = 2 * M_PI / ((double)ny * dy);
    long hx = (long)nx / 2, hy = (long)ny / 2;
    if (synth_begin(nx, ny, seed, &c, &rng)) return -1;
    mom->m0 = mom->m2 = 0;
    for (long j = -hy + 1; j < hy; j++) {
        for (long i = 0; i < hx; i++) {
            if (i == 0 && j <= 0) continue; /* the other half plane holds the conjugates */
            double qx = dqx * (double)i, qy = dqy * (double)j, q2 = qx * qx + qy * qy;
            double phi = 2 * M_PI * gsl_rng_uniform(rng);
            double a2 = synth_P(l, sqrt(q2)) * dqx * dqy;
            if (random_amplitude) a2 *= -log(gsl_rng_uniform_pos(rng));
            double a = sqrt(a2);
            synth_set(c, nx, ny, i, j, a * cos(phi), a * sin(phi));
            mom->m0 += 2 * a2;
            mom->m2 += 2 * a2 * q2;
        }
    }
    gsl_rng_free(rng);
    return synth_end(c, h, nx, ny);
}

#endif
