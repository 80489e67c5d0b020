/* bytes.h -- bounded reads for the file readers (files.h): every read checks the offset and the
 * length against the buffer first, so a truncated or hostile file cannot make a reader look
 * past its end. A reader keeps a cursor {buf, len, pos}; a failed read sets bad (sticky) and
 * returns 0, so a reader may do a run of reads and test bad once.
 */
#ifndef LJGAP_FILES_BYTES_H
#define LJGAP_FILES_BYTES_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

typedef struct {
    const unsigned char *buf;
    size_t len;
    size_t pos;
    int bad;      /* a read went past the end (or a seek did) */
    size_t where; /* the offset of the first failed read */
} ljgap__bytes;

static inline void ljgap__bytes_init(ljgap__bytes *b, const unsigned char *buf, size_t len)
{
    b->buf = buf, b->len = len, b->pos = 0, b->bad = 0, b->where = 0;
}

/* Whether n bytes are there at pos (overflow-safe). */
static inline int ljgap__bytes_has(const ljgap__bytes *b, size_t pos, size_t n)
{
    return pos <= b->len && n <= b->len - pos;
}

static inline const unsigned char *ljgap__bytes_at(ljgap__bytes *b, size_t pos, size_t n)
{
    if (b->bad || !ljgap__bytes_has(b, pos, n)) {
        if (!b->bad) b->bad = 1, b->where = pos;
        return NULL;
    }
    return b->buf + pos;
}

static inline int ljgap__bytes_seek(ljgap__bytes *b, size_t pos)
{
    if (b->bad || pos > b->len) {
        if (!b->bad) b->bad = 1, b->where = pos;
        return -1;
    }
    b->pos = pos;
    return 0;
}

static inline uint64_t ljgap__bytes_uint(ljgap__bytes *b, size_t n, int big_endian)
{
    const unsigned char *p = ljgap__bytes_at(b, b->pos, n);
    uint64_t v = 0;
    if (!p) return 0;
    for (size_t i = 0; i < n; i++) v |= (uint64_t)p[big_endian ? n - 1 - i : i] << (8 * i);
    b->pos += n;
    return v;
}

static inline uint8_t ljgap__bytes_u8(ljgap__bytes *b) { return (uint8_t)ljgap__bytes_uint(b, 1, 0); }
static inline uint16_t ljgap__bytes_u16(ljgap__bytes *b, int be) { return (uint16_t)ljgap__bytes_uint(b, 2, be); }
static inline uint32_t ljgap__bytes_u32(ljgap__bytes *b, int be) { return (uint32_t)ljgap__bytes_uint(b, 4, be); }
static inline uint64_t ljgap__bytes_u64(ljgap__bytes *b, int be) { return ljgap__bytes_uint(b, 8, be); }
static inline int16_t ljgap__bytes_i16(ljgap__bytes *b, int be) { return (int16_t)ljgap__bytes_u16(b, be); }
static inline int32_t ljgap__bytes_i32(ljgap__bytes *b, int be) { return (int32_t)ljgap__bytes_u32(b, be); }

static inline float ljgap__bytes_f32(ljgap__bytes *b, int be)
{
    uint32_t u = ljgap__bytes_u32(b, be);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static inline double ljgap__bytes_f64(ljgap__bytes *b, int be)
{
    uint64_t u = ljgap__bytes_u64(b, be);
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

/* Copies n bytes at the cursor into out (NUL-terminated, at most size - 1 of them kept). */
static inline int ljgap__bytes_str(ljgap__bytes *b, size_t n, char *out, size_t size)
{
    const unsigned char *p = ljgap__bytes_at(b, b->pos, n);
    if (!p) {
        if (size) out[0] = 0;
        return -1;
    }
    size_t k = n < size - 1 ? n : size - 1;
    memcpy(out, p, k);
    out[k] = 0;
    b->pos += n;
    return 0;
}

#endif
