/* util_b.h -- small helpers the X3P, netCDF, Digital Surf and MetroPro readers share (issue 28):
 * the error report (format, byte offset or container member, message), the map's allocation
 * with the point limit, the channel choice by index or title, and length units by name.
 * Static functions only, so each reader stays one file with no new link-time names.
 */
#ifndef LJGAP_FILES_UTIL_B_H
#define LJGAP_FILES_UTIL_B_H

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "files.h"

/* Fills err (when given) and returns code: msg printf-style, offset -1 when none applies,
 * member NULL when the file is not a container. */
static inline int ljgap__fb_fail(ljgap__files_err *err, int code, const char *format, long offset,
                                const char *member, const char *fmt, ...)
    __attribute__((format(printf, 6, 7)));
static inline int ljgap__fb_fail(ljgap__files_err *err, int code, const char *format, long offset,
                                const char *member, const char *fmt, ...)
{
    if (!err) return code;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
    err->format = format;
    err->offset = offset;
    snprintf(err->member, sizeof err->member, "%s", member ? member : "");
    return code;
}

/* Clears the map and names its reader (every field a reader does not set stays 0 or ""). */
static inline void ljgap__fb_map_init(ljgap__files_map *map, const char *format)
{
    memset(map, 0, sizeof *map);
    map->format = format;
}

/* Allocates map->z for nx * ny points: LJGAP_FILES_BAD for an empty grid, TOOBIG past the
 * limit, NOMEM. */
static inline int ljgap__fb_alloc(ljgap__files_map *map, size_t nx, size_t ny, ljgap__files_err *err,
                                 const char *format, long offset)
{
    if (nx == 0 || ny == 0)
        return ljgap__fb_fail(err, LJGAP_FILES_BAD, format, offset, NULL,
                             "the grid is empty (%zu x %zu points)", nx, ny);
    if (nx > LJGAP_FILES_MAX_POINTS || ny > LJGAP_FILES_MAX_POINTS / nx)
        return ljgap__fb_fail(err, LJGAP_FILES_TOOBIG, format, offset, NULL,
                             "%zu x %zu points exceed the limit of %u", nx, ny,
                             (unsigned)LJGAP_FILES_MAX_POINTS);
    map->z = malloc(nx * ny * sizeof *map->z);
    if (!map->z) return ljgap__fb_fail(err, LJGAP_FILES_NOMEM, format, -1, NULL, "out of memory");
    map->nx = nx, map->ny = ny;
    return 0;
}

/* Stores a height: a non-finite value is a missing point (NaN, counted). */
static inline void ljgap__fb_put(ljgap__files_map *map, size_t k, double v)
{
    if (isfinite(v))
        map->z[k] = v;
    else
        map->z[k] = NAN, map->missing++;
}

/* The channel asked for, among map->channels[0 .. n_channels): NULL or "" the default dflt,
 * else a decimal index or a title (case-insensitive). -1 when there is no such channel. */
static inline int ljgap__fb_channel(const ljgap__files_map *map, const char *channel, int dflt)
{
    if (!channel || !*channel) return dflt;
    char *end;
    long i = strtol(channel, &end, 10);
    if (*end == 0 && end != channel) return i >= 0 && i < map->n_channels ? (int)i : -1;
    for (int c = 0; c < map->n_channels; c++)
        if (!strcasecmp(map->channels[c], channel)) return c;
    return -1;
}

/* Metres per unit for a length unit's name (surrounding blanks ignored): m, mm, um (also µm in
 * UTF-8 or Latin-1, and "micron"), nm, pm, A (Å), km. Returns 0 for an unknown name. */
static inline double ljgap__fb_length_unit(const char *unit)
{
    char u[32];
    size_t n = 0;
    while (*unit == ' ' || *unit == '\t')
        unit++;
    while (unit[n] && n < sizeof u - 1)
        u[n] = unit[n], n++;
    while (n && (u[n - 1] == ' ' || u[n - 1] == '\t'))
        n--;
    u[n] = 0;
    static const struct {
        const char *name;
        double f;
    } units[] = {{"m", 1},        {"mm", 1e-3},        {"um", 1e-6},     {"\xc2\xb5m", 1e-6},
                 {"\xb5m", 1e-6}, {"\xce\xbcm", 1e-6}, {"micron", 1e-6}, {"microns", 1e-6},
                 {"nm", 1e-9},    {"pm", 1e-12},       {"A", 1e-10},     {"\xc3\x85", 1e-10},
                 {"\xc5", 1e-10}, {"km", 1e3},         {"cm", 1e-2},     {"dm", 1e-1},
                 {"meter", 1},    {"meters", 1},       {"metre", 1},     {"metres", 1}};
    for (size_t i = 0; i < sizeof units / sizeof units[0]; i++)
        if (!strcmp(u, units[i].name)) return units[i].f;
    return 0;
}

/* Copies n bytes of a fixed-size text field (Latin-1, NUL- or blank-padded) into out as UTF-8,
 * blanks trimmed, control characters dropped. */
static inline void ljgap__fb_text(const unsigned char *p, size_t n, char *out, size_t size)
{
    size_t k = 0;
    for (size_t i = 0; i < n && p[i]; i++) {
        unsigned c = p[i];
        if (c < 0x20 || c == 0x7f) continue;
        if (c < 0x80) {
            if (k + 1 >= size) break;
            out[k++] = (char)c;
        } else {
            if (k + 2 >= size) break;
            out[k++] = (char)(0xc0 | c >> 6), out[k++] = (char)(0x80 | (c & 0x3f));
        }
    }
    while (k && out[k - 1] == ' ')
        k--;
    out[k] = 0;
    size_t lead = 0;
    while (out[lead] == ' ')
        lead++;
    if (lead) memmove(out, out + lead, k - lead + 1);
}

#endif
