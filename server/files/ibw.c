/* ibw.c -- Igor Pro binary waves (.ibw), as Asylum Research's AFMs (MFP-3D, Cypher) write them.
 *
 * The layout is WaveMetrics' (Technical Note 003, the IgorBin.h of their examples): a binary
 * header, a wave header, the data, then optional sections whose sizes the binary header gives.
 * The byte order is the writer's: the version (a short, first) has a nonzero low byte, so a
 * nonzero first byte means little endian. A 16-bit checksum makes the headers sum to 0.
 *
 *   version 5 (what Igor Pro 3+ and Asylum write): BinHeader5 (64 bytes: version, checksum,
 *     wfmSize, formulaSize, noteSize, dataEUnitsSize, dimEUnitsSize[4], dimLabelsSize[4],
 *     sIndicesSize, 2 reserved) and WaveHeader5 (320 bytes up to its data: npnts at 12, type at
 *     16, the name at 28, nDim[4] at 68, sfA[4] (the steps) at 84, sfB[4] at 116, dataUnits[4]
 *     at 148, dimUnits[4][4] at 152); the checksum covers both (384 bytes). The data follow
 *     (wfmSize - 320 bytes), then the formula, the note, the extended data units, the extended
 *     units of each dimension, the labels of each dimension ((nDim + 1) names of 32 bytes: the
 *     dimension's own, then one per index), the string indices.
 *     Dimension 0 varies fastest and is x (Igor's "rows"), dimension 1 is y, dimension 2 the
 *     layers: Asylum stores every channel of a scan as a layer of one 3-D wave and names them
 *     in the labels of dimension 2 (HeightRetrace, AmplitudeRetrace, PhaseRetrace, ZSensor...).
 *   versions 1-3: BinHeader 8/16/20 bytes and WaveHeader2 (110 bytes: dataUnits at 34, xUnits
 *     at 38, npnts at 42, hsA (the step) at 48), data, 16 bytes of padding, the note (2, 3):
 *     one-dimensional waves only, read as a profile. The checksum covers the headers and the
 *     first 16 bytes of data (WaveHeader2's wData[4]); a checksum over the headers alone is
 *     accepted too (some writers do that).
 *
 * Igor's y axis points up (sfB + sfA e grows with the index) while a map's row 0 is its top
 * line, so the rows come out in reverse order, as Gwyddion shows them (tests/files/check_c.sh
 * compares them point by point). Units: one data unit serves every layer of a wave, which does
 * not fit a multi-channel scan, so for a wave with a note (Asylum's) the unit is the note's
 * "<Channel>Unit" line (the title without Trace/Retrace), else the one the title implies
 * (Height, ZSensor, Amplitude, Deflection: m; Phase: deg; Current: A...: Gwyddion's table), else
 * the wave's extended or short data unit; without a note the data unit first, then the title's.
 * A length unit is converted to metres, any other is reported in z_unit, the values as stored. The
 * steps come from the dimension units (metres, or any SI length); without a length unit there
 * the note's FastScanSize/SlowScanSize (or ScanSize) give the size, else it is 0 (unknown). The
 * note also gives the instrument (MicroscopeModel), the date (Date "YYYY-MM-DD" and Time, else
 * the wave's creation date, seconds since 1904) and the tip radius (TipRadius, m) where written.
 * NaN heights (Igor's blanks) are missing points. Complex and text waves are refused.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bytes.h"
#include "files.h"
#include "files_util.h"

#define NAME "ibw"
#define BIN5 64     /* BinHeader5 */
#define WAVE5 320   /* WaveHeader5 up to its data */
#define WAVE2 110   /* WaveHeader2 up to its data */
#define LABEL 32    /* one dimension label */
#define NOTE_MAX 64 /* the longest note value kept */

/* A fault at a byte offset (files_util.h). */
#define bad(err, offset, ...) ljgap__files_fail(err, NAME, offset, NULL, __VA_ARGS__)

