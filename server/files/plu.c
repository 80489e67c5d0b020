/* plu.c -- Sensofar PLu files (.plu): the confocal and interferometric profilers' binary format,
 * versions 2000 and 2006 (the later .plux is a zip of XML and images and is not read here).
 *
 * Layout (little endian; as Gwyddion's sensofar module and SurfaceTopography's PLU reader
 * describe it): a 500-byte header, then the layers.
 *     0  the date, 128 bytes, C's ctime() text "Wed Jun 30 21:49:08 1993" NUL-terminated (a
 *        date of that form is the only magic the format has: the probe checks it)
 *   128  time_t (u32), 132 a comment (256 bytes)
 *   388  the calibration: yres, xres, N_tall (u32), dy_multip, mppx, mppy (µm a pixel), x0,
 *        y0, mpp_tall, z0 (f32)
 *   428  the measurement: type (u32: 0 image, 1 profile, 3 topography, 5 thickness; 2 multiple
 *        profiles, 4 coordinates and 6 custom are not read), algorithm, method, objective, area
 *        type, 20 more bytes of scan settings, incr_z (f64), range (f32), n_planes, tpc (u32)
 *   488  restore, number of layers, format version (0: 2000, 255: 2006), hardware (0 PLu, 1 PLu
 *        2300 XGA, 2 PLu 2300 XGA T5, 3 PLu 2300 SXGA, 4 PLu 3300), image number, reserved
 *        (u8 each), 2 bytes of padding, 496 factor_delmacio (u32)
 *   500  each layer: yres, xres (u32), yres x xres heights in µm (f32, row after row), then
 *        its minimum and maximum (f32 each). Every layer must be there in full (the last one's
 *        minimum and maximum, which nothing needs, may be missing, as Gwyddion allows).
 * The value 1000001 marks a point not measured: it is a missing point (NaN), as a non-finite
 * value is. Every layer is a channel ("layer 0", ...; 0, the topography, by default), the
 * hardware gives the instrument, the ctime text the date (the writer's local time). A profile
 * (one row) has no y size.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bytes.h"
#include "files.h"
#include "files_util.h"

#define NAME "plu"
#define HEADER 500
#define NO_DATA 1000001.0f

/* A fault at a byte offset (files_util.h). */
#define bad(err, offset, ...) ljgap__files_fail(err, NAME, offset, NULL, __VA_ARGS__)

/* Whether buf starts with a ctime() date, "Www Mmm dd hh:mm:ss yyyy" and a NUL; its parts in
 * the ISO 8601 form into iso (may be NULL). */
static int ctime_date(const unsigned char *buf, size_t len, char *iso, size_t size)
{
    static const char days[] = "SunMonTueWedThuFriSat";
    static const char months[] = "JanFebMarAprMayJunJulAugSepOctNovDec";
    char s[25], wd[4], mon[4];
    int day, h, m, sec, y, n = 0;
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    const unsigned char *p = ljgap__bytes_at(&b, 0, 25);
    if (!p || p[24] != 0) return 0;
    memcpy(s, p, 25);
    if (sscanf(s, "%3s %3s %2d %2d:%2d:%2d %4d%n", wd, mon, &day, &h, &m, &sec, &y, &n) != 7 ||
        n != 24)
        return 0;
    const char *dp = strstr(days, wd), *mp = strstr(months, mon);
    if (strlen(wd) != 3 || strlen(mon) != 3 || !dp || (dp - days) % 3 || !mp || (mp - months) % 3 ||
        day < 1 || day > 31 || h < 0 || h > 23 || m < 0 || m > 59 || sec < 0 || sec > 60 || y < 0)
        return 0;
    if (iso)
        snprintf(iso, size, "%04d-%02d-%02dT%02d:%02d:%02d", y, (int)(mp - months) / 3 + 1, day, h,
                 m, sec);
    return 1;
}

static int plu_probe(const unsigned char *buf, size_t len)
{
    return ctime_date(buf, len, NULL, 0);
}

