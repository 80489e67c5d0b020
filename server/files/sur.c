/* sur.c -- Digital Surf .sur files (MountainsMap, many profilometers and optical profilers).
 *
 * A file is one or more objects, each a 512-byte little-endian header, a comment zone and a
 * private zone (their sizes in the header), then the points: nx * ny integers of 16 or 32 bits,
 * x fastest (a row of nx points, ny rows), height = (value * dz + z_offset) in the header's dz
 * unit. The header's fields, by byte offset: signature "DIGITAL SURF" (or "DSCOMPRESSED", then
 * the points are zlib streams: a u32 count of directory entries, each a u32 raw size and a u32
 * compressed size, then the streams one after the other) 0, format 12 (0: PC), number of
 * objects 14, version 16, object type 18 (1 profile, 2 surface), object name 20 (30 bytes),
 * operator 50 (30), acquisition type 82, non-measured points flag 86 (1: points equal to
 * zmin - 2 are missing), bits per point 98, zmin 100, zmax 104, nx 108, ny 112, total points
 * 116, dx dy dz 120..131 (float), the step units dx_unit 180, dy_unit 196, dz_unit 212 (16 bytes
 * each), inversion 290, the date (seconds, minutes, hours, day, month, year: u16 from 306),
 * the compressed data size 324 (u32), comment size 334, private size 336, z offset 474 (float).
 *
 * The inversion field (290): 1 inverts z, 2 also mirrors x, 3 also mirrors y (the way Gwyddion
 * reads them; Gwyddion reflects z about the mean where this negates it: the same map up to a
 * constant). Each object is a channel titled by its object name. What is not read: Macintosh
 * byte order (format 257), the x and y offsets, and objects other than height maps (series,
 * spectra): they are read as maps.
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

#define SUR "sur"
#define HDR 512

typedef struct {
    size_t at;                   /* the header's offset */
    int compressed;              /* "DSCOMPRESSED" */
    int type;                    /* object type */
    char name[31];               /* object name */
    int acquisition;             /* acquisition type */
    int nonmeasured;             /* points equal to zmin - 2 are missing */
    int bits;                    /* 16 or 32 */
    int32_t zmin;                /* smallest value */
    uint32_t nx, ny;             /* points a row, rows */
    double dx, dy, dz;           /* steps in their units */
    char ux[17], uy[17], uz[17]; /* the step units */
    int inversion;               /* 1: z inverted */
    unsigned date[6];            /* seconds, minutes, hours, day, month, year */
    uint32_t csize;              /* compressed data size */
    size_t data;                 /* the offset of the points */
    size_t end;                  /* the offset after the object */
    double zoff;                 /* z offset in the dz unit */
} sur_obj;

static const char *const acq_names[] = {"",
                                        "contact stylus",
                                        "scanning optical gauge",
                                        "thermocouple",
                                        "",
                                        "contact stylus with skid",
                                        "AFM",
                                        "STM",
                                        "video",
                                        "interferometer",
                                        "structured light projection"};

static int sur_probe(const unsigned char *buf, size_t len)
{
    return len >= 12 && (!memcmp(buf, "DIGITAL SURF", 12) || !memcmp(buf, "DSCOMPRESSED", 12));
}

static void field_text(ljgap__bytes *b, size_t at, size_t n, char *out, size_t size)
{
    const unsigned char *p = ljgap__bytes_at(b, at, n);
    if (p)
        ljgap__files_utf8(p, n, out, size);
    else
        out[0] = 0;
}