/* The size of the binary header of a version, 0 for an unknown one. */
static size_t bin_size(unsigned v)
{
    return v == 1 ? 8 : v == 2 ? 16 : v == 3 ? 20 : v == 5 ? BIN5 : 0;
}

/* The version and byte order of the first two bytes, 0 when they are no Igor version. */
static unsigned version_of(const unsigned char *buf, size_t len, int *be)
{
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    const unsigned char *p = ljgap__bytes_at(&b, 0, 2);
    if (!p) return 0;
    *be = p[0] == 0;
    unsigned v = *be ? p[1] : p[0] | (unsigned)p[1] << 8;
    return bin_size(v) ? v : 0;
}

/* The sum of the 16-bit words of [0, n), which Igor makes 0 mod 2^16 over the headers (1 when
 * the file is shorter than n). */
static unsigned checksum(const unsigned char *buf, size_t len, size_t n, int be)
{
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    const unsigned char *p = ljgap__bytes_at(&b, 0, n);
    unsigned s = 0;
    if (!p) return 1;
    for (size_t i = 0; i + 1 < n; i += 2)
        s += be ? (unsigned)p[i] << 8 | p[i + 1] : p[i] | (unsigned)p[i + 1] << 8;
    return s & 0xffff;
}

static int ibw_probe(const unsigned char *buf, size_t len)
{
    int be;
    unsigned v = version_of(buf, len, &be);
    if (!v) return 0;
    size_t head = bin_size(v) + (v == 5 ? WAVE5 : WAVE2);
    if (v == 5) return checksum(buf, len, head, be) == 0;
    return checksum(buf, len, head, be) == 0 || checksum(buf, len, head + 16, be) == 0;
}

/* A NUL-padded field of n bytes at p, as text. */
static void field(const unsigned char *p, size_t n, char *out, size_t size)
{
    if (p)
        ljgap__files_utf8(p, n, out, size);
    else
        out[0] = 0;
}

/* The value of "key: value" in the note (lines end in CR or LF), or NULL. */
static const char *note_value(const unsigned char *note, size_t n, const char *key, char *out)
{
    size_t klen = strlen(key);
    if (!note) return NULL;
    for (size_t i = 0; i < n;) {
        size_t e = i;
        while (e < n && note[e] != '\r' && note[e] != '\n')
            e++;
        if (e - i > klen && !memcmp(note + i, key, klen) && note[i + klen] == ':') {
            size_t v = i + klen + 1;
            while (v < e && note[v] == ' ')
                v++;
            field(note + v, e - v, out, NOTE_MAX);
            return out;
        }
        i = e + 1;
    }
    return NULL;
}

/* A finite positive number in a note value, else 0. */
static double note_number(const unsigned char *note, size_t n, const char *key)
{
    char v[NOTE_MAX], *end;
    if (!note_value(note, n, key, v)) return 0;
    double x = strtod(v, &end);
    return end != v && isfinite(x) && x > 0 ? x : 0;
}

/* acquired: the note's Date (YYYY-MM-DD) and Time ("H:MM:SS" with an optional AM/PM), else the
 * creation date (seconds since 1904-01-01, the writer's local time). */
static void acquired(const unsigned char *note, size_t n, uint32_t created, char *out, size_t size)
{
    char d[NOTE_MAX], t[NOTE_MAX];
    int y, mo, da, h = 0, mi = 0, s = 0;
    char ampm[3] = "";
    if (note_value(note, n, "Date", d) && sscanf(d, "%4d-%2d-%2d", &y, &mo, &da) == 3 && y >= 0 &&
        mo >= 1 && mo <= 12 && da >= 1 && da <= 31) {
        if (note_value(note, n, "Time", t) &&
            sscanf(t, "%2d:%2d:%2d %2[APMapm]", &h, &mi, &s, ampm) >= 3 && h >= 0 && h < 24 &&
            mi >= 0 && mi < 60 && s >= 0 && s < 61) {
            if ((ampm[0] == 'P' || ampm[0] == 'p') && h < 12) h += 12;
            if ((ampm[0] == 'A' || ampm[0] == 'a') && h == 12) h = 0;
            snprintf(out, size, "%04d-%02d-%02dT%02d:%02d:%02d", y, mo, da, h, mi, s);
        } else {
            snprintf(out, size, "%04d-%02d-%02d", y, mo, da);
        }
        return;
    }
    if (created) {
        time_t tt = (time_t)((int64_t)created - 2082844800); /* 1904 to 1970 */
        struct tm tm;
        if (gmtime_r(&tt, &tm)) strftime(out, size, "%Y-%m-%dT%H:%M:%S", &tm);
    }
}

