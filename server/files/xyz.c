/* xyz.c -- x y z text columns on a regular grid (.xyz, .txt, .csv).
 *
 * One point a line: x, y and the height z, separated by white space, one comma or one
 * semicolon; '#' and '%' start comments; lines of words before the first number (a header
 * such as "x y z") are skipped; "nan" as a height is a missing point. Two columns (x z) are a
 * profile. The grid is found, not assumed: the distinct x values (and y values) must lie on
 * one regular spacing (within 1 % of it: exports round their coordinates), the spacing being
 * the least gap between neighbouring distinct values; a grid point no line gives is missing
 * (NaN), a point given twice is an error, and a grid that the points would fill less than half
 * is no grid (a scattered point cloud, which is not read). Any order of the lines is accepted;
 * rows of the map are successive y values from the least.
 *
 * Units: the columns carry none; x, y and z are taken to be metres (z_unit "m"), and the size
 * is the grid's nx dx by ny dy. A file in other units must be converted first (or its PSD
 * scaled: P goes as the square of the height unit times the square of the length unit).
 */
#include "files_util.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NAME "xyz"
#define TOKEN_MAX 64
#define GRID_TOL 1e-2 /* a value's distance from its grid point, in spacings (exports round) */
#define FILL_MIN 0.5  /* the points must fill at least this share of their grid */

static int is_sep(char c)
{
    return c == ' ' || c == '\t' || c == ',' || c == ';' || c == '\r';
}

/* The numbers of line s[0..n) into v (at most 4); their count, or -1 when a token is not a
 * number ("nan" allowed as the last of 2 or 3, *nan set). */
static int numbers(const char *s, size_t n, double *v, int *nan)
{
    int k = 0;
    *nan = 0;
    for (size_t i = 0; i < n;) {
        while (i < n && is_sep(s[i]))
            i++;
        if (i >= n || s[i] == '#' || s[i] == '%') break;
        size_t t = i;
        while (i < n && !is_sep(s[i]) && s[i] != '#')
            i++;
        char tok[TOKEN_MAX + 1], *end;
        if (i - t > TOKEN_MAX || k >= 4) return -1;
        memcpy(tok, s + t, i - t);
        tok[i - t] = '\0';
        double x = strtod(tok, &end);
        if (*end || end == tok) return -1;
        if (!isfinite(x)) {
            if (!isnan(x)) return -1;
            *nan = k + 1;
        }
        v[k++] = x;
    }
    return k;
}

