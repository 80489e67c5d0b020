/* gsf.c -- Gwyddion Simple Field (.gsf).
 *
 * The format (Gwyddion's user guide, "GSF"): the line "Gwyddion Simple Field 1.0", then
 * "Key = Value" lines (XRes and YRes required; XReal, YReal in XYUnits, ZUnits, Title, XOffset,
 * YOffset and any other key optional), then 1 to 4 NUL bytes so that the header's length is
 * a multiple of 4, then XRes * YRes little-endian IEEE 754 single floats, row by row from the
 * top. XReal, YReal default to 1 (unitless) in the format; here a missing XReal leaves the
 * size to the query. Units are SI base units ("m"); a prefixed one ("nm") is read too. A NaN
 * value is a missing point. One channel (its Title).
 */
#include "bytes.h"
#include "files_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define NAME "gsf"
#define MAGIC "Gwyddion Simple Field 1.0"

static int probe(const unsigned char *buf, size_t len)
{
    return len > sizeof MAGIC && memcmp(buf, MAGIC, sizeof MAGIC - 1) == 0 &&
           (buf[sizeof MAGIC - 1] == '\n' || buf[sizeof MAGIC - 1] == '\r');
}

/* The value of key in the header hdr[0..n) into out, or 0 when absent. */
static int get(const char *hdr, size_t n, const char *key, char *out, size_t size)
{
    size_t k = strlen(key);
    for (size_t p = 0; p < n;) {
        const char *s = hdr + p, *nl = memchr(s, '\n', n - p);
        size_t m = nl ? (size_t)(nl - s) : n - p;
        p += m + 1;
        while (m && *s == ' ')
            s++, m--;
        if (m > k && strncasecmp(s, key, k) == 0) {
            const char *t = s + k;
            size_t r = m - k;
            while (r && *t == ' ')
                t++, r--;
            if (r && *t == '=') {
                t++, r--;
                ljgap__files_text(out, size, t, r);
                return 1;
            }
        }
    }
    return 0;
}

static int read_gsf(const unsigned char *buf, size_t len, const char *channel, ljgap__files_map *map,
                    ljgap__files_err *err)
{
    const unsigned char *nul = memchr(buf, '\0', len);
    char v[LJGAP_FILES_TEXT], *end;
    long xres, yres;
    int st;
    if (!probe(buf, len))
        return ljgap__files_fail(err, NAME, 0, NULL, "no \"" MAGIC "\" line at the start");
    if (!nul)
        return ljgap__files_fail(err, NAME, (long)len, NULL,
                                "the header has no NUL padding after it (truncated)");
    size_t hlen = (size_t)(nul - buf), data = (hlen / 4 + 1) * 4;
    const char *hdr = (const char *)buf;
    if (!get(hdr, hlen, "XRes", v, sizeof v) || (xres = strtol(v, &end, 10)) <= 0 || *end ||
        !get(hdr, hlen, "YRes", v, sizeof v) || (yres = strtol(v, &end, 10)) <= 0 || *end)
        return ljgap__files_fail(err, NAME, -1, NULL,
                                "XRes and YRes, the grid, must be positive whole numbers");
    ljgap__files_add_channel(map, get(hdr, hlen, "Title", v, sizeof v) && v[0] ? v : "Data");
    if (ljgap__files_channel_pick(map, channel, err) < 0) return LJGAP_FILES_CHANNEL;
    snprintf(map->channel, sizeof map->channel, "%s", map->channels[0]);
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    for (size_t i = hlen; i < data; i++)
        if (i < len && buf[i] != 0)
            return ljgap__files_fail(err, NAME, (long)i, NULL,
                                    "the header's NUL padding holds a byte that is not NUL");
    /* the data checked before the map is allocated: a header cannot claim memory it lacks */
    if ((unsigned long)xres > LJGAP_FILES_MAX_POINTS / (unsigned long)yres)
        return ljgap__files_alloc(map, (size_t)xres, (size_t)yres, err);
    size_t N = (size_t)xres * (size_t)yres;
    if (!ljgap__bytes_at(&b, data, 4 * N))
        return ljgap__files_fail(err, NAME, (long)len, NULL,
                                "%zu floats need %zu bytes after the header at %zu, the file has "
                                "%zu (truncated)",
                                N, 4 * N, data, len);
    if ((st = ljgap__files_alloc(map, (size_t)xres, (size_t)yres, err))) return st;
    ljgap__bytes_seek(&b, data);
    double zs = 1;
    if (get(hdr, hlen, "ZUnits", v, sizeof v)) {
        ljgap__files_text(map->z_unit, sizeof map->z_unit, v, strlen(v));
        double s = ljgap__files_unit_scale(v);
        if (s > 0) zs = s;
    }
    for (size_t i = 0; i < N; i++) {
        float f = ljgap__bytes_f32(&b, 0);
        map->z[i] = isfinite(f) ? zs * f : NAN;
    }
    double xreal = 0, yreal = 0, xs = 1;
    if (get(hdr, hlen, "XYUnits", v, sizeof v)) xs = ljgap__files_unit_scale(v);
    if (get(hdr, hlen, "XReal", v, sizeof v)) xreal = strtod(v, NULL);
    if (get(hdr, hlen, "YReal", v, sizeof v))
        yreal = strtod(v, NULL);
    else
        yreal = xreal * (double)yres / (double)xres;
    if (xs > 0 && isfinite(xreal) && isfinite(yreal) && xreal > 0 && yreal > 0)
        map->size_x = xs * xreal, map->size_y = xs * yreal;
    return 0;
}

const ljgap__files_format ljgap__files_gsf = {NAME, ".gsf", NULL, probe, read_gsf};