/* Igor's number types: the size of one point, 0 for text, complex or unknown ones. */
static size_t type_size(unsigned type)
{
    switch (type) {
    case 0x02:
        return 4; /* NT_FP32 */
    case 0x04:
        return 8; /* NT_FP64 */
    case 0x08:
    case 0x48:
        return 1; /* NT_I8, unsigned */
    case 0x10:
    case 0x50:
        return 2; /* NT_I16 */
    case 0x20:
    case 0x60:
        return 4; /* NT_I32 */
    default:
        return 0;
    }
}

static double value_at(ljgap__bytes *b, unsigned type, int be)
{
    switch (type) {
    case 0x02:
        return ljgap__bytes_f32(b, be);
    case 0x04:
        return ljgap__bytes_f64(b, be);
    case 0x08:
        return (int8_t)ljgap__bytes_u8(b);
    case 0x48:
        return ljgap__bytes_u8(b);
    case 0x10:
        return ljgap__bytes_i16(b, be);
    case 0x50:
        return ljgap__bytes_u16(b, be);
    case 0x20:
        return ljgap__bytes_i32(b, be);
    default:
        return ljgap__bytes_u32(b, be);
    }
}

/* What the headers say, in one place for both layouts. */
typedef struct {
    int be;                      /* big endian */
    unsigned version;            /* 1, 2, 3 or 5 */
    unsigned type;               /* Igor's number type */
    size_t n[3];                 /* points along x, y, layers (1 where absent) */
    double step[2];              /* sfA (hsA) of x and y */
    char data_unit[32];          /* the wave's data unit (extended if given) */
    char dim_unit[2][32];        /* the units of x and y */
    char name[LJGAP_FILES_TEXT]; /* the wave's name */
    uint32_t created;            /* the creation date, seconds since 1904 */
    size_t data;                 /* the offset of the data */
    const unsigned char *note;   /* the note, noteSize bytes (NULL if none) */
    size_t note_len;
    const unsigned char *labels; /* the labels of dimension 2, nlabels of them */
    size_t nlabels;
} wave;

