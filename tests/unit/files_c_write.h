/* files_c_write.h -- writers of test files for tests/unit/test_files_c.c, each following its
 * format's documentation (not the readers' code): Igor binary waves of version 5 and 2
 * (WaveMetrics' IgorBin.h and WriteWave example: headers, checksum, data, note, labels), Park
 * Systems TIFF (a TIFF directory with Park's tags 50432-50435 and its image header) and Sensofar
 * PLu (the 500-byte header and float32 layers). The heights are exact in the stored types.
 */
#ifndef FILES_C_WRITE_H
#define FILES_C_WRITE_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* ---- a growing byte buffer, written in either byte order ---- */

typedef struct {
    unsigned char *p;
    size_t n, cap;
    int be;
} wbuf;

static void put(wbuf *b, const void *x, size_t n)
{
    if (b->n + n > b->cap) {
        b->cap = 2 * (b->n + n) + 64;
        b->p = realloc(b->p, b->cap);
        assert_non_null(b->p);
    }
    if (x)
        memcpy(b->p + b->n, x, n);
    else
        memset(b->p + b->n, 0, n);
    b->n += n;
}

static void put_uint_at(wbuf *b, size_t at, uint64_t v, int size)
{
    for (int i = 0; i < size; i++)
        b->p[at + (b->be ? size - 1 - i : i)] = (unsigned char)(v >> (8 * i));
}

static void put_uint(wbuf *b, uint64_t v, int size)
{
    put(b, NULL, (size_t)size);
    put_uint_at(b, b->n - (size_t)size, v, size);
}

static void put_f32(wbuf *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_uint(b, u, 4);
}

static void put_f64(wbuf *b, double d)
{
    uint64_t u;
    memcpy(&u, &d, 8);
    put_uint(b, u, 8);
}

static void put_f64_at(wbuf *b, size_t at, double d)
{
    uint64_t u;
    memcpy(&u, &d, 8);
    put_uint_at(b, at, u, 8);
}

static void put_str_at(wbuf *b, size_t at, const char *s)
{
    memcpy(b->p + at, s, strlen(s));
}

/* ---- Igor binary waves ---- */

/* The value written at Igor's index (i, j) of layer c: exact in every type used. */
static double igor_value(size_t i, size_t j, size_t c)
{
    return (double)i + 32.0 * (double)j + 1024.0 * (double)c - 300.0;
}

typedef struct {
    int be;            /* big endian */
    unsigned type;     /* 2, 4, 0x10, 0x20, 0x48 ... */
    size_t nx, ny, nl; /* nl 0: a 2-D wave */
    double dx, dy;     /* sfA */
    const char *data_unit, *dim_unit;
    const char *note;          /* NULL: none */
    const char *const *labels; /* nl titles or NULL */
    const char *data_eunits;   /* extended data units or NULL */
} igor_spec;

static void put_igor_value(wbuf *b, unsigned type, double v)
{
    switch (type) {
    case 2:
        put_f32(b, (float)v);
        break;
    case 4:
        put_f64(b, v);
        break;
    case 8:
    case 0x48:
        put_uint(b, (uint64_t)(int64_t)v, 1);
        break;
    case 0x10:
    case 0x50:
        put_uint(b, (uint64_t)(int64_t)v, 2);
        break;
    default:
        put_uint(b, (uint64_t)(int64_t)v, 4);
        break;
    }
}

static size_t igor_tsize(unsigned type)
{
    return type == 4 ? 8 : type == 2 || (type & 0x20) ? 4 : (type & 0x10) ? 2 : 1;
}

