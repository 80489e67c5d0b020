/* gwy.c -- Gwyddion's native files (.gwy).
 *
 * The format (Gwyddion's user guide, "GWY file format"): the magic "GWYP", then one serialized
 * object, a GwyContainer. A serialized object is its type name (a NUL-terminated string), the
 * byte size of its components (uint32, little-endian, as every number here), then the
 * components, each a name (NUL-terminated), a type character and the value: 'b' and 'c' one
 * byte, 'i' int32, 'q' int64, 'd' a double, 's' a NUL-terminated string, 'o' an object;
 * capital letters are arrays, a uint32 count and the items ('C', 'I', 'Q', 'D', 'S', 'O').
 *
 * The container's channels are its members "/N/data", GwyDataField objects: "xres", "yres"
 * (the grid), "xreal", "yreal" (the size in "si_unit_xy"), "si_unit_z", both GwySIUnit objects
 * with a "unitstr", and "data", xres * yres doubles row by row from the top. "/N/data/title"
 * is the channel's title; "/N/mask", a GwyDataField of the same grid, marks points with values
 * > 0.5: those are read as missing, as are non-finite values. Not read: graphs, spectra,
 * volume data, XYZ data, the metadata container "/N/meta" (no instrument or date is taken from
 * it), the offsets xoff, yoff.
 */
#include "bytes.h"
#include "files_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NAME "gwy"
#define DEPTH_MAX 16 /* nesting of objects */
#define MAX_FIELDS 64

typedef struct {
    int id;      /* N of /N/data */
    size_t data; /* offset of the GwyDataField's object */
    size_t mask; /* offset of /N/mask's object, 0 when none */
    char title[LJGAP_FILES_TEXT];
} field;

static int probe(const unsigned char *buf, size_t len)
{
    return len >= 4 && memcmp(buf, "GWYP", 4) == 0;
}

/* A NUL-terminated string at the cursor into out (cut to size); -1 when it does not end. */
static int cstr(ljgap__bytes *b, char *out, size_t size)
{
    const unsigned char *p = b->bad ? NULL : memchr(b->buf + b->pos, '\0', b->len - b->pos);
    if (!p) {
        if (!b->bad) b->bad = 1, b->where = b->len;
        if (size) out[0] = '\0';
        return -1;
    }
    size_t n = (size_t)(p - (b->buf + b->pos));
    if (out) ljgap__files_text(out, size, (const char *)b->buf + b->pos, n);
    b->pos += n + 1;
    return 0;
}

/* An object's header at the cursor: its type name and the end of its components. */
static int object_head(ljgap__bytes *b, char *type, size_t tsize, size_t *end)
{
    if (cstr(b, type, tsize)) return -1;
    uint32_t size = ljgap__bytes_u32(b, 0);
    if (b->bad || !ljgap__bytes_has(b, b->pos, size)) {
        if (!b->bad) b->bad = 1, b->where = b->len;
        return -1;
    }
    *end = b->pos + size;
    return 0;
}

static int skip_value(ljgap__bytes *b, char t, int depth);

static int skip_object(ljgap__bytes *b, int depth)
{
    char type[64];
    size_t end;
    if (depth > DEPTH_MAX || object_head(b, type, sizeof type, &end)) {
        if (!b->bad) b->bad = 1, b->where = b->pos;
        return -1;
    }
    return ljgap__bytes_seek(b, end);
}

/* Skips one value of type t at the cursor. */
static int skip_value(ljgap__bytes *b, char t, int depth)
{
    size_t one = 0;
    switch (t) {
    case 'b':
    case 'c':
        one = 1;
        break;
    case 'i':
        one = 4;
        break;
    case 'q':
    case 'd':
        one = 8;
        break;
    case 's':
        return cstr(b, NULL, 0);
    case 'o':
        return skip_object(b, depth + 1);
    case 'C':
    case 'I':
    case 'Q':
    case 'D':
    case 'S':
    case 'O': {
        uint32_t n = ljgap__bytes_u32(b, 0);
        if (b->bad) return -1;
        if (t == 'S' || t == 'O') {
            for (uint32_t i = 0; i < n && !b->bad; i++)
                skip_value(b, t == 'S' ? 's' : 'o', depth);
            return b->bad ? -1 : 0;
        }
        size_t w = t == 'C' ? 1 : t == 'I' ? 4 : 8;
        if (!ljgap__bytes_has(b, b->pos, (size_t)n * w)) {
            b->bad = 1, b->where = b->len;
            return -1;
        }
        b->pos += (size_t)n * w;
        return 0;
    }
    default:
        if (!b->bad) b->bad = 1, b->where = b->pos - 1;
        return -1;
    }
    return ljgap__bytes_at(b, b->pos, one) ? (b->pos += one, 0) : -1;
}