static int read_file(const unsigned char *buf, size_t len, const char *channel,
                     ljgap__files_map *map, ljgap__files_err *err)
{
    static const char *const hardware[] = {"PLu", "PLu 2300 XGA", "PLu 2300 XGA T5",
                                           "PLu 2300 SXGA", "PLu 3300"};
    ljgap__files_map_init(map, NAME);
    if (!ctime_date(buf, len, map->acquired, sizeof map->acquired))
        return bad(err, 0, "the file does not start with a date (Sensofar PLu)");
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    ljgap__bytes_seek(&b, 404);
    float mppx = ljgap__bytes_f32(&b, 0), mppy = ljgap__bytes_f32(&b, 0);
    ljgap__bytes_seek(&b, 428);
    uint32_t type = ljgap__bytes_u32(&b, 0);
    ljgap__bytes_seek(&b, 489);
    unsigned layers = ljgap__bytes_u8(&b), version = ljgap__bytes_u8(&b), hw = ljgap__bytes_u8(&b);
    ljgap__bytes_seek(&b, HEADER);
    if (b.bad) return bad(err, (long)b.where, "the header is truncated (500 bytes)");
    if (type != 0 && type != 1 && type != 3 && type != 5)
        return bad(err, 428,
                   "measurement type %u (multiple profiles, coordinates, custom) is "
                   "not read",
                   type);
    if (version != 0 && version != 255) return bad(err, 490, "unknown format version %u", version);
    if (layers == 0) layers = 1; /* version 2000 files may say 0 */
    snprintf(map->instrument, sizeof map->instrument, "Sensofar %s",
             hw < sizeof hardware / sizeof hardware[0] ? hardware[hw] : "PLu");
    int n = (int)(layers < LJGAP_FILES_MAX_CHANNELS ? layers : LJGAP_FILES_MAX_CHANNELS);
    for (int c = 0; c < n; c++)
        snprintf(map->channels[c], LJGAP_FILES_TEXT, "layer %d", c);
    map->n_channels = n;
    int ch = ljgap__files_channel_pick(map, channel, err); /* layer 0, the topography, first */
    if (ch < 0) return LJGAP_FILES_CHANNEL;
    map->channel_index = ch;
    snprintf(map->channel, sizeof map->channel, "%s", map->channels[ch]);
    snprintf(map->z_unit, sizeof map->z_unit, "um");

    /* every layer must be there (8 bytes of sizes, the heights, 8 bytes of min and max, which
     * the last one may lack); the one asked for is kept */
    uint32_t yres = 0, xres = 0;
    size_t data = 0;
    for (unsigned c = 0; c < layers; c++) {
        size_t at = b.pos;
        uint32_t ny = ljgap__bytes_u32(&b, 0), nx = ljgap__bytes_u32(&b, 0);
        if (b.bad) return bad(err, (long)b.where, "the file ends before layer %u's sizes", c);
        if (nx == 0 || ny == 0) return bad(err, (long)at, "layer %u has %u x %u points", c, ny, nx);
        if ((uint64_t)nx * ny > LJGAP_FILES_MAX_POINTS)
            return ljgap__files_report(err, LJGAP_FILES_TOOBIG, NAME, -1, NULL,
                                       "layer %u: %u x %u points are too many", c, ny, nx);
        uint64_t bytes = (uint64_t)nx * ny * 4;
        if (!ljgap__bytes_has(&b, b.pos, bytes))
            return bad(err, (long)len, "the file ends inside layer %u (%u x %u heights at %zu)", c,
                       ny, nx, b.pos);
        if (c == (unsigned)ch) yres = ny, xres = nx, data = b.pos;
        if (c + 1 < layers && ljgap__bytes_seek(&b, b.pos + bytes + 8))
            return bad(err, (long)len, "the file ends after layer %u", c);
    }
    ljgap__bytes_seek(&b, data);
    int rc = ljgap__files_alloc(map, xres, yres, err);
    if (rc) return rc;
    for (size_t i = 0; i < (size_t)xres * yres; i++) {
        float v = ljgap__bytes_f32(&b, 0);
        ljgap__files_put(map, i, v == NO_DATA ? NAN : v * 1e-6);
    }
    double sx = fabs((double)mppx) * xres * 1e-6, sy = fabs((double)mppy) * yres * 1e-6;
    map->size_x = isfinite(sx) ? sx : 0;
    map->size_y = yres > 1 && isfinite(sy) ? sy : 0;
    return 0;
}

/* The reader: read_file, a fault's offset kept inside the file (files_util.h). */
static int plu_read(const unsigned char *buf, size_t len, const char *channel, ljgap__files_map *map,
                    ljgap__files_err *err)
{
    return ljgap__files_read_within(read_file, buf, len, channel, map, err);
}

const ljgap__files_format ljgap__files_plu = {
    .name = NAME,
    .extensions = ".plu",
    .media_type = "application/x-sensofar-spm",
    .probe = plu_probe,
    .read = plu_read,
};
