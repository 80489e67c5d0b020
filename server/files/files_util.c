/* files_util.c -- what the readers of server/files/ share (files_util.h): the report of a
 * failure, the map's allocation against LJGAP_FILES_MAX_POINTS, channel titles and texts.
 */
#include "files_util.h"

#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int vreport(ljgap__files_err *err, int code, const char *format, long offset,
                   const char *member, const char *fmt, va_list ap)
{
    if (!err) return code;
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    err->format = format;
    err->offset = offset;
    snprintf(err->member, sizeof err->member, "%s", member ? member : "");
    return code;
}

int ljgap__files_fail(ljgap__files_err *err, const char *format, long offset, const char *member,
                     const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = vreport(err, LJGAP_FILES_BAD, format, offset, member, fmt, ap);
    va_end(ap);
    return rc;
}

int ljgap__files_report(ljgap__files_err *err, int code, const char *format, long offset,
                        const char *member, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = vreport(err, code, format, offset, member, fmt, ap);
    va_end(ap);
    return rc;
}

void ljgap__files_map_init(ljgap__files_map *map, const char *format)
{
    memset(map, 0, sizeof *map);
    map->format = format;
}

int ljgap__files_alloc(ljgap__files_map *map, size_t nx, size_t ny, ljgap__files_err *err)
{
    return ljgap__files_alloc_at(map, nx, ny, err, -1);
}

int ljgap__files_alloc_at(ljgap__files_map *map, size_t nx, size_t ny, ljgap__files_err *err,
                          long offset)
{
    if (nx == 0 || ny == 0)
        return ljgap__files_fail(err, map->format, offset, NULL, "a map of %zu x %zu points", nx,
                                 ny);
    if (nx > LJGAP_FILES_MAX_POINTS / ny)
        return ljgap__files_report(err, LJGAP_FILES_TOOBIG, map->format, offset, NULL,
                                   "%zu x %zu points: more than the %u a map may have", nx, ny,
                                   LJGAP_FILES_MAX_POINTS);
    free(map->z);
    if (!(map->z = malloc(nx * ny * sizeof *map->z)))
        return ljgap__files_report(err, LJGAP_FILES_NOMEM, map->format, -1, NULL,
                                   "out of memory for %zu x %zu points", nx, ny);
    map->nx = nx;
    map->ny = ny;
    return 0;
}

void ljgap__files_put(ljgap__files_map *map, size_t k, double v)
{
    if (isfinite(v))
        map->z[k] = v;
    else
        map->z[k] = NAN, map->missing++;
}

int ljgap__files_read_within(int (*read_file)(const unsigned char *, size_t, const char *,
                                              ljgap__files_map *, ljgap__files_err *),
                             const unsigned char *buf, size_t len, const char *channel,
                             ljgap__files_map *map, ljgap__files_err *err)
{
    err->offset = -1;
    int rc = read_file(buf, len, channel, map, err);
    if (rc == LJGAP_FILES_BAD && err->offset > (long)len) err->offset = (long)len;
    return rc;
}

void ljgap__files_add_channel(ljgap__files_map *map, const char *title)
{
    if (map->n_channels >= LJGAP_FILES_MAX_CHANNELS) return;
    ljgap__files_text(map->channels[map->n_channels++], LJGAP_FILES_TEXT, title, strlen(title));
}

void ljgap__files_text(char *out, size_t size, const char *s, size_t n)
{
    size_t k = 0;
    while (n && isspace((unsigned char)*s))
        s++, n--;
    while (n && (isspace((unsigned char)s[n - 1]) || s[n - 1] == '\0'))
        n--;
    /* printable ASCII and whole UTF-8 sequences kept; other bytes (Latin-1) become '?' */
    for (size_t i = 0; i < n && k + 1 < size && s[i]; i++) {
        unsigned char c = (unsigned char)s[i];
        out[k++] = (c >= 0x20 && c < 0x7f) ? (char)c : '?';
    }
    out[k] = '\0';
}

void ljgap__files_utf8(const unsigned char *p, size_t n, char *out, size_t size)
{
    size_t i = 0, k = 0;
    while (i < n && (p[i] == ' ' || p[i] == '\t'))
        i++;
    while (i < n && p[i]) {
        unsigned char c = p[i], u[4];
        size_t m = 1, take = 1;
        if (c >= 0x80) {
            size_t need = c >= 0xc2 && c <= 0xdf ? 2 : c >= 0xe0 && c <= 0xef ? 3 : 0;
            size_t j = 1;
            while (need && j < need && i + j < n && (p[i + j] & 0xc0) == 0x80)
                j++;
            if (need && j == need && !(c == 0xe0 && p[i + 1] < 0xa0) &&
                !(c == 0xed && p[i + 1] >= 0xa0)) {
                memcpy(u, p + i, need), m = take = need;
            } else {
                u[0] = (unsigned char)(0xc0 | c >> 6), u[1] = (unsigned char)(0x80 | (c & 0x3f));
                m = 2;
            }
        } else {
            u[0] = c < 0x20 || c == 0x7f ? '?' : c;
        }
        if (k + m + 1 > size) break;
        memcpy(out + k, u, m), k += m, i += take;
    }
    out[k] = 0;
    while (k && (out[k - 1] == ' ' || out[k - 1] == '?'))
        out[--k] = 0;
}