/* "/N/data", "/N/data/title", "/N/mask": N and which (1, 2, 3), else 0. */
static int channel_key(const char *k, int *id)
{
    char *end;
    if (k[0] != '/' || k[1] < '0' || k[1] > '9') return 0;
    long n = strtol(k + 1, &end, 10);
    if (n > 1000000) return 0;
    *id = (int)n;
    return strcmp(end, "/data") == 0         ? 1
           : strcmp(end, "/data/title") == 0 ? 2
           : strcmp(end, "/mask") == 0       ? 3
                                             : 0;
}

static field *field_of(field *f, int *n, int id)
{
    for (int i = 0; i < *n; i++)
        if (f[i].id == id) return &f[i];
    if (*n >= MAX_FIELDS) return NULL;
    memset(&f[*n], 0, sizeof f[*n]);
    f[*n].id = id;
    return &f[(*n)++];
}

/* A GwySIUnit object's unitstr at the cursor into unit. */
static void si_unit(ljgap__bytes *b, char *unit, size_t size)
{
    char type[32], name[32];
    size_t end;
    unit[0] = '\0';
    if (object_head(b, type, sizeof type, &end)) return;
    while (b->pos < end && !b->bad) {
        cstr(b, name, sizeof name);
        char t = (char)ljgap__bytes_u8(b);
        if (t == 's' && strcmp(name, "unitstr") == 0)
            cstr(b, unit, size);
        else
            skip_value(b, t, 2);
    }
    ljgap__bytes_seek(b, end);
}

typedef struct {
    long xres, yres;
    double xreal, yreal;
    char uxy[32], uz[32];
    size_t data; /* offset of the doubles */
    uint32_t ndata;
} datafield;

/* A GwyDataField object at off. */
static int data_field(const unsigned char *buf, size_t len, size_t off, datafield *d,
                      ljgap__files_err *err)
{
    ljgap__bytes b;
    char type[32], name[32];
    size_t end;
    memset(d, 0, sizeof *d);
    ljgap__bytes_init(&b, buf, len);
    ljgap__bytes_seek(&b, off);
    if (object_head(&b, type, sizeof type, &end) || strcmp(type, "GwyDataField") != 0)
        return ljgap__files_fail(err, NAME, (long)off, NULL, "a channel that is no GwyDataField");
    while (b.pos < end && !b.bad) {
        cstr(&b, name, sizeof name);
        char t = (char)ljgap__bytes_u8(&b);
        if (t == 'i' && strcmp(name, "xres") == 0)
            d->xres = ljgap__bytes_i32(&b, 0);
        else if (t == 'i' && strcmp(name, "yres") == 0)
            d->yres = ljgap__bytes_i32(&b, 0);
        else if (t == 'd' && strcmp(name, "xreal") == 0)
            d->xreal = ljgap__bytes_f64(&b, 0);
        else if (t == 'd' && strcmp(name, "yreal") == 0)
            d->yreal = ljgap__bytes_f64(&b, 0);
        else if (t == 'o' && strcmp(name, "si_unit_xy") == 0)
            si_unit(&b, d->uxy, sizeof d->uxy);
        else if (t == 'o' && strcmp(name, "si_unit_z") == 0)
            si_unit(&b, d->uz, sizeof d->uz);
        else if (t == 'D' && strcmp(name, "data") == 0) {
            d->ndata = ljgap__bytes_u32(&b, 0);
            d->data = b.pos;
            if (!ljgap__bytes_has(&b, b.pos, (size_t)d->ndata * 8)) {
                b.bad = 1, b.where = b.len;
                break;
            }
            b.pos += (size_t)d->ndata * 8;
        } else
            skip_value(&b, t, 1);
    }
    if (b.bad)
        return ljgap__files_fail(err, NAME, (long)b.where, NULL,
                                "the GwyDataField at byte %zu is cut short or corrupt", off);
    if (d->xres <= 0 || d->yres <= 0 || !d->data ||
        (uint64_t)d->ndata != (uint64_t)d->xres * (uint64_t)d->yres)
        return ljgap__files_fail(err, NAME, (long)off, NULL,
                                "the GwyDataField at byte %zu has %ld x %ld points and %u values",
                                off, d->xres, d->yres, d->ndata);
    return 0;
}