/* Reads the header of the object at `at` and places its zones: 0, or LJGAP_FILES_BAD. */
static int sur_header(ljgap__bytes *b, size_t at, sur_obj *o, ljgap__files_err *err)
{
    memset(o, 0, sizeof *o);
    o->at = at;
    const unsigned char *sig = ljgap__bytes_at(b, at, 12);
    if (!sig || (memcmp(sig, "DIGITAL SURF", 12) && memcmp(sig, "DSCOMPRESSED", 12)))
        return ljgap__files_fail(err, SUR, (long)at, NULL,
                                 "no Digital Surf object header at byte %zu", at);
    o->compressed = !memcmp(sig, "DSCOMPRESSED", 12);
    if (!ljgap__bytes_has(b, at, HDR))
        return ljgap__files_fail(err, SUR, (long)b->len, NULL,
                                 "the 512-byte header at byte %zu is cut short at byte %zu", at,
                                 b->len);
    ljgap__bytes_seek(b, at + 12);
    unsigned format = ljgap__bytes_u16(b, 0);
    if (format != 0)
        return ljgap__files_fail(err, SUR, (long)at + 12, NULL,
                                 "format %u: only the PC byte order (0) is read", format);
    ljgap__bytes_seek(b, at + 18);
    o->type = ljgap__bytes_u16(b, 0);
    field_text(b, at + 20, 30, o->name, sizeof o->name);
    ljgap__bytes_seek(b, at + 82);
    o->acquisition = ljgap__bytes_u16(b, 0);
    ljgap__bytes_seek(b, at + 86);
    o->nonmeasured = ljgap__bytes_u16(b, 0) == 1;
    ljgap__bytes_seek(b, at + 98);
    o->bits = ljgap__bytes_u16(b, 0);
    o->zmin = ljgap__bytes_i32(b, 0);
    (void)ljgap__bytes_i32(b, 0); /* zmax */
    int32_t nx = ljgap__bytes_i32(b, 0), ny = ljgap__bytes_i32(b, 0);
    uint32_t total = ljgap__bytes_u32(b, 0);
    o->dx = ljgap__bytes_f32(b, 0), o->dy = ljgap__bytes_f32(b, 0), o->dz = ljgap__bytes_f32(b, 0);
    field_text(b, at + 180, 16, o->ux, sizeof o->ux);
    field_text(b, at + 196, 16, o->uy, sizeof o->uy);
    field_text(b, at + 212, 16, o->uz, sizeof o->uz);
    ljgap__bytes_seek(b, at + 290);
    o->inversion = ljgap__bytes_u16(b, 0);
    ljgap__bytes_seek(b, at + 306);
    for (int i = 0; i < 6; i++)
        o->date[i] = ljgap__bytes_u16(b, 0);
    ljgap__bytes_seek(b, at + 324);
    o->csize = ljgap__bytes_u32(b, 0);
    ljgap__bytes_seek(b, at + 334);
    unsigned comment = ljgap__bytes_u16(b, 0), priv = ljgap__bytes_u16(b, 0);
    ljgap__bytes_seek(b, at + 474);
    o->zoff = ljgap__bytes_f32(b, 0);
    if (b->bad) /* not reached: the header's 512 bytes are there */
        return ljgap__files_fail(err, SUR, (long)b->where, NULL, "header cut short");
    if (o->bits != 16 && o->bits != 32)
        return ljgap__files_fail(err, SUR, (long)at + 98, NULL,
                                 "%d bits a point: only 16 and 32 are defined", o->bits);
    if (nx <= 0 || ny <= 0)
        return ljgap__files_fail(err, SUR, (long)at + 108, NULL, "a grid of %d x %d points",
                                 (int)nx, (int)ny);
    o->nx = (uint32_t)nx, o->ny = (uint32_t)ny;
    if ((uint64_t)o->nx * o->ny != total)
        return ljgap__files_fail(err, SUR, (long)at + 116, NULL,
                                 "%u points stated, %u x %u in the grid", total, o->nx, o->ny);
    if (!isfinite(o->dz) || !isfinite(o->zoff))
        return ljgap__files_fail(err, SUR, (long)at + 128, NULL,
                                 "the z step or offset is not a finite number");
    o->data = at + HDR + comment + priv;
    uint64_t size = o->compressed ? o->csize : (uint64_t)total * (unsigned)(o->bits / 8);
    if (!ljgap__bytes_has(b, o->data, 0) || size > b->len - o->data)
        return ljgap__files_fail(err, SUR, (long)b->len, NULL,
                                 "the points (%llu bytes from byte %zu) are cut short at byte %zu",
                                 (unsigned long long)size, o->data, b->len);
    o->end = o->data + (size_t)size;
    return 0;
}