/* A version 5 wave as WaveMetrics' WriteVersion5NumericWave lays it out. */
static wbuf igor5(const igor_spec *s)
{
    wbuf b = {.be = s->be};
    size_t nl = s->nl ? s->nl : 1, npnts = s->nx * s->ny * nl, ts = igor_tsize(s->type);
    size_t note = s->note ? strlen(s->note) : 0;
    size_t eunits = s->data_eunits ? strlen(s->data_eunits) : 0;
    size_t labels = s->labels ? (nl + 1) * 32 : 0;
    put_uint(&b, 5, 2);
    put_uint(&b, 0, 2); /* checksum, below */
    put_uint(&b, 320 + npnts * ts, 4);
    put_uint(&b, 0, 4);                                          /* formula */
    put_uint(&b, note, 4);                                       /* note */
    put_uint(&b, eunits, 4);                                     /* dataEUnits */
    put(&b, NULL, 16);                                           /* dimEUnits */
    put(&b, NULL, 8), put_uint(&b, labels, 4), put(&b, NULL, 4); /* dimLabels: dim 2 only */
    put(&b, NULL, 12);
    assert_int_equal(b.n, 64);
    put(&b, NULL, 320);
    put_uint_at(&b, 64 + 4, 3786912000u, 4); /* 2024-01-01T00:00:00 in seconds since 1904 */
    put_uint_at(&b, 64 + 12, npnts, 4);
    put_uint_at(&b, 64 + 16, s->type, 2);
    put_str_at(&b, 64 + 28, "wave0");
    put_uint_at(&b, 64 + 68, s->nx, 4);
    put_uint_at(&b, 64 + 72, s->ny, 4);
    put_uint_at(&b, 64 + 76, s->nl, 4);
    put_f64_at(&b, 64 + 84, s->dx);
    put_f64_at(&b, 64 + 92, s->dy);
    put_str_at(&b, 64 + 148, s->data_unit);
    put_str_at(&b, 64 + 152, s->dim_unit);
    put_str_at(&b, 64 + 156, s->dim_unit);
    unsigned sum = 0;
    for (size_t i = 0; i < 384; i += 2)
        sum += s->be ? (unsigned)b.p[i] << 8 | b.p[i + 1] : b.p[i] | (unsigned)b.p[i + 1] << 8;
    put_uint_at(&b, 2, (0x10000 - (sum & 0xffff)) & 0xffff, 2);
    for (size_t c = 0; c < nl; c++)
        for (size_t j = 0; j < s->ny; j++)
            for (size_t i = 0; i < s->nx; i++)
                put_igor_value(&b, s->type, igor_value(i, j, c));
    if (note) put(&b, s->note, note);
    if (eunits) put(&b, s->data_eunits, eunits);
    if (labels) {
        put(&b, NULL, 32);
        for (size_t c = 0; c < nl; c++) {
            put(&b, NULL, 32);
            memcpy(b.p + b.n - 32, s->labels[c], strlen(s->labels[c]));
        }
    }
    return b;
}

/* A version 2 wave (a profile): BinHeader2, WaveHeader2, data, 16 bytes of padding, note. */
static wbuf igor2(int be, size_t n, const char *note)
{
    wbuf b = {.be = be};
    size_t nlen = strlen(note);
    put_uint(&b, 2, 2);
    put_uint(&b, 110 + 4 * n + 16, 4);
    put_uint(&b, nlen, 4);
    put_uint(&b, 0, 4);
    put_uint(&b, 0, 2); /* checksum */
    put(&b, NULL, 110);
    put_uint_at(&b, 16 + 0, 2, 2); /* NT_FP32 */
    put_str_at(&b, 16 + 2 + 4, "prof");
    put_str_at(&b, 16 + 34, "nm");
    put_str_at(&b, 16 + 38, "um");
    put_uint_at(&b, 16 + 42, n, 4);
    put_f64_at(&b, 16 + 48, 0.25);
    for (size_t i = 0; i < n; i++)
        put_f32(&b, (float)igor_value(i, 0, 0));
    put(&b, NULL, 16);
    put(&b, note, nlen);
    unsigned sum = 0; /* over the headers and the first 16 bytes of data, as Igor does */
    for (size_t i = 0; i < 16 + 126; i += 2)
        sum += be ? (unsigned)b.p[i] << 8 | b.p[i + 1] : b.p[i] | (unsigned)b.p[i + 1] << 8;
    put_uint_at(&b, 14, (0x10000 - (sum & 0xffff)) & 0xffff, 2);
    return b;
}

/* ---- Park Systems TIFF ---- */

typedef struct {
    int version;    /* 1 or 2 */
    unsigned dtype; /* 0 int16, 1 int32, 2 float32 */
    size_t xres, yres;
    double gain, zscale, zoff;
    const char *unit, *source;
    int swap;
    int park;         /* 0: a plain TIFF (no Park tags) */
    int short_header; /* the header tag shorter than the version's minimum */
} park_spec;

static double park_raw(size_t i, size_t j)
{
    return (double)i - 3.0 * (double)j + 11.0;
}

static void put_utf16_at(wbuf *b, size_t at, const char *s)
{
    for (size_t i = 0; s[i]; i++)
        b->p[at + 2 * i] = (unsigned char)s[i], b->p[at + 2 * i + 1] = 0;
}

