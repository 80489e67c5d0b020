/* files_util.h -- what the readers of server/files/ share (files_util.c), besides bytes.h and
 * files.h's channel choice and length units: the report of a failure, the map's start and
 * allocation, a height's storing, channel titles and texts. Not for the request layer (files.h
 * is its interface).
 */
#ifndef LJGAP_FILES_UTIL_H
#define LJGAP_FILES_UTIL_H

#include "files.h"

#include <stddef.h>

/* Fills err (format, offset or -1, member or NULL, a printf message); returns LJGAP_FILES_BAD. */
int ljgap__files_fail(ljgap__files_err *err, const char *format, long offset, const char *member,
                     const char *fmt, ...) __attribute__((format(printf, 5, 6)));
/* The same with any code (LJGAP_FILES_CHANNEL, TOOBIG, NOMEM...): returns code; err may be NULL. */
int ljgap__files_report(ljgap__files_err *err, int code, const char *format, long offset,
                        const char *member, const char *fmt, ...)
    __attribute__((format(printf, 6, 7)));
/* Clears the map and names its reader (every field the reader does not set stays 0 or ""). */
void ljgap__files_map_init(ljgap__files_map *map, const char *format);
/* map->z for nx x ny points (map->nx, ny set): 0, LJGAP_FILES_BAD (an empty map),
 * LJGAP_FILES_TOOBIG (over LJGAP_FILES_MAX_POINTS) or LJGAP_FILES_NOMEM; a failure's offset is
 * -1 (ljgap__files_alloc) or offset, where the file states the size (ljgap__files_alloc_at). */
int ljgap__files_alloc(ljgap__files_map *map, size_t nx, size_t ny, ljgap__files_err *err);
int ljgap__files_alloc_at(ljgap__files_map *map, size_t nx, size_t ny, ljgap__files_err *err,
                          long offset);
/* Stores a height at map->z[k]: a non-finite value is a missing point (NaN, counted). */
void ljgap__files_put(ljgap__files_map *map, size_t k, double v);
/* A reader's read: read_file(buf, len, channel, map, err) with err->offset -1 to start with, and
 * a LJGAP_FILES_BAD fault's offset past the file's end (a length or an offset read from a
 * header may point there) put where the file ends. Returns read_file's code. */
int ljgap__files_read_within(int (*read_file)(const unsigned char *, size_t, const char *,
                                              ljgap__files_map *, ljgap__files_err *),
                             const unsigned char *buf, size_t len, const char *channel,
                             ljgap__files_map *map, ljgap__files_err *err);
/* Appends a channel title (at most LJGAP_FILES_MAX_CHANNELS are kept). */
void ljgap__files_add_channel(ljgap__files_map *map, const char *title);
/* s[0..n) into out, trimmed, bytes outside printable ASCII as '?'. */
void ljgap__files_text(char *out, size_t size, const char *s, size_t n);
/* A text field of at most n bytes at p (it ends at a NUL) into out as valid UTF-8: UTF-8
 * sequences are kept, any other byte above 0x7f is taken as Latin-1 (what older writers use),
 * control characters become '?'; at most size - 1 bytes, no sequence cut, leading blanks and
 * trailing blanks and '?' cut. */
void ljgap__files_utf8(const unsigned char *p, size_t n, char *out, size_t size);

#endif