/* Reads the headers and locates the sections of a version 5 wave. */
static int read_v5(ljgap__bytes *b, wave *w, ljgap__files_err *err)
{
    int be = w->be;
    ljgap__bytes_seek(b, 4);
    uint32_t wfm = ljgap__bytes_u32(b, be), formula = ljgap__bytes_u32(b, be);
    uint32_t note = ljgap__bytes_u32(b, be), data_eunits = ljgap__bytes_u32(b, be);
    uint32_t dim_eunits[4], dim_labels[4];
    for (int i = 0; i < 4; i++)
        dim_eunits[i] = ljgap__bytes_u32(b, be);
    for (int i = 0; i < 4; i++)
        dim_labels[i] = ljgap__bytes_u32(b, be);
    ljgap__bytes_seek(b, BIN5 + 4);
    w->created = ljgap__bytes_u32(b, be);
    ljgap__bytes_seek(b, BIN5 + 12);
    uint32_t npnts = ljgap__bytes_u32(b, be);
    w->type = ljgap__bytes_u16(b, be);
    const unsigned char *p = ljgap__bytes_at(b, BIN5 + 28, 32);
    if (p) field(p, 32, w->name, sizeof w->name);
    ljgap__bytes_seek(b, BIN5 + 68);
    uint32_t ndim[4];
    for (int i = 0; i < 4; i++)
        ndim[i] = ljgap__bytes_u32(b, be);
    for (int i = 0; i < 2; i++)
        w->step[i] = ljgap__bytes_f64(b, be);
    if ((p = ljgap__bytes_at(b, BIN5 + 148, 4))) field(p, 4, w->data_unit, sizeof w->data_unit);
    for (int i = 0; i < 2; i++)
        if ((p = ljgap__bytes_at(b, BIN5 + 152 + 4 * i, 4)))
            field(p, 4, w->dim_unit[i], sizeof w->dim_unit[i]);
    if (b->bad) return bad(err, (long)b->where, "the headers are truncated");

    if (ndim[0] == 0 || (ndim[1] == 0 && ndim[2]) || ndim[3] > 1)
        return bad(err, BIN5 + 68, "a wave of %u x %u x %u x %u points is no map", ndim[0], ndim[1],
                   ndim[2], ndim[3]);
    w->n[0] = ndim[0], w->n[1] = ndim[1] ? ndim[1] : 1, w->n[2] = ndim[2] ? ndim[2] : 1;
    if ((uint64_t)w->n[0] * w->n[1] * w->n[2] != npnts)
        return bad(err, BIN5 + 12, "npnts %u is not the product of the dimensions", npnts);
    size_t ts = type_size(w->type);
    if (!ts) return bad(err, BIN5 + 16, "unsupported wave type 0x%x (text or complex)", w->type);
    if ((uint64_t)w->n[0] * w->n[1] > LJGAP_FILES_MAX_POINTS)
        return ljgap__files_report(err, LJGAP_FILES_TOOBIG, NAME, -1, NULL,
                                   "%zu x %zu points are too many", w->n[0], w->n[1]);
    if (wfm < WAVE5 || wfm - WAVE5 < (uint64_t)npnts * ts)
        return bad(err, 4, "wfmSize %u does not hold %u points", wfm, npnts);

    /* the sections after the data, in order; each must be there in full */
    w->data = BIN5 + WAVE5;
    uint64_t at = (uint64_t)w->data + (wfm - WAVE5);
    if (at > b->len)
        return bad(err, (long)b->len, "the file ends inside the data (%u bytes from %zu)",
                   wfm - WAVE5, w->data);
    uint64_t sizes[12] = {formula,       note,          data_eunits,   dim_eunits[0],
                          dim_eunits[1], dim_eunits[2], dim_eunits[3], dim_labels[0],
                          dim_labels[1], dim_labels[2], dim_labels[3], 0};
    uint64_t start[12];
    for (int i = 0; i < 11; i++) {
        start[i] = at;
        at += sizes[i];
        if (at > b->len)
            return bad(err, (long)(start[i] <= b->len ? b->len : start[i]),
                       "the file ends inside a section of %llu bytes at offset %llu",
                       (unsigned long long)sizes[i], (unsigned long long)start[i]);
    }
    if (note) w->note = ljgap__bytes_at(b, start[1], note), w->note_len = note;
    if (data_eunits)
        field(ljgap__bytes_at(b, start[2], data_eunits), data_eunits, w->data_unit,
              sizeof w->data_unit);
    for (int i = 0; i < 2; i++)
        if (dim_eunits[i])
            field(ljgap__bytes_at(b, start[3 + i], dim_eunits[i]), dim_eunits[i], w->dim_unit[i],
                  sizeof w->dim_unit[i]);
    if (dim_labels[2])
        w->labels = ljgap__bytes_at(b, start[9], dim_labels[2]), w->nlabels = dim_labels[2] / LABEL;
    return 0;
}

