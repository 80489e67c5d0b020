/* topo_prep.c -- a height map made ready for its periodogram (topo.c): the detrending (mean,
 * plane or per-line, by name: ljgap_topo_detrend_name/_parse) and the Hann window of a
 * non-periodic map.
 */
#include "ljgap_topo.h"
#include "topo_parts.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Removes what mode says, in place; a is [ny][nx] (a profile: ny = 1). On the centred
 * coordinates x = i - ī, y = j - ȳ the polynomials 1, x, y, x² - <x²>, xy, y² - <y²> are
 * orthogonal over the full grid, so each least-squares coefficient is Σ h φ / Σ φ² on its own
 * (mean: the first; plane: three; curvature: all six; a profile has y = 0 and keeps those of
 * x). lines: each row's own mean and slope along x (AFM scan lines with their offsets and
 * tilts). The sums run in long double, so that a map that is a plane (or constant) leaves only
 * the rounding of its own heights. */
void ljgap__topo_detrend(double *a, size_t nx, size_t ny, ljgap_topo_detrend mode)
{
    const long double xc = 0.5L * (long double)(nx - 1), yc = 0.5L * (long double)(ny - 1);
    const long double mx2 = ((long double)nx * nx - 1) / 12, my2 = ((long double)ny * ny - 1) / 12;
    if (mode == LJGAP_DETREND_LINES) {
        for (size_t j = 0; j < ny; j++) {
            double *r = a + j * nx;
            long double s = 0, sx = 0;
            for (size_t i = 0; i < nx; i++)
                s += r[i], sx += r[i] * ((long double)i - xc);
            long double m = s / (long double)nx, bx = mx2 > 0 ? sx / (mx2 * (long double)nx) : 0;
            for (size_t i = 0; i < nx; i++)
                r[i] = (double)(r[i] - (m + bx * ((long double)i - xc)));
        }
        return;
    }
    if (mode != LJGAP_DETREND_CURVATURE) { /* mean or plane: the three sums alone (fast) */
        long double sm = 0, sx = 0, sy = 0, bx = 0, by = 0;
        for (size_t j = 0; j < ny; j++) {
            long double y = (long double)j - yc, r = 0, rx = 0;
            for (size_t i = 0; i < nx; i++) {
                long double h = a[j * nx + i];
                r += h, rx += h * ((long double)i - xc);
            }
            sm += r, sx += rx, sy += r * y;
        }
        long double N = (long double)nx * (long double)ny, mean = sm / N;
        if (mode == LJGAP_DETREND_PLANE) {
            if (mx2 > 0) bx = sx / (mx2 * N);
            if (my2 > 0) by = sy / (my2 * N);
        }
        for (size_t j = 0; j < ny; j++) {
            double off = (double)(mean + by * ((long double)j - yc));
            for (size_t i = 0; i < nx; i++)
                a[j * nx + i] = (double)(a[j * nx + i] - (off + bx * ((long double)i - xc)));
        }
        return;
    }
    const int np = 6;
    long double num[6] = {0}, den[6] = {0}, c[6] = {0}, phi[6];
    for (int pass = 0; pass < 2; pass++)
        for (size_t j = 0; j < ny; j++) {
            long double y = (long double)j - yc;
            for (size_t i = 0; i < nx; i++) {
                long double x = (long double)i - xc, h = a[j * nx + i], fit = 0;
                phi[0] = 1, phi[1] = x, phi[2] = y;
                phi[3] = x * x - mx2, phi[4] = x * y, phi[5] = y * y - my2;
                for (int p = 0; p < np; p++) {
                    if (pass == 0)
                        num[p] += h * phi[p], den[p] += phi[p] * phi[p];
                    else
                        fit += c[p] * phi[p];
                }
                if (pass == 1) a[j * nx + i] = (double)(h - fit);
            }
            if (pass == 0 && j + 1 == ny)
                for (int p = 0; p < np; p++)
                    c[p] = den[p] > 0 ? num[p] / den[p] : 0;
        }
}

const char *ljgap_topo_detrend_name(ljgap_topo_detrend d)
{
    switch (d) {
    case LJGAP_DETREND_MEAN:
        return "mean";
    case LJGAP_DETREND_PLANE:
        return "plane";
    case LJGAP_DETREND_LINES:
        return "lines";
    case LJGAP_DETREND_CURVATURE:
        return "curvature";
    default:
        return "auto";
    }
}

int ljgap_topo_detrend_parse(const char *name)
{
    for (int d = LJGAP_DETREND_MEAN; d <= LJGAP_DETREND_CURVATURE; d++)
        if (name && strcmp(name, ljgap_topo_detrend_name((ljgap_topo_detrend)d)) == 0) return d;
    return -1;
}

/* The periodic Hann window of length n at i, w = (1 - cos(2πi/n))/2 (1 when n == 1). */
static double hann(size_t i, size_t n)
{
    return n > 1 ? 0.5 * (1 - cos(2 * M_PI * (double)i / (double)n)) : 1.0;
}

/* Multiplies a by w(i)w(j) / rms(w ⊗ w). */
void ljgap__topo_window(double *a, size_t nx, size_t ny)
{
    double *wx = malloc(nx * sizeof *wx), *wy = malloc(ny * sizeof *wy), sx = 0, sy = 0;
    if (!wx || !wy) { /* small; fall back to computing in place */
        free(wx);
        free(wy);
        wx = wy = NULL;
    }
    for (size_t i = 0; i < nx; i++) {
        double w = hann(i, nx);
        sx += w * w;
        if (wx) wx[i] = w;
    }
    for (size_t j = 0; j < ny; j++) {
        double w = hann(j, ny);
        sy += w * w;
        if (wy) wy[j] = w;
    }
    double norm = 1 / sqrt(sx / (double)nx * sy / (double)ny);
    for (size_t j = 0; j < ny; j++) {
        double w = (wy ? wy[j] : hann(j, ny)) * norm;
        for (size_t i = 0; i < nx; i++)
            a[j * nx + i] *= w * (wx ? wx[i] : hann(i, nx));
    }
    free(wx);
    free(wy);
}