static int probe(const unsigned char *buf, size_t len)
{
    /* text (no NUL, no control bytes) whose first number line has 2 or 3 columns, and the
     * next ones as many */
    size_t n = len < 4096 ? len : 4096, p = 0;
    int cols = 0, lines = 0;
    for (size_t i = 0; i < n; i++)
        if (buf[i] == 0 || (buf[i] < 0x20 && buf[i] != '\n' && buf[i] != '\r' && buf[i] != '\t'))
            return 0;
    while (p < n && lines < 4) {
        const char *s = (const char *)buf + p, *nl = memchr(s, '\n', n - p);
        size_t m = nl ? (size_t)(nl - s) : n - p;
        double v[4];
        int nan, k;
        p += m + 1;
        if (!nl && p < len) break; /* a line cut by the 4 KiB look: not judged */
        if ((k = numbers(s, m, v, &nan)) == 0) continue;
        if (k < 0) {
            if (cols) return 0;
            continue; /* a header line */
        }
        if (k < 2 || k > 3 || (cols && k != cols) || (nan && nan != k)) return 0;
        cols = k;
        lines++;
    }
    return lines >= 2;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The regular grid of the values v[0..n) (stride 3 apart): its start, spacing and count; 0,
 * or a reason. One value: count 1, spacing 0. */
static const char *grid(const double *v, size_t n, size_t stride, double *x0, double *d,
                        size_t *count)
{
    double *s = malloc(n * sizeof *s);
    size_t u = 0;
    if (!s) return "out of memory";
    for (size_t i = 0; i < n; i++)
        s[i] = v[i * stride];
    qsort(s, n, sizeof *s, cmp);
    double range = s[n - 1] - s[0], tol = 1e-9 * (fabs(s[0]) + fabs(s[n - 1]));
    for (size_t i = 0; i < n; i++)
        if (!u || s[i] - s[u - 1] > tol) s[u++] = s[i];
    *x0 = s[0];
    *count = u;
    *d = 0;
    if (u == 1) {
        free(s);
        return NULL;
    }
    double least = INFINITY;
    for (size_t i = 1; i < u; i++)
        least = fmin(least, s[i] - s[i - 1]);
    double steps = range / least;
    if (!(steps < 1e8)) {
        free(s);
        return "its values are not on a regular spacing";
    }
    size_t k = (size_t)llround(steps);
    *d = range / (double)k; /* the spacing that puts the last value on the grid */
    for (size_t i = 0; i < u; i++) {
        double r = (s[i] - s[0]) / *d;
        if (fabs(r - nearbyint(r)) > GRID_TOL) {
            free(s);
            return "its values are not on a regular spacing";
        }
    }
    *count = k + 1;
    free(s);
    return NULL;
}

static int read_xyz(const unsigned char *buf, size_t len, const char *channel, ljgap__files_map *map,
                    ljgap__files_err *err)
{
    double *v = NULL;
    size_t n = 0, cap = 0, p = 0, line = 0;
    int cols = 0, st = 0;
    const char *why;
    while (p < len) {
        const char *s = (const char *)buf + p, *nl = memchr(s, '\n', len - p);
        size_t m = nl ? (size_t)(nl - s) : len - p, at = p;
        double x[4];
        int nan, k;
        p += m + 1;
        line++;
        if ((k = numbers(s, m, x, &nan)) == 0) continue;
        if (k < 0 && !n) continue; /* a header line before the numbers */
        if (k < 0 || k < 2 || k > 3 || (cols && k != cols) || (nan && nan != k)) {
            st = ljgap__files_fail(err, NAME, (long)at, NULL, "line %zu is not %s numbers (x%s z)",
                                  line, cols == 2 ? "2" : "3", cols == 2 ? "" : " y");
            goto end;
        }
        cols = k;
        if (n / 3 >= LJGAP_FILES_MAX_POINTS) {
            ljgap__files_fail(err, NAME, (long)at, NULL, "more than %u points",
                             LJGAP_FILES_MAX_POINTS);
            st = LJGAP_FILES_TOOBIG;
            goto end;
        }
        if (n + 3 > cap) {
            size_t c = cap ? 2 * cap : 3 * 4096;
            double *w = realloc(v, c * sizeof *w);
            if (!w) {
                st = LJGAP_FILES_NOMEM;
                goto end;
            }
            v = w, cap = c;
        }
        v[n] = x[0];
        v[n + 1] = k == 3 ? x[1] : 0;
        v[n + 2] = x[k - 1];
        n += 3;
    }
    size_t N = n / 3, nx, ny;
    double x0, y0, dx, dy;
    if (N < 2) {
        st = ljgap__files_fail(err, NAME, (long)len, NULL, "fewer than 2 points");
        goto end;
    }
    ljgap__files_add_channel(map, "Height");
    if (ljgap__files_channel_pick(map, channel, err) < 0) {
        st = LJGAP_FILES_CHANNEL;
        goto end;
    }
    snprintf(map->channel, sizeof map->channel, "Height");
    const char *axis = "x";
    if ((why = grid(v, N, 3, &x0, &dx, &nx)) ||
        (axis = "y", why = grid(v + 1, N, 3, &y0, &dy, &ny))) {
        st = ljgap__files_fail(err, NAME, -1, NULL, "the points form no grid: %s %s", axis, why);
        goto end;
    }
    if (nx < 2 || (cols == 3 && ny < 2) || (double)nx * (double)ny > N / FILL_MIN) {
        st = ljgap__files_fail(err, NAME, -1, NULL,
                              "the %zu points form no regular grid (%zu x %zu points would "
                              "hold them)",
                              N, nx, ny);
        goto end;
    }
    if ((st = ljgap__files_alloc(map, nx, ny, err))) goto end;
    for (size_t i = 0; i < nx * ny; i++)
        map->z[i] = INFINITY; /* not given yet */
    for (size_t i = 0; i < N; i++) {
        size_t a = (size_t)llround((v[3 * i] - x0) / dx),
               b = ny > 1 ? (size_t)llround((v[3 * i + 1] - y0) / dy) : 0;
        double *z = &map->z[b * nx + a];
        if (*z != INFINITY) {
            st = ljgap__files_fail(err, NAME, -1, NULL, "the point x = %g, y = %g is given twice",
                                  v[3 * i], v[3 * i + 1]);
            goto end;
        }
        *z = v[3 * i + 2];
    }
    for (size_t i = 0; i < nx * ny; i++)
        if (map->z[i] == INFINITY) map->z[i] = NAN;
    snprintf(map->z_unit, sizeof map->z_unit, "m");
    map->size_x = (double)nx * dx;
    map->size_y = ny > 1 ? (double)ny * dy : dx;
end:
    free(v);
    return st;
}

const ljgap__files_format ljgap__files_xyz = {NAME, ".xyz .txt .csv", NULL, probe, read_xyz};