/* A TIFF: the header, a preview strip, Park's header and data blobs, then the directory. */
static wbuf park_tiff(const park_spec *s)
{
    wbuf b = {.be = 0};
    size_t hlen = s->version == 1 ? 356 : 580, n = s->xres * s->yres;
    size_t bps = s->dtype == 0 ? 2 : 4;
    if (s->short_header) hlen -= 1;
    put(&b, "II*\0", 4);
    put_uint(&b, 0, 4); /* the directory's offset, below */
    size_t thumb = b.n;
    for (size_t i = 0; i < n; i++)
        put_uint(&b, i & 0xff, 1);
    if (b.n & 1) put(&b, NULL, 1);
    size_t head = b.n;
    put(&b, NULL, hlen);
    put_utf16_at(&b, head + 4, s->source);
    put_utf16_at(&b, head + 68, "AFM");
    put_uint_at(&b, head + 100, s->xres, 4);
    put_uint_at(&b, head + 104, s->yres, 4);
    put_uint_at(&b, head + 136, (uint64_t)s->swap, 4);
    put_f64_at(&b, head + 140, 8.0); /* µm */
    put_f64_at(&b, head + 148, 4.0);
    put_f64_at(&b, head + 220, s->gain);
    put_f64_at(&b, head + 228, s->zscale);
    put_f64_at(&b, head + 236, s->zoff);
    put_utf16_at(&b, head + 244, s->unit);
    if (s->version == 2) put_uint_at(&b, head + 348, s->dtype, 4);
    size_t data = b.n;
    for (size_t j = 0; j < s->yres; j++)
        for (size_t i = 0; i < s->xres; i++) {
            if (s->dtype == 2)
                put_f32(&b, (float)park_raw(i, j));
            else
                put_uint(&b, (uint64_t)(int64_t)park_raw(i, j), (int)bps);
        }
    size_t date = b.n;
    put(&b, "2023:04:05 06:07:08", 20);
    size_t ifd = b.n;
    put_uint_at(&b, 4, ifd, 4);
    struct {
        unsigned tag, type;
        uint32_t count, value;
    } e[] = {{256, 4, 1, (uint32_t)s->xres},
             {257, 4, 1, (uint32_t)s->yres},
             {258, 3, 1, 8},
             {259, 3, 1, 1},
             {262, 3, 1, 1},
             {273, 4, 1, (uint32_t)thumb},
             {277, 3, 1, 1},
             {278, 4, 1, (uint32_t)s->yres},
             {279, 4, 1, (uint32_t)n},
             {306, 2, 20, (uint32_t)date},
             {50432, 4, 1, 0x0E031301},
             {50433, 4, 1, s->version == 1 ? 0x01000001 : 0x01000002},
             {50434, 1, (uint32_t)(n * bps), (uint32_t)data},
             {50435, 1, (uint32_t)hlen, (uint32_t)head}};
    size_t ne = s->park ? sizeof e / sizeof e[0] : 10;
    put_uint(&b, ne, 2);
    for (size_t i = 0; i < ne; i++) {
        put_uint(&b, e[i].tag, 2), put_uint(&b, e[i].type, 2), put_uint(&b, e[i].count, 4);
        if (e[i].type == 3)
            put_uint(&b, e[i].value, 2), put_uint(&b, 0, 2);
        else
            put_uint(&b, e[i].value, 4);
    }
    put_uint(&b, 0, 4);
    return b;
}

/* ---- Sensofar PLu ---- */

static float plu_value(size_t i, size_t j, size_t layer)
{
    return (float)((double)i * 0.5 - (double)j * 0.25 + 100.0 * (double)layer);
}

static wbuf plu_file(size_t nx, size_t ny, size_t layers, unsigned type, unsigned version)
{
    wbuf b = {.be = 0};
    put(&b, NULL, 500);
    put_str_at(&b, 0, "Tue Mar  5 14:03:09 2024");
    put_uint_at(&b, 388, ny, 4);
    put_uint_at(&b, 392, nx, 4);
    float mppx = 0.5f, mppy = 0.75f;
    memcpy(b.p + 404, &mppx, 4), memcpy(b.p + 408, &mppy, 4);
    put_uint_at(&b, 428, type, 4);
    b.p[489] = (unsigned char)layers, b.p[490] = (unsigned char)version, b.p[491] = 4;
    for (size_t l = 0; l < (layers ? layers : 1); l++) {
        put_uint(&b, ny, 4), put_uint(&b, nx, 4);
        for (size_t j = 0; j < ny; j++)
            for (size_t i = 0; i < nx; i++)
                put_f32(&b, (i + j + l) % 7 == 3 ? 1000001.0f : plu_value(i, j, l));
        put_f32(&b, -1), put_f32(&b, 1);
    }
    return b;
}

#endif