static int read_gwy(const unsigned char *buf, size_t len, const char *channel, ljgap__files_map *map,
                    ljgap__files_err *err)
{
    field f[MAX_FIELDS];
    int nf = 0, id, st, pick;
    char type[32], name[96];
    size_t end;
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    if (!probe(buf, len)) return ljgap__files_fail(err, NAME, 0, NULL, "no GWYP at the start");
    ljgap__bytes_seek(&b, 4);
    if (object_head(&b, type, sizeof type, &end))
        return ljgap__files_fail(err, NAME, (long)b.where, NULL,
                                "the top object's size runs past the end of the file (truncated)");
    if (strcmp(type, "GwyContainer") != 0)
        return ljgap__files_fail(err, NAME, 4, NULL, "the top object is a %s, not a GwyContainer",
                                type);
    while (b.pos < end && !b.bad) {
        size_t at = b.pos;
        cstr(&b, name, sizeof name);
        char t = (char)ljgap__bytes_u8(&b);
        int which = b.bad ? 0 : channel_key(name, &id);
        field *fd = which ? field_of(f, &nf, id) : NULL;
        if (fd && which == 1 && t == 'o') fd->data = b.pos;
        if (fd && which == 3 && t == 'o') fd->mask = b.pos;
        if (fd && which == 2 && t == 's') {
            cstr(&b, fd->title, sizeof fd->title);
            continue;
        }
        if (skip_value(&b, t, 0) && !b.bad) b.bad = 1, b.where = at;
    }
    if (b.bad)
        return ljgap__files_fail(err, NAME, (long)b.where, NULL,
                                "a member of the container is cut short or corrupt");
    /* the channels in the order of their numbers (a container keeps no order) */
    for (int i = 1; i < nf; i++)
        for (int k = i; k > 0 && f[k].id < f[k - 1].id; k--) {
            field t = f[k];
            f[k] = f[k - 1], f[k - 1] = t;
        }
    int keep = 0;
    for (int i = 0; i < nf; i++)
        if (f[i].data) f[keep++] = f[i];
    nf = keep;
    if (!nf) return ljgap__files_fail(err, NAME, -1, NULL, "the file holds no channel (/N/data)");
    for (int i = 0; i < nf; i++) {
        if (!f[i].title[0]) snprintf(f[i].title, sizeof f[i].title, "channel %d", f[i].id);
        ljgap__files_add_channel(map, f[i].title);
    }
    if ((pick = ljgap__files_channel_pick(map, channel, err)) < 0) return LJGAP_FILES_CHANNEL;
    map->channel_index = pick;
    snprintf(map->channel, sizeof map->channel, "%s", map->channels[pick]);
    datafield d, m;
    snprintf(name, sizeof name, "/%d/data", f[pick].id);
    if ((st = data_field(buf, len, f[pick].data, &d, err))) {
        snprintf(err->member, sizeof err->member, "%.60s", name);
        return st;
    }
    if ((st = ljgap__files_alloc(map, (size_t)d.xres, (size_t)d.yres, err))) return st;
    double zs = ljgap__files_unit_scale(d.uz), xs = ljgap__files_unit_scale(d.uxy);
    snprintf(map->z_unit, sizeof map->z_unit, "%s", d.uz);
    ljgap__bytes_seek(&b, d.data);
    for (size_t i = 0; i < map->nx * map->ny; i++) {
        double z = ljgap__bytes_f64(&b, 0);
        map->z[i] = isfinite(z) ? (zs > 0 ? zs : 1) * z : NAN;
        if (isinf(map->z[i]))
            return ljgap__files_fail(err, NAME, (long)(d.data + 8 * i), name,
                                    "a height of %g %s overflows in metres", z, d.uz);
    }
    if (f[pick].mask) {
        snprintf(name, sizeof name, "/%d/mask", f[pick].id);
        if ((st = data_field(buf, len, f[pick].mask, &m, err))) {
            snprintf(err->member, sizeof err->member, "%.60s", name);
            return st;
        }
        if (m.xres != d.xres || m.yres != d.yres) {
            ljgap__files_fail(err, NAME, (long)f[pick].mask, name,
                             "the mask has %ld x %ld points, its channel %ld x %ld", m.xres, m.yres,
                             d.xres, d.yres);
            return LJGAP_FILES_BAD;
        }
        ljgap__bytes_seek(&b, m.data);
        for (size_t i = 0; i < map->nx * map->ny; i++)
            if (ljgap__bytes_f64(&b, 0) > 0.5) map->z[i] = NAN;
    }
    if (xs > 0 && isfinite(d.xreal) && isfinite(d.yreal) && d.xreal > 0 && d.yreal > 0)
        map->size_x = xs * d.xreal, map->size_y = xs * d.yreal;
    return 0;
}

const ljgap__files_format ljgap__files_gwy = {NAME, ".gwy", NULL, probe, read_gwy};