/* Inflates the compressed points of o into out (raw bytes of nx * ny points). */
static int sur_inflate(ljgap__bytes *b, const sur_obj *o, unsigned char *out, size_t rawsize,
                       ljgap__files_err *err)
{
    ljgap__bytes_seek(b, o->data);
    uint32_t ndir = ljgap__bytes_u32(b, 0);
    if (b->bad || ndir == 0 || ndir > (o->end - o->data) / 8)
        return ljgap__files_fail(err, SUR, (long)o->data, NULL,
                                 "a compressed data block with %u directory entries", ndir);
    size_t stream = o->data + 4 + (size_t)ndir * 8, done = 0;
    for (uint32_t d = 0; d < ndir; d++) {
        ljgap__bytes_seek(b, o->data + 4 + (size_t)d * 8);
        uint32_t raw = ljgap__bytes_u32(b, 0), zipped = ljgap__bytes_u32(b, 0);
        if (b->bad || zipped > o->end - stream || raw > rawsize - done)
            return ljgap__files_fail(err, SUR, (long)(o->data + 4 + d * 8), NULL,
                                     "compressed stream %u (%u bytes, %u raw) does not fit", d,
                                     zipped, raw);
        z_stream zs;
        memset(&zs, 0, sizeof zs);
        if (inflateInit(&zs) != Z_OK)
            return ljgap__files_report(err, LJGAP_FILES_NOMEM, SUR, -1, NULL, "out of memory");
        zs.next_in = (unsigned char *)(uintptr_t)(b->buf + stream), zs.avail_in = zipped;
        zs.next_out = out + done, zs.avail_out = raw;
        int rc = inflate(&zs, Z_FINISH);
        size_t got = raw - zs.avail_out;
        inflateEnd(&zs);
        if (rc != Z_STREAM_END || got != raw)
            return ljgap__files_fail(err, SUR, (long)stream, NULL,
                                     "compressed stream %u does not inflate to its %u bytes", d,
                                     raw);
        done += raw, stream += zipped;
    }
    if (done != rawsize)
        return ljgap__files_fail(err, SUR, (long)o->data, NULL,
                                 "the compressed streams hold %zu bytes, the grid %zu", done,
                                 rawsize);
    return 0;
}

