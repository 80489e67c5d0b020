/* files.c -- the registry of the instrument-file readers and what they share (files.h).
 *
 * ljgap__files_read recognises a file by content: every reader's probe (magic bytes and a look
 * at the structure) is asked in the registry's order, most specific first, the loosest (xyz
 * text columns) last; the first that says yes reads it. A format name forces that reader
 * (its own checks then say whether the bytes are that format: 422 bad-file, not 415).
 *
 * Here too: the choice of a channel from the titles a reader found (ljgap__files_channel_pick:
 * an index, a title, or the height channel by its name), length units to metres
 * (ljgap__files_unit_scale), the count of missing points, and the largest complete rectangle
 * of a map with holes, which is what the PSD is computed on (docs/topography.md, "Instrument
 * files"). What only the readers share (a failure's message, the map's allocation, channel
 * titles) is files_util.c's.
 */
#include "files.h"

#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* Most specific first: magic bytes (GWYP, the GSF line, a zip with main.xml, DIGITAL SURF, CDF,
 * MetroPro's, a TIFF with Park's tags), then NanoScope's text header, then the formats whose
 * recognition rests on structure more than on magic (an Igor wave's version and checksum, a
 * Sensofar header), xyz columns last. */
static const ljgap__files_format *const registry[] = {
    &ljgap__files_gwy,       &ljgap__files_gsf,      &ljgap__files_x3p,      &ljgap__files_sur,
    &ljgap__files_netcdf,    &ljgap__files_metropro, &ljgap__files_park_tiff, &ljgap__files_nanoscope,
    &ljgap__files_ibw,       &ljgap__files_plu,      &ljgap__files_xyz,      NULL};

const ljgap__files_format *const *ljgap__files_formats(void)
{
    return registry;
}

const ljgap__files_format *ljgap__files_find(const char *name)
{
    for (const ljgap__files_format *const *f = registry; *f; f++)
        if (strcasecmp((*f)->name, name) == 0) return *f;
    return NULL;
}

/* The names of the formats ("nanoscope, gwy, ..."), with their extensions when ext. */
static void names_of(char *out, size_t size, int ext)
{
    size_t k = 0;
    out[0] = '\0';
    for (const ljgap__files_format *const *f = registry; *f && k < size; f++) {
        int n = ext ? snprintf(out + k, size - k, "%s%s (%s)", k ? ", " : "", (*f)->name,
                               (*f)->extensions)
                    : snprintf(out + k, size - k, "%s%s", k ? ", " : "", (*f)->name);
        if (n < 0) break;
        k += (size_t)n;
    }
}

const ljgap__files_format *ljgap__files_detect(const unsigned char *buf, size_t len)
{
    for (const ljgap__files_format *const *f = registry; buf && len && *f; f++)
        if ((*f)->probe(buf, len)) return *f;
    return NULL;
}

void ljgap__files_names(char *out, size_t size)
{
    names_of(out, size, 1);
}

/* err's message and format (no offset, no member); LJGAP_FILES_BAD. */
static int set_err(ljgap__files_err *err, const char *format, const char *fmt, const char *arg)
{
    snprintf(err->msg, sizeof err->msg, fmt, arg);
    err->format = format;
    err->offset = -1;
    err->member[0] = '\0';
    return LJGAP_FILES_BAD;
}

/* Is the title one of a height channel's names? */
static int is_height_title(const char *t)
{
    static const char *const words[] = {"height",   "topograph", "zsensor", "z sensor",
                                        "z-sensor", "surface",   NULL};
    char low[LJGAP_FILES_TEXT];
    size_t i = 0;
    for (; t[i] && i + 1 < sizeof low; i++)
        low[i] = (char)tolower((unsigned char)t[i]);
    low[i] = '\0';
    for (int k = 0; words[k]; k++)
        if (strstr(low, words[k])) return 1;
    return 0;
}

/* The height channel among map->channels: the first title that starts with Height, else
 * Topography, else ZSensor (Asylum's layers, in that order of preference), else the first that
 * names a height (is_height_title), else channel 0. */
static int height_channel(const ljgap__files_map *map)
{
    static const char *const prefixes[] = {"Height", "Topography", "ZSensor"};
    for (size_t p = 0; p < sizeof prefixes / sizeof prefixes[0]; p++)
        for (int i = 0; i < map->n_channels; i++)
            if (!strncasecmp(map->channels[i], prefixes[p], strlen(prefixes[p]))) return i;
    for (int i = 0; i < map->n_channels; i++)
        if (is_height_title(map->channels[i])) return i;
    return 0;
}

int ljgap__files_channel_pick(const ljgap__files_map *map, const char *channel, ljgap__files_err *err)
{
    char list[LJGAP_FILES_MAX_CHANNELS * 24] = "";
    size_t k = 0;
    if (map->n_channels <= 0) {
        set_err(err, map->format, "%s", "the file holds no channel of data");
        return -1;
    }
    if (!channel || !*channel) return height_channel(map);
    if (strspn(channel, "0123456789") == strlen(channel) && strlen(channel) < 6) {
        int i = atoi(channel);
        if (i < map->n_channels) return i;
    } else {
        for (int i = 0; i < map->n_channels; i++) /* the exact title first, then any case */
            if (strcmp(map->channels[i], channel) == 0) return i;
        for (int i = 0; i < map->n_channels; i++)
            if (strcasecmp(map->channels[i], channel) == 0) return i;
    }
    for (int i = 0; i < map->n_channels && k < sizeof list; i++) {
        int n = snprintf(list + k, sizeof list - k, "%s%d \"%.16s\"", i ? ", " : "", i,
                         map->channels[i]);
        if (n < 0) break;
        k += (size_t)n;
    }
    snprintf(err->msg, sizeof err->msg, "no channel \"%.40s\": the file has %.180s", channel, list);
    err->format = map->format;
    err->offset = -1;
    err->member[0] = '\0';
    return -1;
}

