/* metropro.c -- Zygo MetroPro .dat files (NewView, GPI and other Zygo interferometers).
 *
 * A big-endian header (its format and size in the header: format 1 and 2 with magic 0x881B036F
 * and 0x881B0370 have 834 bytes, format 3 with 0x881B0371 has 4096), then the intensity data
 * (ac_n_buckets frames of ac_width x ac_height unsigned 16-bit values, ac_n_bytes bytes in all),
 * then the phase data (cn_width x cn_height signed 32-bit values, cn_n_bytes bytes), rows one
 * after the other, x fastest. Phase values from 2147483640 up mark invalid points (intensity:
 * from 65412 up). A height is phase * intf_scale_factor * obliquity_factor * wavelength_in / R,
 * R = 4096, 32768 or 131072 for phase_res 0, 1, 2, negated when the sign field is 1; the lateral
 * resolution (m a pixel) gives the size. Header fields used, by byte offset: header_format 4,
 * header_size 6, ac_org_width 52, ac_org_height 54, ac_n_buckets 56, ac_n_bytes 60, cn_org_width
 * 68, cn_org_height 70, cn_n_bytes 72, time_stamp 76 (Unix seconds), intf_scale_factor 164,
 * wavelength_in 168 (m), obliquity_factor 176, lateral_res 184 (m), phase_res 218, sign 232,
 * sys_type 238, sys_serial 242 (as in Zygo's MetroPro Reference Guide, section "Data Format").
 *
 * Channels: "Height" (the phase, the default), then "Intensity" frames. Not read: the
 * connected-phase origin offsets (the map starts at its own corner), the films and asphere
 * fields of format 3.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>

#include "bytes.h"
#include "files_util.h"

#define MP "metropro"

static int magic_format(const unsigned char *buf, size_t len)
{
    if (len < 4 || buf[0] != 0x88 || buf[1] != 0x1b || buf[2] != 0x03) return 0;
    return buf[3] == 0x6f ? 1 : buf[3] == 0x70 ? 2 : buf[3] == 0x71 ? 3 : 0;
}

static int mp_probe(const unsigned char *buf, size_t len)
{
    return magic_format(buf, len) != 0;
}

static const char *const system_types[] = {"",         "Mark IVxp",  "Maxim 3D",
                                           "Maxim NT", "GPI-XP",     "NewView",
                                           "Maxim GP", "NewView/GP", "Mark to GPI conversion"};

static int mp_read(const unsigned char *buf, size_t len, const char *channel, ljgap__files_map *map,
                   ljgap__files_err *err)
{
    ljgap__files_map_init(map, MP);
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    int fmt = magic_format(buf, len);
    if (!fmt) return ljgap__files_fail(err, MP, 0, NULL, "no MetroPro magic number");
    if (len < 834)
        return ljgap__files_fail(err, MP, (long)len, NULL,
                                 "the header (834 bytes at least) is cut short at byte %zu", len);
    ljgap__bytes_seek(&b, 4);
    unsigned hformat = ljgap__bytes_u16(&b, 1);
    uint32_t hsize = ljgap__bytes_u32(&b, 1);
    uint32_t want = fmt == 3 ? 4096 : 834;
    if (hformat != (unsigned)fmt || hsize != want)
        return ljgap__files_fail(err, MP, 4, NULL,
                                 "header format %u of %u bytes: the magic number says format %d "
                                 "of %u bytes",
                                 hformat, hsize, fmt, want);
    if (len < hsize)
        return ljgap__files_fail(err, MP, (long)len, NULL,
                                 "the %u-byte header is cut short at byte %zu", hsize, len);
    ljgap__bytes_seek(&b, 52);
    unsigned acw = ljgap__bytes_u16(&b, 1), ach = ljgap__bytes_u16(&b, 1);
    unsigned nbuckets = ljgap__bytes_u16(&b, 1);
    ljgap__bytes_seek(&b, 60);
    uint32_t acbytes = ljgap__bytes_u32(&b, 1);
    ljgap__bytes_seek(&b, 68);
    unsigned cnw = ljgap__bytes_u16(&b, 1), cnh = ljgap__bytes_u16(&b, 1);
    uint32_t cnbytes = ljgap__bytes_u32(&b, 1);
    int32_t stamp = ljgap__bytes_i32(&b, 1);
    ljgap__bytes_seek(&b, 164);
    double scale = ljgap__bytes_f32(&b, 1), wavelength = ljgap__bytes_f32(&b, 1);
    ljgap__bytes_seek(&b, 176);
    double obliquity = ljgap__bytes_f32(&b, 1);
    ljgap__bytes_seek(&b, 184);
    double lateral = ljgap__bytes_f32(&b, 1);
    ljgap__bytes_seek(&b, 218);
    int phase_res = ljgap__bytes_i16(&b, 1);
    ljgap__bytes_seek(&b, 232);
    int sign = ljgap__bytes_i16(&b, 1);
    ljgap__bytes_seek(&b, 238);
    int systype = ljgap__bytes_i16(&b, 1);
    ljgap__bytes_seek(&b, 242);
    int serial = ljgap__bytes_i16(&b, 1);
    if (b.bad) /* not reached: 834 bytes are there */
        return ljgap__files_fail(err, MP, (long)b.where, NULL, "header cut short");

    uint64_t acwant = (uint64_t)acw * ach * nbuckets * 2;
    if (acbytes != acwant)
        return ljgap__files_fail(err, MP, 60, NULL,
                                 "%u bytes of intensity data for %u frames of %u x %u points",
                                 acbytes, nbuckets, acw, ach);
    if (cnbytes != (uint64_t)cnw * cnh * 4)
        return ljgap__files_fail(err, MP, 72, NULL, "%u bytes of phase data for %u x %u points",
                                 cnbytes, cnw, cnh);
    if ((uint64_t)hsize + acbytes + cnbytes > len)
        return ljgap__files_fail(err, MP, (long)len, NULL,
                                 "the data (%u + %u bytes after the header) are cut short at "
                                 "byte %zu",
                                 acbytes, cnbytes, len);

    /* channels: the height (when there is phase data), then the intensity frames */
    int has_phase = cnbytes > 0;
    if (has_phase) snprintf(map->channels[map->n_channels++], LJGAP_FILES_TEXT, "Height");
    for (unsigned k = 0; k < nbuckets && map->n_channels < LJGAP_FILES_MAX_CHANNELS; k++) {
        if (nbuckets == 1)
            snprintf(map->channels[map->n_channels++], LJGAP_FILES_TEXT, "Intensity");
        else
            snprintf(map->channels[map->n_channels++], LJGAP_FILES_TEXT, "Intensity %u", k);
    }
    if (map->n_channels == 0)
        return ljgap__files_fail(err, MP, 68, NULL, "neither phase nor intensity data in the file");
    int c = ljgap__files_channel_pick(map, channel, err);
    if (c < 0) return LJGAP_FILES_CHANNEL;
    map->channel_index = c;
    snprintf(map->channel, sizeof map->channel, "%s", map->channels[c]);

    int height = has_phase && c == 0;
    unsigned w = height ? cnw : acw, h = height ? cnh : ach;
    int rc = ljgap__files_alloc_at(map, w, h, err, height ? 68 : 52);
    if (rc) return rc;
    size_t n = (size_t)w * h;
    if (height) {
        double R = phase_res == 0 ? 4096 : phase_res == 1 ? 32768 : phase_res == 2 ? 131072 : 0;
        if (R == 0)
            return ljgap__files_fail(err, MP, 218, NULL,
                                     "phase resolution %d: 0, 1 or 2 are defined", phase_res);
        double q = scale * obliquity * wavelength / R;
        if (!isfinite(q) || q == 0)
            return ljgap__files_fail(err, MP, 164, NULL,
                                     "the scale, obliquity and wavelength give no height scale");
        if (sign == 1) q = -q;
        ljgap__bytes_seek(&b, (size_t)hsize + acbytes);
        for (size_t k = 0; k < n; k++) {
            int32_t v = ljgap__bytes_i32(&b, 1);
            ljgap__files_put(map, k, v >= 2147483640 ? NAN : q * v);
        }
        snprintf(map->z_unit, sizeof map->z_unit, "m");
    } else {
        unsigned frame = (unsigned)(c - has_phase);
        ljgap__bytes_seek(&b, (size_t)hsize + (size_t)frame * n * 2);
        for (size_t k = 0; k < n; k++) {
            unsigned v = ljgap__bytes_u16(&b, 1);
            ljgap__files_put(map, k, v >= 65412 ? NAN : (double)v);
        }
    }
    if (b.bad) /* not reached: the sizes were checked */
        return ljgap__files_fail(err, MP, (long)b.where, NULL, "data cut short");
    if (isfinite(lateral) && lateral > 0) map->size_x = lateral * w, map->size_y = lateral * h;
    const char *sys = systype > 0 && systype < (int)(sizeof system_types / sizeof *system_types)
                          ? system_types[systype]
                          : "";
    snprintf(map->instrument, sizeof map->instrument, "Zygo%s%s, serial %d", *sys ? " " : "", sys,
             serial);
    if (stamp > 0) {
        time_t t = stamp;
        struct tm tm;
        if (gmtime_r(&t, &tm))
            strftime(map->acquired, sizeof map->acquired, "%Y-%m-%dT%H:%M:%SZ", &tm);
    }
    return 0;
}

const ljgap__files_format ljgap__files_metropro = {
    .name = "metropro",
    .extensions = ".dat",
    .media_type = NULL,
    .probe = mp_probe,
    .read = mp_read,
};
