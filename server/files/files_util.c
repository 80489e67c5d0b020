/* files_util.c -- what the readers of server/files/ share (files_util.h): the message of a
 * failure, the map's allocation against LJGAP_FILES_MAX_POINTS, channel titles as text.
 */
#include "files_util.h"

#include <ctype.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int ljgap__files_fail(ljgap__files_err *err, const char *format, long offset, const char *member,
                     const char *fmt, ...)
{
    va_list ap;
    if (!err) return LJGAP_FILES_BAD;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
    err->format = format;
    err->offset = offset;
    snprintf(err->member, sizeof err->member, "%s", member ? member : "");
    return LJGAP_FILES_BAD;
}

int ljgap__files_alloc(ljgap__files_map *map, size_t nx, size_t ny, ljgap__files_err *err)
{
    if (nx == 0 || ny == 0)
        return ljgap__files_fail(err, map->format, -1, NULL, "a map of %zu x %zu points", nx, ny);
    if (nx > LJGAP_FILES_MAX_POINTS / ny) {
        ljgap__files_fail(err, map->format, -1, NULL,
                         "%zu x %zu points: more than the %u a map may have", nx, ny,
                         LJGAP_FILES_MAX_POINTS);
        return LJGAP_FILES_TOOBIG;
    }
    free(map->z);
    if (!(map->z = malloc(nx * ny * sizeof *map->z))) {
        snprintf(err->msg, sizeof err->msg, "out of memory for %zu x %zu points", nx, ny);
        return LJGAP_FILES_NOMEM;
    }
    map->nx = nx;
    map->ny = ny;
    return 0;
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
