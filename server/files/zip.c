/* zip.c -- one member out of a zip archive in memory (zip.h), after PKWARE's APPNOTE.TXT: the
 * end of central directory record (signature 0x06054b50, within the last 64 KiB + 22 bytes),
 * its central directory (entries 0x02014b50: method, CRC-32, sizes, name, local header offset)
 * and the member's local header (0x04034b50: its name and extra field lengths place the data).
 * Sizes and the CRC come from the central directory, so members written with a data
 * descriptor read too. Methods: 0 (stored) and 8 (deflate, through zlib's raw inflate).
 * Not read: encrypted members, zip64 archives (over 4 GiB), other methods.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <zlib.h>

#include "bytes.h"
#include "files_util.h"
#include "zip.h"

int ljgap__zip_extract(const unsigned char *buf, size_t len, const char *name, size_t maxlen,
                      unsigned char **out, size_t *outlen, const char *format, ljgap__files_err *err)
{
    *out = NULL, *outlen = 0;
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    /* the end record: the last signature from which its fixed 22 bytes fit */
    size_t eocd = (size_t)-1;
    if (len >= 22)
        for (size_t p = len - 22 + 1, stop = len > 65557 ? len - 65557 : 0; p-- > stop;)
            if (buf[p] == 0x50 && buf[p + 1] == 0x4b && buf[p + 2] == 5 && buf[p + 3] == 6) {
                eocd = p;
                break;
            }
    if (eocd == (size_t)-1)
        return ljgap__files_fail(err, format, (long)len, NULL,
                                 "no zip central directory: the archive is cut short or damaged");
    ljgap__bytes_seek(&b, eocd + 10);
    unsigned entries = ljgap__bytes_u16(&b, 0);
    uint32_t cdsize = ljgap__bytes_u32(&b, 0), cdoff = ljgap__bytes_u32(&b, 0);
    if (b.bad || cdoff > eocd || cdsize > eocd - cdoff)
        return ljgap__files_fail(err, format, (long)eocd, NULL,
                                 "the zip central directory (%u bytes at %u) lies outside the "
                                 "archive",
                                 cdsize, cdoff);
    size_t nlen = strlen(name), at = cdoff;
    for (unsigned e = 0; e < entries; e++) {
        size_t entry = at; /* this entry's offset */
        ljgap__bytes_seek(&b, at);
        uint32_t sig = ljgap__bytes_u32(&b, 0);
        if (b.bad || sig != 0x02014b50)
            return ljgap__files_fail(err, format, (long)(at < len ? at : len), NULL,
                                     "zip central directory entry %u is damaged", e);
        ljgap__bytes_seek(&b, at + 8);
        unsigned flags = ljgap__bytes_u16(&b, 0), method = ljgap__bytes_u16(&b, 0);
        ljgap__bytes_seek(&b, at + 16);
        uint32_t crc = ljgap__bytes_u32(&b, 0), csize = ljgap__bytes_u32(&b, 0),
                 usize = ljgap__bytes_u32(&b, 0);
        unsigned namelen = ljgap__bytes_u16(&b, 0), extra = ljgap__bytes_u16(&b, 0),
                 comment = ljgap__bytes_u16(&b, 0);
        ljgap__bytes_seek(&b, at + 42);
        uint32_t local = ljgap__bytes_u32(&b, 0);
        const unsigned char *ename = ljgap__bytes_at(&b, at + 46, namelen);
        if (!ename)
            return ljgap__files_fail(err, format, (long)b.where, NULL,
                                     "zip central directory entry %u is cut short", e);
        at += 46 + (size_t)namelen + extra + comment;
        if (namelen != nlen || memcmp(ename, name, nlen)) continue;

        /* the member */
        if (flags & 1)
            return ljgap__files_fail(err, format, (long)entry, name, "the member is encrypted");
        if (method != 0 && method != 8)
            return ljgap__files_fail(err, format, (long)entry, name,
                                     "compression method %u: only stored (0) and deflate (8) are "
                                     "read",
                                     method);
        if (usize > maxlen)
            return ljgap__files_report(err, LJGAP_FILES_TOOBIG, format, (long)entry, name,
                                       "the member has %u bytes, more than the %zu allowed", usize,
                                       maxlen);
        ljgap__bytes_seek(&b, local);
        sig = ljgap__bytes_u32(&b, 0);
        ljgap__bytes_seek(&b, (size_t)local + 26);
        unsigned lname = ljgap__bytes_u16(&b, 0), lextra = ljgap__bytes_u16(&b, 0);
        if (b.bad || sig != 0x04034b50)
            return ljgap__files_fail(err, format, (long)(local < len ? local : len), name,
                                     "the member's local header is missing or damaged");
        size_t data = (size_t)local + 30 + lname + lextra;
        const unsigned char *src = ljgap__bytes_at(&b, data, csize);
        if (!src)
            return ljgap__files_fail(err, format, (long)len, name,
                                     "the member (%u bytes from byte %zu) is cut short", csize,
                                     data);
        unsigned char *dst = malloc((size_t)usize + 1);
        if (!dst)
            return ljgap__files_report(err, LJGAP_FILES_NOMEM, format, -1, name, "out of memory");
        if (method == 0) {
            if (csize != usize) {
                free(dst);
                return ljgap__files_fail(err, format, (long)entry, name,
                                         "a stored member of %u bytes claims %u", csize, usize);
            }
            memcpy(dst, src, usize);
        } else {
            z_stream zs;
            memset(&zs, 0, sizeof zs);
            if (inflateInit2(&zs, -15) != Z_OK) {
                free(dst);
                return ljgap__files_report(err, LJGAP_FILES_NOMEM, format, -1, name,
                                           "out of memory");
            }
            zs.next_in = (unsigned char *)(uintptr_t)src, zs.avail_in = csize;
            zs.next_out = dst, zs.avail_out = usize;
            int rc = inflate(&zs, Z_FINISH);
            size_t got = usize - zs.avail_out, used = csize - zs.avail_in;
            inflateEnd(&zs);
            if (rc != Z_STREAM_END || got != usize) {
                free(dst);
                return ljgap__files_fail(err, format, (long)(data + used), name,
                                         "the deflated member does not inflate to its %u bytes",
                                         usize);
            }
        }
        if (crc32(0L, dst, usize) != crc) {
            free(dst);
            return ljgap__files_fail(err, format, (long)data, name,
                                     "the member's CRC-32 does not match: it is damaged");
        }
        dst[usize] = 0;
        *out = dst, *outlen = usize;
        return 0;
    }
    return ljgap__files_fail(err, format, -1, name, "the archive has no member %s", name);
}
