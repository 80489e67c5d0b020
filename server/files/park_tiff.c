/* park_tiff.c -- Park Systems (formerly PSIA) AFM images: a TIFF whose picture is only a preview
 * and whose heights sit in private tags.
 *
 * The file is a classic little-endian TIFF ("II*\0": Park writes no other, and Gwyddion takes a
 * big-endian one for a plain picture, so that is refused). A small IFD walker of our own
 * (bounded: the entry count is checked against the bytes left, every value goes through
 * bytes.h, the next-directory offset must be there) finds the tags of the first directory.
 * Park's tags, as Gwyddion's psia module and SurfaceTopography describe them:
 *   50432  magic, LONG 0x0E031301 (a TIFF without it is not claimed: a plain TIFF is not Park's)
 *   50433  version, LONG 0x01000001 or 0x01000002
 *   50434  the data, BYTE[n], little endian, row after row: int16 (version 1), or as the
 *          header's data type says (version 2: 0 int16, 1 int32, 2 float32)
 *   50435  the image header, BYTE[n] (at least 356 bytes in version 1, 580 in version 2), little
 *          endian: image type (u32 at 0: 0 a 2-D image; line profiles and spectroscopy are not
 *          read), source name (the channel, UTF-16, 32 units at 4), image mode (8 at 68), xres,
 *          yres (u32 at 100, 104), swap_xy (u32 at 136: the fast axis was y; the data are in
 *          image order all the same), the scan size in µm (doubles at 140, 148), data gain,
 *          z scale, z offset (doubles at 220, 228, 236), z unit (UTF-16, 8 at 244); version 2:
 *          the data type (u32 at 348)
 *   306    DateTime ("YYYY:MM:DD HH:MM:SS"); 271, 272 Make and Model, where written.
 * A height is data_gain * (raw * z_scale + z_offset) in the z unit (z_scale 0 means 1), as
 * Gwyddion computes it, converted to metres when the unit is a length (um, nm, m...). The rows
 * are stored bottom first, so they come out reversed, as Gwyddion shows them (Gwyddion once also
 * turned swap_xy maps a quarter turn; 2.62 no longer does, and neither do we). Non-finite floats
 * are missing points. One channel a file (Park writes a file per channel); the instrument is
 * "Park Systems" (the magic says so), or the Make and Model tags where present.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bytes.h"
#include "files.h"
#include "files_util.h"

#define NAME "park-tiff"
#define PARK_MAGIC 0x0E031301u
#define PARK_V1 0x01000001u
#define PARK_V2 0x01000002u
#define MAX_ENTRIES 4096 /* a directory longer than this is not a Park file's */

/* A fault at a byte offset (files_util.h). */
#define bad(err, offset, ...) ljgap__files_fail(err, NAME, offset, NULL, __VA_ARGS__)

/* One tag of the first directory: where its value lies and how long it is. */
typedef struct {
    int found;      /* the tag is there */
    unsigned type;  /* TIFF type (1 BYTE, 2 ASCII, 3 SHORT, 4 LONG, 7 UNDEFINED...) */
    uint32_t count; /* number of values */
    size_t at;      /* the offset of the value (inline in the entry when it fits 4 bytes) */
    size_t len;     /* its length in bytes */
    size_t entry;   /* the offset of the entry (for messages) */
} tiff_tag;

enum { T_MAKE, T_MODEL, T_DATETIME, T_MAGIC, T_VERSION, T_DATA, T_HEADER, T_N };
static const unsigned tag_ids[T_N] = {271, 272, 306, 50432, 50433, 50434, 50435};

/* Walks the first directory: 0, or -1 with *where the offset of the fault (not a TIFF, a
 * directory or a value outside the file). Values are located, not read. */
static int tiff_walk(ljgap__bytes *b, int *be, tiff_tag tags[T_N], size_t *where)
{
    static const unsigned type_size[] = {0, 1, 1, 2, 4, 8, 1, 1, 2, 4, 8, 4, 8};
    const unsigned char *h = ljgap__bytes_at(b, 0, 8);
    memset(tags, 0, T_N * sizeof *tags);
    *where = 0;
    if (!h) return -1;
    if (!memcmp(h, "II*\0", 4))
        *be = 0;
    else if (!memcmp(h, "MM\0*", 4))
        *be = 1;
    else
        return -1;
    ljgap__bytes_seek(b, 4);
    size_t ifd = ljgap__bytes_u32(b, *be);
    ljgap__bytes_seek(b, ifd);
    unsigned n = ljgap__bytes_u16(b, *be);
    if (b->bad || n > MAX_ENTRIES || !ljgap__bytes_has(b, ifd + 2, (size_t)n * 12 + 4)) {
        *where = b->bad ? b->where : ifd;
        return -1;
    }
    for (unsigned i = 0; i < n; i++) {
        size_t e = ifd + 2 + (size_t)i * 12;
        ljgap__bytes_seek(b, e);
        unsigned id = ljgap__bytes_u16(b, *be), type = ljgap__bytes_u16(b, *be);
        uint32_t count = ljgap__bytes_u32(b, *be);
        for (int t = 0; t < T_N; t++) {
            if (id != tag_ids[t]) continue;
            unsigned ts = type < sizeof type_size / sizeof type_size[0] ? type_size[type] : 0;
            tiff_tag *g = &tags[t];
            g->found = 1, g->type = type, g->count = count, g->entry = e;
            g->len = (size_t)count * (ts ? ts : 1);
            g->at = g->len <= 4 ? e + 8 : ljgap__bytes_u32(b, *be);
            if (!ts || !ljgap__bytes_has(b, g->at, g->len)) {
                *where = ts ? g->at : e;
                return -1;
            }
        }
    }
    return b->bad ? (*where = b->where, -1) : 0;
}

