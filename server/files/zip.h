/* zip.h -- one member out of a zip archive in memory, for the X3P reader (x3p.c): the central
 * directory is found from its end record, the member's local header checked, the bytes
 * inflated (stored or deflated members) and their CRC-32 checked. Every read is bounded.
 */
#ifndef LJGAP_FILES_ZIP_H
#define LJGAP_FILES_ZIP_H

#include <stddef.h>

#include "files.h"

/* Extracts the member `name` (its path in the archive) into a buffer it allocates (*out, with a
 * NUL byte after the *outlen bytes; free() it). Refuses members over maxlen bytes. Returns 0,
 * or LJGAP_FILES_BAD (err: format, the byte offset, the member), LJGAP_FILES_TOOBIG,
 * LJGAP_FILES_NOMEM. A missing member is LJGAP_FILES_BAD too. */
int ljgap__zip_extract(const unsigned char *buf, size_t len, const char *name, size_t maxlen,
                      unsigned char **out, size_t *outlen, const char *format,
                      ljgap__files_err *err);

#endif