/* Reads the headers of a version 1-3 wave (one dimension). */
static int read_v2(ljgap__bytes *b, wave *w, ljgap__files_err *err)
{
    int be = w->be;
    size_t bh = bin_size(w->version), wh = bh;
    ljgap__bytes_seek(b, 2);
    uint32_t wfm = ljgap__bytes_u32(b, be), note = w->version >= 2 ? ljgap__bytes_u32(b, be) : 0;
    w->type = (ljgap__bytes_seek(b, wh), ljgap__bytes_u16(b, be));
    const unsigned char *p = ljgap__bytes_at(b, wh + 6, 20);
    if (p) field(p, 20, w->name, sizeof w->name);
    if ((p = ljgap__bytes_at(b, wh + 34, 4))) field(p, 4, w->data_unit, sizeof w->data_unit);
    if ((p = ljgap__bytes_at(b, wh + 38, 4))) field(p, 4, w->dim_unit[0], sizeof w->dim_unit[0]);
    ljgap__bytes_seek(b, wh + 42);
    uint32_t npnts = ljgap__bytes_u32(b, be);
    ljgap__bytes_seek(b, wh + 48);
    w->step[0] = ljgap__bytes_f64(b, be);
    ljgap__bytes_seek(b, wh + 96);
    w->created = w->version > 1 ? ljgap__bytes_u32(b, be) : 0;
    if (b->bad) return bad(err, (long)b->where, "the headers are truncated");
    size_t ts = type_size(w->type);
    if (!ts) return bad(err, (long)wh, "unsupported wave type 0x%x (text or complex)", w->type);
    if (npnts == 0) return bad(err, (long)wh + 42, "the wave has no points");
    if (npnts > LJGAP_FILES_MAX_POINTS)
        return ljgap__files_report(err, LJGAP_FILES_TOOBIG, NAME, -1, NULL,
                                   "%u points are too many", npnts);
    if (wfm < WAVE2 + 16 || wfm - WAVE2 - 16 < (uint64_t)npnts * ts)
        return bad(err, 2, "wfmSize %u does not hold %u points", wfm, npnts);
    w->n[0] = npnts, w->n[1] = 1, w->n[2] = 1;
    w->data = bh + WAVE2;
    uint64_t at = (uint64_t)bh + wfm;
    if (at > b->len) return bad(err, (long)b->len, "the file ends inside the data");
    if (at + note > b->len) return bad(err, (long)b->len, "the file ends inside the note");
    if (note) w->note = ljgap__bytes_at(b, at, note), w->note_len = note;
    return 0;
}

/* The unit an Asylum channel's title implies (Gwyddion's table), NULL for an unknown title. */
static const char *title_unit(const char *title)
{
    static const struct {
        const char *prefix, *unit;
    } table[] = {{"Height", "m"},     {"ZSensor", "m"},     {"Deflection", "m"},
                 {"Amplitude", "m"},  {"Phase", "deg"},     {"Current", "A"},
                 {"Frequency", "Hz"}, {"Capacitance", "F"}, {"Potential", "V"}};
    if (!strncmp(title, "DAC", 3)) title += 3;
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
        if (!strncmp(title, table[i].prefix, strlen(table[i].prefix))) return table[i].unit;
    return NULL;
}

/* The name a channel's unit goes by in Asylum's note: the title without Trace/Retrace. */
static void unit_key(const char *title, char *key, size_t size)
{
    char t[LJGAP_FILES_TEXT];
    snprintf(t, sizeof t, "%s", title);
    size_t n = strlen(t);
    if (n > 7 && !strcmp(t + n - 7, "Retrace"))
        t[n - 7] = 0;
    else if (n > 5 && !strcmp(t + n - 5, "Trace"))
        t[n - 5] = 0;
    snprintf(key, size, "%sUnit", t);
}

