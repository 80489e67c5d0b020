/* files_util.h -- what the readers of server/files/ share (files_util.c), besides bytes.h: the
 * message of a failure, the map's allocation, channel titles. Not for the request layer
 * (files.h is its interface).
 */
#ifndef LJGAP_FILES_UTIL_H
#define LJGAP_FILES_UTIL_H

#include "files.h"

#include <stddef.h>

/* Fills err (format, offset or -1, member or NULL, a printf message); returns LJGAP_FILES_BAD. */
int ljgap__files_fail(ljgap__files_err *err, const char *format, long offset, const char *member,
                     const char *fmt, ...) __attribute__((format(printf, 5, 6)));
/* map->z for nx x ny points (map->nx, ny set): 0, LJGAP_FILES_BAD (an empty map),
 * LJGAP_FILES_TOOBIG (over LJGAP_FILES_MAX_POINTS) or LJGAP_FILES_NOMEM. */
int ljgap__files_alloc(ljgap__files_map *map, size_t nx, size_t ny, ljgap__files_err *err);
/* Appends a channel title (at most LJGAP_FILES_MAX_CHANNELS are kept). */
void ljgap__files_add_channel(ljgap__files_map *map, const char *title);
/* s[0..n) into out, trimmed, bytes outside printable ASCII as '?'. */
void ljgap__files_text(char *out, size_t size, const char *s, size_t n);

#endif