double ljgap__files_unit_scale(const char *unit)
{
    static const struct {
        const char *name;
        double scale;
    } units[] = {{"m", 1},
                 {"mm", 1e-3},
                 {"um", 1e-6},
                 {"~m", 1e-6},
                 {"\xc2\xb5m", 1e-6},
                 {"\xb5m", 1e-6},
                 {"\xce\xbcm", 1e-6},
                 {"micron", 1e-6},
                 {"microns", 1e-6},
                 {"nm", 1e-9},
                 {"pm", 1e-12},
                 {"A", 1e-10},
                 {"\xc3\x85", 1e-10},
                 {"\xc5", 1e-10},
                 {"angstrom", 1e-10},
                 {"Angstrom", 1e-10},
                 {"km", 1e3},
                 {"cm", 1e-2},
                 {"dm", 1e-1},
                 {"meter", 1},
                 {"meters", 1},
                 {"metre", 1},
                 {"metres", 1}};
    char u[32];
    size_t n = 0;
    while (*unit == ' ' || *unit == '\t') /* surrounding blanks ignored */
        unit++;
    while (unit[n] && n < sizeof u - 1)
        u[n] = unit[n], n++;
    while (n && (u[n - 1] == ' ' || u[n - 1] == '\t'))
        n--;
    u[n] = '\0';
    for (size_t i = 0; i < sizeof units / sizeof units[0]; i++)
        if (strcmp(u, units[i].name) == 0) return units[i].scale;
    return 0;
}

size_t ljgap__files_count_missing(ljgap__files_map *map)
{
    size_t n = 0, N = map->nx * map->ny;
    for (size_t i = 0; i < N; i++)
        n += isnan(map->z[i]) != 0;
    map->missing = n;
    return n;
}

int ljgap__files_largest_rect(const ljgap__files_map *map, size_t *x0, size_t *y0, size_t *w,
                             size_t *h)
{
    /* the maximal rectangle of complete points: per row, the heights of the columns of
     * complete points ending there, then the largest rectangle under that histogram (a stack
     * of increasing heights); O(nx ny) */
    size_t nx = map->nx, ny = map->ny, best = 0;
    size_t *col = calloc(nx + 1, sizeof *col), *stack = malloc((nx + 1) * sizeof *stack);
    *x0 = *y0 = *w = *h = 0;
    if (!col || !stack) {
        free(col);
        free(stack);
        return -1;
    }
    for (size_t j = 0; j < ny; j++) {
        size_t top = 0;
        for (size_t i = 0; i < nx; i++)
            col[i] = isnan(map->z[j * nx + i]) ? 0 : col[i] + 1;
        col[nx] = 0;
        for (size_t i = 0; i <= nx; i++) {
            while (top && col[stack[top - 1]] >= col[i]) {
                size_t hh = col[stack[--top]];
                size_t left = top ? stack[top - 1] + 1 : 0, ww = i - left;
                if (hh * ww > best) {
                    best = hh * ww;
                    *x0 = left, *w = ww, *h = hh, *y0 = j + 1 - hh;
                }
            }
            stack[top++] = i;
        }
    }
    free(col);
    free(stack);
    return 0;
}

void ljgap__files_map_free(ljgap__files_map *map)
{
    if (!map) return;
    free(map->z);
    map->z = NULL;
    map->nx = map->ny = 0;
}

int ljgap__files_read(const unsigned char *buf, size_t len, const char *format, const char *channel,
                     ljgap__files_map *map, ljgap__files_err *err)
{
    const ljgap__files_format *f = NULL;
    char names[160];
    int st;
    memset(map, 0, sizeof *map);
    memset(err, 0, sizeof *err);
    err->offset = -1;
    if (!buf) len = 0;
    if (format && *format) {
        if (!(f = ljgap__files_find(format))) {
            names_of(names, sizeof names, 0);
            snprintf(err->msg, sizeof err->msg, "no format \"%.32s\": the formats read are %.160s",
                     format, names);
            return LJGAP_FILES_UNKNOWN;
        }
    } else {
        if (!(f = ljgap__files_detect(buf, len))) {
            names_of(names, sizeof names, 0);
            snprintf(err->msg, sizeof err->msg, "not a file of a format read here: %.160s", names);
            return LJGAP_FILES_UNKNOWN;
        }
    }
    map->format = f->name;
    err->format = f->name;
    st = len ? f->read(buf, len, channel && *channel ? channel : NULL, map, err)
             : set_err(err, f->name, "%s", "the file is empty");
    if (st == 0 && (!map->z || !map->nx || !map->ny))
        st = set_err(err, f->name, "%s", "the reader found no data");
    if (st == 0) {
        ljgap__files_count_missing(map);
        if (map->missing == map->nx * map->ny)
            st = set_err(err, f->name, "%s", "every point of the map is missing");
    }
    if (st) {
        ljgap__files_map_free(map);
        if (!err->format) err->format = f->name;
    }
    return st;
}