static int sur_read(const unsigned char *buf, size_t len, const char *channel, ljgap__files_map *map,
                    ljgap__files_err *err)
{
    ljgap__files_map_init(map, SUR);
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    if (!ljgap__bytes_has(&b, 0, 16))
        return ljgap__files_fail(err, SUR, (long)len, NULL, "cut short in the header");
    ljgap__bytes_seek(&b, 14);
    unsigned nobj = ljgap__bytes_u16(&b, 0);
    if (nobj == 0) nobj = 1;
    if (nobj > LJGAP_FILES_MAX_CHANNELS) nobj = LJGAP_FILES_MAX_CHANNELS;
    /* Every object's header, for the channel list; the chosen one is read. */
    sur_obj objs[LJGAP_FILES_MAX_CHANNELS];
    size_t at = 0;
    for (unsigned k = 0; k < nobj; k++) {
        int rc = sur_header(&b, at, &objs[k], err);
        if (rc) return rc;
        if (objs[k].name[0])
            snprintf(map->channels[k], LJGAP_FILES_TEXT, "%s", objs[k].name);
        else
            snprintf(map->channels[k], LJGAP_FILES_TEXT, "object %u", k);
        map->n_channels = (int)k + 1;
        at = objs[k].end;
    }
    int c = ljgap__files_channel_pick(map, channel, err);
    if (c < 0) return LJGAP_FILES_CHANNEL;
    const sur_obj *o = &objs[c];
    map->channel_index = c;
    snprintf(map->channel, sizeof map->channel, "%s", map->channels[c]);
    int rc = ljgap__files_alloc_at(map, o->nx, o->ny, err, (long)o->at + 108);
    if (rc) return rc;

    size_t n = (size_t)o->nx * o->ny, w = (size_t)o->bits / 8;
    const unsigned char *p;
    unsigned char *raw = NULL;
    if (o->compressed) {
        raw = malloc(n * w);
        if (!raw)
            return ljgap__files_report(err, LJGAP_FILES_NOMEM, SUR, -1, NULL, "out of memory");
        rc = sur_inflate(&b, o, raw, n * w, err);
        if (rc) {
            free(raw);
            return rc;
        }
        p = raw;
    } else {
        p = ljgap__bytes_at(&b, o->data, n * w); /* checked by sur_header */
        if (!p) return ljgap__files_fail(err, SUR, (long)len, NULL, "cut short");
    }
    double fz = ljgap__files_unit_scale(o->uz), fx = ljgap__files_unit_scale(o->ux),
           fy = ljgap__files_unit_scale(o->uy);
    if (fz == 0) fz = 1; /* not a length: the values in the stated unit */
    double sign = o->inversion >= 1 && o->inversion <= 3 ? -1 : 1;
    int64_t hole = (int64_t)o->zmin - 2;
    for (size_t k = 0; k < n; k++) {
        int64_t v = w == 2 ? (int16_t)(p[2 * k] | p[2 * k + 1] << 8)
                           : (int32_t)((uint32_t)p[4 * k] | (uint32_t)p[4 * k + 1] << 8 |
                                       (uint32_t)p[4 * k + 2] << 16 | (uint32_t)p[4 * k + 3] << 24);
        if (o->nonmeasured && v == hole)
            ljgap__files_put(map, k, NAN);
        else
            ljgap__files_put(map, k, sign * ((double)v * o->dz + o->zoff) * fz);
    }
    free(raw);
    /* inversion 2 and 3 also mirror the map (as Gwyddion reads them): x, then y */
    for (size_t j = 0; o->inversion == 2 && j < o->ny; j++)
        for (size_t i = 0, r = j * o->nx; i < o->nx / 2; i++) {
            double t = map->z[r + i];
            map->z[r + i] = map->z[r + o->nx - 1 - i], map->z[r + o->nx - 1 - i] = t;
        }
    for (size_t j = 0; o->inversion == 3 && j < o->ny / 2; j++)
        for (size_t i = 0; i < o->nx; i++) {
            double t = map->z[j * o->nx + i];
            map->z[j * o->nx + i] = map->z[(o->ny - 1 - j) * o->nx + i];
            map->z[(o->ny - 1 - j) * o->nx + i] = t;
        }
    if (fx > 0 && fy > 0 && o->dx > 0 && o->dy > 0 && isfinite(o->dx) && isfinite(o->dy)) {
        map->size_x = fabs(o->dx) * fx * o->nx;
        map->size_y = fabs(o->dy) * fy * o->ny;
    }
    snprintf(map->z_unit, sizeof map->z_unit, "%s", o->uz);
    if (o->acquisition > 0 && o->acquisition < (int)(sizeof acq_names / sizeof acq_names[0]) &&
        acq_names[o->acquisition][0])
        snprintf(map->instrument, sizeof map->instrument, "%s", acq_names[o->acquisition]);
    const unsigned *d = o->date;
    if (d[5] >= 1900 && d[5] <= 9999 && d[4] >= 1 && d[4] <= 12 && d[3] >= 1 && d[3] <= 31 &&
        d[2] < 24 && d[1] < 60 && d[0] < 61)
        snprintf(map->acquired, sizeof map->acquired, "%04u-%02u-%02uT%02u:%02u:%02u", d[5] % 10000,
                 d[4] % 100, d[3] % 100, d[2] % 100, d[1] % 100, d[0] % 100);
    return 0;
}

const ljgap__files_format ljgap__files_sur = {
    .name = "sur",
    .extensions = ".sur",
    .media_type = NULL,
    .probe = sur_probe,
    .read = sur_read,
};