static int read_file(const unsigned char *buf, size_t len, const char *channel,
                     ljgap__files_map *map, ljgap__files_err *err)
{
    ljgap__files_map_init(map, NAME);
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    wave w;
    memset(&w, 0, sizeof w);
    w.version = version_of(buf, len, &w.be);
    if (!w.version) return bad(err, 0, "no Igor binary wave version (1, 2, 3 or 5)");
    size_t head = bin_size(w.version) + (w.version == 5 ? WAVE5 : WAVE2);
    if (len < head) return bad(err, (long)len, "the file ends inside the headers");
    if (!ibw_probe(buf, len)) return bad(err, 0, "the header checksum is wrong");
    int rc = w.version == 5 ? read_v5(&b, &w, err) : read_v2(&b, &w, err);
    if (rc) return rc;

    /* channels: the labels of dimension 2 (label 0 names the dimension itself) */
    int nch = (int)(w.n[2] < LJGAP_FILES_MAX_CHANNELS ? w.n[2] : LJGAP_FILES_MAX_CHANNELS);
    for (int c = 0; c < nch; c++) {
        char *t = map->channels[c];
        if (w.labels && (size_t)c + 1 < w.nlabels)
            field(w.labels + (c + 1) * LABEL, LABEL, t, LJGAP_FILES_TEXT);
        if (!t[0]) {
            if (w.n[2] == 1 && w.name[0])
                snprintf(t, LJGAP_FILES_TEXT, "%s", w.name);
            else
                snprintf(t, LJGAP_FILES_TEXT, "layer %d", c);
        }
    }
    map->n_channels = nch;
    int ch = ljgap__files_channel_pick(map, channel, err);
    if (ch < 0) return LJGAP_FILES_CHANNEL;
    map->channel_index = ch;
    snprintf(map->channel, sizeof map->channel, "%s", map->channels[ch]);

    /* units and size */
    char key[LJGAP_FILES_TEXT + 8], unit[NOTE_MAX] = "";
    const char *implied = title_unit(map->channel);
    unit_key(map->channel, key, sizeof key);
    if (!w.note || !note_value(w.note, w.note_len, key, unit))
        snprintf(unit, sizeof unit, "%s",
                 implied && (w.note || !w.data_unit[0]) ? implied : w.data_unit);
    snprintf(map->z_unit, sizeof map->z_unit, "%s", unit);
    double q = ljgap__files_unit_scale(unit);
    if (q == 0) q = 1;
    size_t nx = w.n[0], ny = w.n[1];
    for (int i = 0; i < 2; i++) {
        double s = 0, f = ljgap__files_unit_scale(w.dim_unit[i]);
        if (i == 1 && ny == 1) continue; /* a profile has no y extent */
        if (f > 0) s = fabs(w.step[i]) * f * (double)w.n[i];
        if (!(isfinite(s) && s > 0))
            s = note_number(w.note, w.note_len, i ? "SlowScanSize" : "FastScanSize");
        if (s == 0) s = note_number(w.note, w.note_len, "ScanSize");
        *(i ? &map->size_y : &map->size_x) = s;
    }
    char v[NOTE_MAX];
    if (note_value(w.note, w.note_len, "MicroscopeModel", v))
        snprintf(map->instrument, sizeof map->instrument, "Asylum Research %s", v);
    map->tip_radius = note_number(w.note, w.note_len, "TipRadius");
    if (!(map->tip_radius < 1e-3)) map->tip_radius = 0;
    acquired(w.note, w.note_len, w.created, map->acquired, sizeof map->acquired);

    /* the data, rows reversed (Igor's y grows with the index) */
    if ((rc = ljgap__files_alloc(map, nx, ny, err))) return rc;
    size_t ts = type_size(w.type), layer = nx * ny;
    ljgap__bytes_seek(&b, w.data + (size_t)ch * layer * ts);
    for (size_t j = 0; j < map->ny; j++) {
        size_t row = (map->ny - 1 - j) * map->nx;
        for (size_t i = 0; i < map->nx; i++)
            ljgap__files_put(map, row + i, value_at(&b, w.type, w.be) * q);
    }
    if (b.bad) { /* cannot happen: read_v5/read_v2 checked the extent; kept as a guard */
        free(map->z), map->z = NULL;
        return bad(err, (long)b.where, "the data are truncated");
    }
    return 0;
}

/* The reader: read_file, a fault's offset kept inside the file (files_util.h). */
static int ibw_read(const unsigned char *buf, size_t len, const char *channel, ljgap__files_map *map,
                    ljgap__files_err *err)
{
    return ljgap__files_read_within(read_file, buf, len, channel, map, err);
}

const ljgap__files_format ljgap__files_ibw = {
    .name = NAME,
    .extensions = ".ibw",
    .media_type = "application/x-igor-binary-wave",
    .probe = ibw_probe,
    .read = ibw_read,
};