/* A SHORT or LONG tag's single value, or ~0u. */
static uint32_t tag_uint(ljgap__bytes *b, const tiff_tag *g, int be)
{
    if (!g->found || g->count != 1 || (g->type != 3 && g->type != 4)) return ~0u;
    ljgap__bytes_seek(b, g->at);
    return g->type == 3 ? ljgap__bytes_u16(b, be) : ljgap__bytes_u32(b, be);
}

static int park_probe(const unsigned char *buf, size_t len)
{
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    tiff_tag tags[T_N];
    int be;
    size_t where;
    if (tiff_walk(&b, &be, tags, &where) || be) return 0;
    return tag_uint(&b, &tags[T_MAGIC], be) == PARK_MAGIC;
}

/* A UTF-16LE string of n units at p as UTF-8 (BMP only; stops at NUL; unpaired surrogates
 * become '?'). */
static void utf16(const unsigned char *p, size_t n, char *out, size_t size)
{
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        unsigned c = p[2 * i] | (unsigned)p[2 * i + 1] << 8;
        if (!c) break;
        if (c >= 0xd800 && c < 0xe000) c = '?';
        unsigned char u[3];
        size_t m = c < 0x80 ? 1 : c < 0x800 ? 2 : 3;
        if (m == 1)
            u[0] = (unsigned char)c;
        else if (m == 2)
            u[0] = 0xc0 | c >> 6, u[1] = 0x80 | (c & 0x3f);
        else
            u[0] = 0xe0 | c >> 12, u[1] = 0x80 | ((c >> 6) & 0x3f), u[2] = 0x80 | (c & 0x3f);
        if (k + m + 1 > size) break;
        memcpy(out + k, u, m), k += m;
    }
    out[k] = 0;
}

/* An ASCII tag's text (empty when the tag is absent or of another type). */
static void tag_text(ljgap__bytes *b, const tiff_tag *g, char *out, size_t size)
{
    const unsigned char *p = g->found && g->type == 2 ? ljgap__bytes_at(b, g->at, g->len) : NULL;
    out[0] = 0;
    if (p) ljgap__files_utf8(p, g->len, out, size);
}

