/* realsurf.h -- synthetic height maps like measured ones, for the topography tests (issue 25;
 * static functions: include it in one .c file; FFTW3 and GSL).
 *
 * A Gaussian random surface: every wavevector q = (2π i/Lx, 2π j/Ly) of an nx × ny periodic
 * grid gets a complex amplitude c_q with independent normal real and imaginary parts of variance
 * P(|q|) Δqx Δqy / 2 each (so E|c_q|² = P Δq², the project's convention ∫∫ P d²k = h_rms²),
 * c_{-q} = conj(c_q) (Hermitian symmetry, FFTW's c2r), the Nyquist lines left empty. The
 * spectrum is the shape measured surfaces have:
 *     P(k) = C k_r^(2D-8)  for k < k_r        (roll-off: flat at long wavelengths)
 *          = C k^(2D-8)    for k_r <= k <= k_c (the self-affine band)
 *          = 0             for k > k_c         (a short cutoff)
 * and then, in this order, what an instrument does to it: a spherical tip of radius R dilates
 * it (morphological: h_d(x) = max over |u| <= ρ of h(x + u) - (R - √(R² - u²)), the apex
 * following the highest contact; periodic wrap; ρ the footprint where the sphere's depth stays
 * below the map's height range), white noise of rms `noise` is added to every height, each row
 * (a scan line along x) gets a random offset of rms `line_offset` and the map a tilt
 * (tilt_x, tilt_y: dh/dx, dh/dy). Crop the result for a non-periodic map. The half spectrum's
 * plumbing is synth.h's.
 */
#ifndef LJGAP_TEST_REALSURF_H
#define LJGAP_TEST_REALSURF_H

#include <fftw3.h>
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "synth.h"

typedef struct {
    double C, D;        /* P = C k^(2D-8) in the band */
    double k_r;         /* roll-off below (0: none) */
    double k_c;         /* cutoff above (0: none) */
    double tip_R;       /* spherical tip radius (0: none) */
    double noise;       /* rms of white noise added to each height (0: none) */
    double line_offset; /* rms of each row's offset (0: none) */
    double tilt_x, tilt_y;
} realsurf_spec;

/* The spectrum of s at k. */
static double realsurf_P(const realsurf_spec *s, double k)
{
    if (s->k_c > 0 && k > s->k_c) return 0;
    if (k < s->k_r) k = s->k_r;
    return k > 0 ? s->C * pow(k, 2 * s->D - 8) : 0;
}

/* The level C for which the band [k_r, k_c] alone (no roll-off part) has variance m0. */
static double realsurf_level(double D, double k1, double k2, double m0)
{
    double e = 2 * D - 6;
    return m0 / (2 * M_PI * (pow(k2, e) - pow(k1, e)) / e);
}

/* Spherical-tip dilation of a periodic map (nx × ny, spacings dx, dy), in place. */
static int realsurf_dilate(double *h, size_t nx, size_t ny, double dx, double dy, double R)
{
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < nx * ny; i++)
        lo = fmin(lo, h[i]), hi = fmax(hi, h[i]);
    double depth = hi - lo, rho = depth < R ? sqrt(R * R - (R - depth) * (R - depth)) : R;
    long rx = (long)ceil(rho / dx), ry = (long)ceil(rho / dy);
    if (rx >= (long)nx / 2) rx = (long)nx / 2 - 1;
    if (ry >= (long)ny / 2) ry = (long)ny / 2 - 1;
    size_t m = 0, cap = (size_t)(2 * rx + 1) * (size_t)(2 * ry + 1);
    long *ox = malloc(cap * sizeof *ox), *oy = malloc(cap * sizeof *oy);
    double *dz = malloc(cap * sizeof *dz), *out = malloc(nx * ny * sizeof *out);
    if (!ox || !oy || !dz || !out) {
        free(ox), free(oy), free(dz), free(out);
        return -1;
    }
    for (long b = -ry; b <= ry; b++)
        for (long a = -rx; a <= rx; a++) {
            double u2 = (a * dx) * (a * dx) + (b * dy) * (b * dy);
            if (u2 > rho * rho) continue;
            ox[m] = a, oy[m] = b, dz[m++] = R - sqrt(R * R - u2);
        }
    for (size_t j = 0; j < ny; j++)
        for (size_t i = 0; i < nx; i++) {
            double best = -INFINITY;
            for (size_t t = 0; t < m; t++) {
                size_t ii = (size_t)(((long)i + ox[t] + (long)nx) % (long)nx);
                size_t jj = (size_t)(((long)j + oy[t] + (long)ny) % (long)ny);
                double z = h[jj * nx + ii] - dz[t];
                if (z > best) best = z;
            }
            out[j * nx + i] = best;
        }
    memcpy(h, out, nx * ny * sizeof *h);
    free(ox), free(oy), free(dz), free(out);
    return 0;
}

/* One realization into h[j*nx + i] (nx, ny even); *m0 (may be NULL) receives the variance of
 * the Gaussian surface before the instrument (Σ |c_q|², exact). 0, or -1 out of memory. */
static int realsurf_make(double *h, size_t nx, size_t ny, double dx, double dy,
                         const realsurf_spec *s, unsigned long seed, double *m0)
{
    fftw_complex *c;
    gsl_rng *rng;
    double dqx = 2 * M_PI / ((double)nx * dx), dqy = 2 * M_PI / ((double)ny * dy), v = 0;
    long hx = (long)nx / 2, hy = (long)ny / 2;
    if (synth_begin(nx, ny, seed, &c, &rng)) return -1;
    for (long j = -hy + 1; j < hy; j++)
        for (long i = 0; i < hx; i++) {
            if (i == 0 && j <= 0) continue; /* the other half plane holds the conjugates */
            double qx = dqx * (double)i, qy = dqy * (double)j;
            double sd = sqrt(0.5 * realsurf_P(s, sqrt(qx * qx + qy * qy)) * dqx * dqy);
            double re = gsl_ran_gaussian(rng, 1) * sd, im = gsl_ran_gaussian(rng, 1) * sd;
            synth_set(c, nx, ny, i, j, re, im);
            v += 2 * (re * re + im * im);
        }
    if (synth_end(c, h, nx, ny)) {
        gsl_rng_free(rng);
        return -1;
    }
    if (m0) *m0 = v;
    if (s->tip_R > 0 && realsurf_dilate(h, nx, ny, dx, dy, s->tip_R)) {
        gsl_rng_free(rng);
        return -1;
    }
    for (size_t j = 0; j < ny; j++) {
        double off = s->line_offset > 0 ? gsl_ran_gaussian(rng, s->line_offset) : 0;
        for (size_t i = 0; i < nx; i++) {
            double z = off + s->tilt_x * (double)i * dx + s->tilt_y * (double)j * dy;
            if (s->noise > 0) z += gsl_ran_gaussian(rng, s->noise);
            h[j * nx + i] += z;
        }
    }
    gsl_rng_free(rng);
    return 0;
}

#endif