static int read_file(const unsigned char *buf, size_t len, const char *channel,
                     ljgap__files_map *map, ljgap__files_err *err)
{
    ljgap__files_map_init(map, NAME);
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    tiff_tag tags[T_N];
    int be;
    size_t where;
    if (tiff_walk(&b, &be, tags, &where))
        return bad(err, (long)where, "the TIFF structure is truncated or corrupt");
    if (be) return bad(err, 0, "a big-endian TIFF: Park Systems files are little endian");
    if (tag_uint(&b, &tags[T_MAGIC], be) != PARK_MAGIC)
        return bad(err, tags[T_MAGIC].found ? (long)tags[T_MAGIC].entry : -1,
                   "no Park Systems magic number (tag 50432)");
    uint32_t version = tag_uint(&b, &tags[T_VERSION], be);
    if (version != PARK_V1 && version != PARK_V2)
        return bad(err, tags[T_VERSION].found ? (long)tags[T_VERSION].entry : -1,
                   "unknown Park Systems version 0x%x (tag 50433)", version);
    const tiff_tag *th = &tags[T_HEADER], *td = &tags[T_DATA];
    size_t need = version == PARK_V1 ? 356 : 580;
    if (!th->found || th->len < need)
        return bad(err, th->found ? (long)th->entry : -1,
                   "the image header (tag 50435) is missing or shorter than %zu bytes", need);
    if (!td->found) return bad(err, -1, "the data tag (50434) is missing");

    /* the image header (little endian whatever the TIFF's order) */
    size_t h = th->at;
    ljgap__bytes_seek(&b, h);
    uint32_t image_type = ljgap__bytes_u32(&b, 0);
    ljgap__bytes_seek(&b, h + 100);
    uint32_t xres = ljgap__bytes_u32(&b, 0), yres = ljgap__bytes_u32(&b, 0);
    ljgap__bytes_seek(&b, h + 140);
    double xreal = ljgap__bytes_f64(&b, 0), yreal = ljgap__bytes_f64(&b, 0);
    ljgap__bytes_seek(&b, h + 220);
    double gain = ljgap__bytes_f64(&b, 0), zscale = ljgap__bytes_f64(&b, 0);
    double zoff = ljgap__bytes_f64(&b, 0);
    uint32_t dtype = 0;
    if (version == PARK_V2) ljgap__bytes_seek(&b, h + 348), dtype = ljgap__bytes_u32(&b, 0);
    if (b.bad) return bad(err, (long)b.where, "the image header is truncated");
    if (image_type != 0)
        return bad(err, (long)h, "image type %u is a line profile or spectroscopy, not a map",
                   image_type);
    if (xres == 0 || yres == 0)
        return bad(err, (long)h + 100, "an image of %u x %u points", xres, yres);
    size_t bps = dtype == 0 ? 2 : dtype <= 2 ? 4 : 0;
    if (!bps) return bad(err, (long)h + 348, "unknown data type %u", dtype);
    if ((uint64_t)xres * yres > LJGAP_FILES_MAX_POINTS)
        return ljgap__files_report(err, LJGAP_FILES_TOOBIG, NAME, -1, NULL,
                                   "%u x %u points are too many", xres, yres);
    if (td->len < (uint64_t)xres * yres * bps)
        return bad(err, (long)td->entry, "the data tag holds %zu bytes, %u x %u points need %llu",
                   td->len, xres, yres, (unsigned long long)xres * yres * bps);
    if (!(isfinite(gain) && isfinite(zscale) && isfinite(zoff)))
        return bad(err, (long)h + 220, "the data gain, z scale or z offset is not a number");
    if (zscale == 0) zscale = 1;

    /* texts: the channel, the unit, the instrument, the date */
    char title[LJGAP_FILES_TEXT], unit[32];
    const unsigned char *tp = ljgap__bytes_at(&b, h + 4, 64), *up = ljgap__bytes_at(&b, h + 244, 16);
    if (!tp || !up) return bad(err, (long)b.where, "the image header is truncated");
    utf16(tp, 32, title, sizeof title);
    utf16(up, 8, unit, sizeof unit);
    snprintf(map->channels[0], LJGAP_FILES_TEXT, "%s", title[0] ? title : "channel 0");
    map->n_channels = 1;
    if (ljgap__files_channel_pick(map, channel, err) != 0) return LJGAP_FILES_CHANNEL;
    snprintf(map->channel, sizeof map->channel, "%s", map->channels[0]);
    snprintf(map->z_unit, sizeof map->z_unit, "%s", unit);
    char make[LJGAP_FILES_TEXT / 2], model[LJGAP_FILES_TEXT / 2], dt[32];
    tag_text(&b, &tags[T_MAKE], make, sizeof make);
    tag_text(&b, &tags[T_MODEL], model, sizeof model);
    if (make[0] || model[0])
        snprintf(map->instrument, sizeof map->instrument, "%s%s%s", make,
                 make[0] && model[0] ? " " : "", model);
    else
        snprintf(map->instrument, sizeof map->instrument, "Park Systems");
    tag_text(&b, &tags[T_DATETIME], dt, sizeof dt);
    int Y, M, D, hh, mm, ss;
    if (sscanf(dt, "%4d:%2d:%2d %2d:%2d:%2d", &Y, &M, &D, &hh, &mm, &ss) == 6 && Y >= 0 &&
        Y <= 9999 && M >= 1 && M <= 12 && D >= 1 && D <= 31 && hh >= 0 && hh < 24 && mm >= 0 &&
        mm < 60 && ss >= 0 && ss < 61)
        snprintf(map->acquired, sizeof map->acquired, "%04d-%02d-%02dT%02d:%02d:%02d", Y, M, D, hh,
                 mm, ss);

    double f = ljgap__files_unit_scale(unit), q = gain * (f > 0 ? f : 1);
    double sx = fabs(xreal) * 1e-6, sy = fabs(yreal) * 1e-6;
    int rc = ljgap__files_alloc(map, xres, yres, err);
    if (rc) return rc;
    map->size_x = isfinite(sx) ? sx : 0;
    map->size_y = isfinite(sy) ? sy : 0;
    ljgap__bytes_seek(&b, td->at);
    for (size_t j = 0; j < yres; j++) {
        size_t row = (yres - 1 - j) * (size_t)xres; /* bottom row first */
        for (size_t i = 0; i < xres; i++) {
            double raw = dtype == 0   ? ljgap__bytes_i16(&b, 0)
                         : dtype == 1 ? ljgap__bytes_i32(&b, 0)
                                      : ljgap__bytes_f32(&b, 0);
            ljgap__files_put(map, row + i, q * (raw * zscale + zoff));
        }
    }
    if (b.bad) { /* the walker checked the data tag's extent: a guard only */
        free(map->z), map->z = NULL;
        return bad(err, (long)b.where, "the data are truncated");
    }
    return 0;
}

/* The reader: read_file, a fault's offset kept inside the file (files_util.h). */
static int park_read(const unsigned char *buf, size_t len, const char *channel,
                     ljgap__files_map *map, ljgap__files_err *err)
{
    return ljgap__files_read_within(read_file, buf, len, channel, map, err);
}

const ljgap__files_format ljgap__files_park_tiff = {
    .name = NAME,
    .extensions = ".tiff .tif",
    .media_type = NULL, /* image/tiff would claim every TIFF */
    .probe = park_probe,
    .read = park_read,
};
