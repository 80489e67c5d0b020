/* netcdf.c -- netCDF files as contact.engineering and SurfaceTopography write them.
 *
 * The layout (SurfaceTopography's NC.py, its writer write_nc_uniform): a variable `heights`
 * with dimensions (x, y) -- the first index runs along x -- or (x) for a line scan, optional
 * coordinate variables `x` and `y` whose attributes `length` (the physical size, in `unit`),
 * `unit` and `periodic` (nonzero: periodic) describe the grid, `heights:unit` (the same unit),
 * an optional byte variable `mask` (nonzero: the point is undefined) and a global attribute
 * `json` holding SurfaceTopography's info dictionary (acquisition_time, instrument). Missing
 * points are also those equal to `_FillValue` or `missing_value` (or, without `_FillValue`,
 * netCDF's default fill value of the type) and non-finite values; `scale_factor` and
 * `add_offset` apply. Dimensions named (y, x) are taken as such (rows along y).
 *
 * SurfaceTopography writes the classic formats (NETCDF3_64BIT_OFFSET by default), so this is a
 * reader of the classic format itself (CDF-1, CDF-2 and CDF-5, Unidata's "NetCDF Classic Format
 * Specification"): a big-endian header -- magic "CDF" and version byte, the record count, the
 * dimension list, the global attributes, the variables (name, dimension ids, attributes, type,
 * size and begin offset) -- then the data. Every read is bounded (bytes.h). Not read: netCDF-4
 * (HDF5) files (recognised and refused with a message), record (unlimited) variables,
 * nonuniform line scans (dimension `n`), and other variable names than `heights`.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "bytes.h"
#include "files_util.h"

#define NC "netcdf"
#define NC_DIMENSION 10
#define NC_VARIABLE 11
#define NC_ATTRIBUTE 12
#define MAX_DIMS 1024

typedef struct {
    int type;   /* nc_type, 0 when absent */
    uint64_t n; /* values */
    size_t at;  /* offset of the values */
} nc_att;

typedef struct {
    int present;       /* the variable exists */
    int ndims;         /* its dimensions (at most 2 are kept) */
    uint64_t dimid[2]; /* their ids */
    int type;          /* nc_type */
    uint64_t begin;    /* data offset */
    nc_att unit, length, periodic, fill, missing, scale, offset; /* attributes read */
} nc_var;

typedef struct {
    ljgap__bytes b;              /* the cursor */
    int version;                /* 1, 2 (64-bit offsets) or 5 (64-bit data) */
    size_t ndims;               /* dimensions */
    uint64_t dimlen[MAX_DIMS];  /* their lengths (0: the record dimension) */
    char dimname[MAX_DIMS][8];  /* their names (first 7 bytes) */
    nc_att json;                /* the global attribute json */
    uint64_t data_end;          /* the end of the last fixed-size variable's data */
    nc_var heights, x, y, mask; /* the variables read */
} nc_file;

static int nc_probe(const unsigned char *buf, size_t len)
{
    if (len >= 4 && !memcmp(buf, "CDF", 3) && (buf[3] == 1 || buf[3] == 2 || buf[3] == 5)) return 1;
    return len >= 8 && !memcmp(buf, "\x89HDF\r\n\x1a\n", 8);
}

static size_t type_size(int t)
{
    static const size_t s[] = {0, 1, 1, 2, 4, 4, 8, 1, 2, 4, 8, 8};
    return t >= 1 && t <= 11 ? s[t] : 0;
}

/* A count: 32 bits, 64 in CDF-5. */
static uint64_t rd_n(nc_file *f)
{
    return f->version == 5 ? ljgap__bytes_u64(&f->b, 1) : ljgap__bytes_u32(&f->b, 1);
}

/* Skips to the next multiple of 4. */
static void rd_pad(nc_file *f)
{
    size_t p = f->b.pos;
    if (p % 4) ljgap__bytes_seek(&f->b, p + 4 - p % 4);
}

/* A name: its length, its bytes, padding; the first size - 1 bytes kept in out. */
static void rd_name(nc_file *f, char *out, size_t size)
{
    uint64_t n = rd_n(f);
    if (n > f->b.len) {
        if (!f->b.bad) f->b.bad = 1, f->b.where = f->b.pos;
        out[0] = 0;
        return;
    }
    ljgap__bytes_str(&f->b, (size_t)n, out, size);
    rd_pad(f);
}

/* One value of type t at offset at, as a double (b.bad set when out of the buffer). */
static double value_at(ljgap__bytes *b, int t, size_t at)
{
    if (ljgap__bytes_seek(b, at)) return 0;
    switch (t) {
    case 1:
        return (int8_t)ljgap__bytes_u8(b);
    case 2:
        return ljgap__bytes_u8(b);
    case 3:
        return ljgap__bytes_i16(b, 1);
    case 4:
        return ljgap__bytes_i32(b, 1);
    case 5:
        return ljgap__bytes_f32(b, 1);
    case 6:
        return ljgap__bytes_f64(b, 1);
    case 7:
        return ljgap__bytes_u8(b);
    case 8:
        return ljgap__bytes_u16(b, 1);
    case 9:
        return ljgap__bytes_u32(b, 1);
    case 10:
        return (double)(int64_t)ljgap__bytes_u64(b, 1);
    case 11:
        return (double)ljgap__bytes_u64(b, 1);
    }
    return 0;
}

/* An attribute's first value as a number (0 when absent or text). */
static int att_num(nc_file *f, const nc_att *a, double *v)
{
    if (!a->type || a->type == 2 || a->n == 0) return 0;
    *v = value_at(&f->b, a->type, a->at);
    return !f->b.bad;
}

/* A text attribute into out. */
static int att_str(nc_file *f, const nc_att *a, char *out, size_t size)
{
    out[0] = 0;
    if (a->type != 2) return 0;
    const unsigned char *p = ljgap__bytes_at(&f->b, a->at, (size_t)a->n);
    if (!p) return 0;
    ljgap__files_utf8(p, (size_t)a->n, out, size);
    return 1;
}

/* An attribute list (tag, count, attributes); the ones named in `want` are stored. */
static int rd_atts(nc_file *f, nc_var *var, nc_att *json)
{
    uint32_t tag = ljgap__bytes_u32(&f->b, 1);
    uint64_t n = rd_n(f);
    if (tag == 0 && n == 0) return 0;
    if (tag != NC_ATTRIBUTE) return -1;
    for (uint64_t i = 0; i < n && !f->b.bad; i++) {
        char name[32];
        rd_name(f, name, sizeof name);
        nc_att a = {(int)ljgap__bytes_u32(&f->b, 1), 0, 0};
        a.n = rd_n(f);
        a.at = f->b.pos;
        size_t sz = type_size(a.type);
        if (!sz || a.n > (f->b.len - a.at) / sz) return -1;
        ljgap__bytes_seek(&f->b, a.at + (size_t)a.n * sz);
        rd_pad(f);
        if (json && !strcmp(name, "json")) *json = a;
        if (!var) continue;
        if (!strcmp(name, "unit") || (!strcmp(name, "units") && !var->unit.type))
            var->unit = a;
        else if (!strcmp(name, "length"))
            var->length = a;
        else if (!strcmp(name, "periodic"))
            var->periodic = a;
        else if (!strcmp(name, "_FillValue"))
            var->fill = a;
        else if (!strcmp(name, "missing_value"))
            var->missing = a;
        else if (!strcmp(name, "scale_factor"))
            var->scale = a;
        else if (!strcmp(name, "add_offset"))
            var->offset = a;
    }
    return f->b.bad ? -1 : 0;
}

/* The header: 0, or the byte offset of the fault + 1 (negated) on a bad header. */
static long rd_header(nc_file *f)
{
    ljgap__bytes_seek(&f->b, 4);
    (void)rd_n(f); /* numrecs */
    uint32_t tag = ljgap__bytes_u32(&f->b, 1);
    uint64_t n = rd_n(f);
    if (tag != NC_DIMENSION && !(tag == 0 && n == 0)) return (long)f->b.pos - 8;
    if (n > MAX_DIMS) return (long)f->b.pos - 4;
    f->ndims = (size_t)n;
    for (size_t i = 0; i < f->ndims && !f->b.bad; i++) {
        rd_name(f, f->dimname[i], sizeof f->dimname[i]);
        f->dimlen[i] = rd_n(f);
    }
    if (rd_atts(f, NULL, &f->json)) return f->b.bad ? (long)f->b.where : (long)f->b.pos;
    size_t vat = f->b.pos;
    tag = ljgap__bytes_u32(&f->b, 1);
    n = rd_n(f);
    if (tag != NC_VARIABLE && !(tag == 0 && n == 0)) return (long)vat;
    for (uint64_t i = 0; i < n && !f->b.bad; i++) {
        char name[16];
        rd_name(f, name, sizeof name);
        nc_var tmp, *v = !strcmp(name, "heights") ? &f->heights
                         : !strcmp(name, "x")     ? &f->x
                         : !strcmp(name, "y")     ? &f->y
                         : !strcmp(name, "mask")  ? &f->mask
                                                  : &tmp;
        memset(v, 0, sizeof *v);
        v->present = 1;
        uint64_t nd = rd_n(f);
        if (nd > MAX_DIMS) return (long)f->b.pos;
        v->ndims = (int)nd;
        uint64_t count = 1; /* values, saturating; 0 for a record variable */
        for (uint64_t d = 0; d < nd && !f->b.bad; d++) {
            uint64_t id = rd_n(f);
            if (id >= f->ndims) return (long)f->b.pos - 4;
            if (d < 2) v->dimid[d] = id;
            uint64_t l = f->dimlen[id];
            count = l == 0 ? 0 : count > UINT64_MAX / 16 / l ? UINT64_MAX / 16 : count * l;
        }
        if (rd_atts(f, v, NULL)) return f->b.bad ? (long)f->b.where : (long)f->b.pos;
        v->type = (int)ljgap__bytes_u32(&f->b, 1);
        if (!type_size(v->type) && !f->b.bad) return (long)f->b.pos - 4;
        (void)rd_n(f); /* vsize */
        v->begin = f->version == 1 ? ljgap__bytes_u32(&f->b, 1) : ljgap__bytes_u64(&f->b, 1);
        uint64_t end = v->begin + count * type_size(v->type);
        if (count && v->begin <= UINT64_MAX / 2 && end > f->data_end) f->data_end = end;
    }
    return f->b.bad ? (long)f->b.where : -1;
}

/* Scans SurfaceTopography's json info for "key": "text" (the first occurrence after from). */
static const char *json_text(const char *js, const char *from, const char *key, char *out,
                             size_t size)
{
    char pat[40];
    snprintf(pat, sizeof pat, "\"%s\"", key);
    const char *p = strstr(from ? from : js, pat);
    out[0] = 0;
    if (!p) return NULL;
    p += strlen(pat);
    while (*p == ' ' || *p == ':')
        p++;
    size_t k = 0;
    if (*p == '"') {
        for (p++; *p && *p != '"'; p++) {
            char c = *p;
            if (c == '\\' && p[1]) { /* an escape: \" \\ \/ kept, others a blank */
                c = strchr("\"\\/", p[1]) ? p[1] : ' ';
                p += p[1] == 'u' && p[2] && p[3] && p[4] && p[5] ? 5 : 1;
            }
            if (k + 1 < size) out[k++] = c;
        }
    } else {
        for (; *p && (strchr("+-.eE", *p) || (*p >= '0' && *p <= '9')) && k + 1 < size; p++)
            out[k++] = *p;
    }
    out[k] = 0;
    return p;
}

/* acquisition_time, instrument name and tip radius from the json attribute. */
static void read_info(nc_file *f, ljgap__files_map *map)
{
    if (f->json.type != 2 || f->json.n == 0 || f->json.n > 65536) return;
    char *js = malloc((size_t)f->json.n + 1);
    if (!js) return;
    const unsigned char *p = ljgap__bytes_at(&f->b, f->json.at, (size_t)f->json.n);
    if (p) {
        memcpy(js, p, (size_t)f->json.n);
        js[f->json.n] = 0;
        json_text(js, NULL, "acquisition_time", map->acquired, sizeof map->acquired);
        const char *ins = strstr(js, "\"instrument\"");
        if (ins) json_text(js, ins, "name", map->instrument, sizeof map->instrument);
        const char *tip = strstr(js, "\"tip_radius\"");
        char val[40], unit[16];
        if (tip && json_text(js, tip, "value", val, sizeof val) &&
            json_text(js, tip, "unit", unit, sizeof unit)) {
            double r = strtod(val, NULL) * ljgap__files_unit_scale(unit);
            if (isfinite(r) && r > 0) map->tip_radius = r;
        }
    }
    free(js);
}

static double default_fill(int t)
{
    static const double fill[] = {0,
                                  -127,
                                  0,
                                  -32767,
                                  -2147483647,
                                  9.9692099683868690e+36f,
                                  9.9692099683868690e+36,
                                  255,
                                  65535,
                                  4294967295.0,
                                  -9223372036854775806.0,
                                  18446744073709551614.0};
    return t >= 1 && t <= 11 ? fill[t] : 0;
}

static int nc_read(const unsigned char *buf, size_t len, const char *channel, ljgap__files_map *map,
                   ljgap__files_err *err)
{
    ljgap__files_map_init(map, NC);
    if (len >= 8 && !memcmp(buf, "\x89HDF\r\n\x1a\n", 8))
        return ljgap__files_fail(err, NC, 0, NULL,
                                 "a netCDF-4 (HDF5) file: only the classic formats are read; save "
                                 "as NETCDF3_64BIT_OFFSET (SurfaceTopography's default)");
    nc_file *f = calloc(1, sizeof *f);
    if (!f) return ljgap__files_report(err, LJGAP_FILES_NOMEM, NC, -1, NULL, "out of memory");
    ljgap__bytes_init(&f->b, buf, len);
    int rc = 0;
    if (len < 4 || memcmp(buf, "CDF", 3) || (buf[3] != 1 && buf[3] != 2 && buf[3] != 5)) {
        rc = ljgap__files_fail(err, NC, 0, NULL, "no classic netCDF magic");
        goto done;
    }
    f->version = buf[3];
    long bad = rd_header(f);
    if (bad > (long)len) bad = (long)len; /* a padding skipped past the end */
    if (bad >= 0) {
        rc = ljgap__files_fail(err, NC, bad, NULL, "the netCDF header is %s at byte %ld",
                               f->b.bad ? "cut short" : "malformed", bad);
        goto done;
    }
    f->b.bad = 0;
    if (f->data_end > len) {
        rc = ljgap__files_fail(err, NC, (long)len, NULL,
                               "the file is cut short at byte %zu: its variables reach byte %llu",
                               len, (unsigned long long)f->data_end);
        goto done;
    }
    snprintf(map->channels[0], LJGAP_FILES_TEXT, "heights");
    map->n_channels = 1;
    if (ljgap__files_channel_pick(map, channel, err) != 0) {
        rc = LJGAP_FILES_CHANNEL;
        goto done;
    }
    snprintf(map->channel, sizeof map->channel, "heights");
    nc_var *h = &f->heights;
    if (!h->present) {
        rc = ljgap__files_fail(err, NC, -1, NULL, "no variable named heights");
        goto done;
    }
    if (h->ndims < 1 || h->ndims > 2) {
        rc = ljgap__files_fail(err, NC, -1, NULL,
                               "the variable heights has %d dimensions: 1 or 2 are read", h->ndims);
        goto done;
    }
    uint64_t n0 = f->dimlen[h->dimid[0]], n1 = h->ndims == 2 ? f->dimlen[h->dimid[1]] : 1;
    if (n0 == 0 || n1 == 0) {
        rc = ljgap__files_fail(err, NC, -1, NULL,
                               "heights is a record (unlimited) variable or empty: not read");
        goto done;
    }
    if (!strcmp(f->dimname[h->dimid[0]], "n")) {
        rc = ljgap__files_fail(err, NC, -1, NULL, "a nonuniform line scan (dimension n): not read");
        goto done;
    }
    /* (y, x): rows along y as stored; otherwise the first index runs along x */
    int yx = h->ndims == 2 && !strcmp(f->dimname[h->dimid[0]], "y") &&
             !strcmp(f->dimname[h->dimid[1]], "x");
    size_t nx = (size_t)(yx ? n1 : n0), ny = (size_t)(yx ? n0 : n1);
    if (n0 > LJGAP_FILES_MAX_POINTS || n1 > LJGAP_FILES_MAX_POINTS) {
        rc = ljgap__files_report(err, LJGAP_FILES_TOOBIG, NC, -1, NULL, "%llu x %llu points",
                                 (unsigned long long)n0, (unsigned long long)n1);
        goto done;
    }
    size_t n = nx * ny, sz = type_size(h->type);
    if (h->begin > len || n > (len - h->begin) / sz) {
        rc = ljgap__files_fail(err, NC, (long)len, NULL,
                               "the heights (%zu values from byte %llu) are cut short at byte %zu",
                               n, (unsigned long long)h->begin, len);
        goto done;
    }
    int has_mask = f->mask.present && f->mask.ndims == h->ndims &&
                   f->mask.dimid[0] == h->dimid[0] && f->mask.dimid[1] == h->dimid[1] &&
                   type_size(f->mask.type);
    size_t msz = has_mask ? type_size(f->mask.type) : 0;
    if (has_mask && (f->mask.begin > len || n > (len - f->mask.begin) / msz)) {
        rc = ljgap__files_fail(err, NC, (long)len, NULL,
                               "the mask (%zu values from byte %llu) is cut short at byte %zu", n,
                               (unsigned long long)f->mask.begin, len);
        goto done;
    }
    rc = ljgap__files_alloc_at(map, nx, ny, err, -1);
    if (rc) goto done;

    /* units: heights:unit, else x:unit (SurfaceTopography keeps one unit for all) */
    char unit[32] = "";
    if (!att_str(f, &h->unit, unit, sizeof unit) || !unit[0])
        att_str(f, &f->x.unit, unit, sizeof unit);
    double fz = ljgap__files_unit_scale(unit);
    snprintf(map->z_unit, sizeof map->z_unit, "%s", unit);
    double fill = default_fill(h->type), missing = 0, scale = 1, offset = 0;
    int has_fill = 1, has_missing = att_num(f, &h->missing, &missing);
    if (h->fill.type) has_fill = att_num(f, &h->fill, &fill);
    att_num(f, &h->scale, &scale);
    att_num(f, &h->offset, &offset);
    for (size_t j = 0; j < ny; j++)
        for (size_t i = 0; i < nx; i++) {
            size_t k = yx ? j * nx + i : i * ny + j; /* the value's index in the file */
            double v = value_at(&f->b, h->type, (size_t)h->begin + k * sz);
            int hole = (has_fill && v == fill) || (has_missing && v == missing);
            if (has_mask && value_at(&f->b, f->mask.type, (size_t)f->mask.begin + k * msz) != 0)
                hole = 1;
            v = (v * scale + offset) * (fz > 0 ? fz : 1);
            ljgap__files_put(map, j * nx + i, hole ? NAN : v);
        }
    if (f->b.bad) { /* not reached: the extents were checked */
        rc = ljgap__files_fail(err, NC, (long)f->b.where, NULL, "data cut short");
        goto done;
    }
    /* size: x:length and y:length in x's unit */
    char xunit[32] = "";
    if (!att_str(f, &f->x.unit, xunit, sizeof xunit)) snprintf(xunit, sizeof xunit, "%s", unit);
    double fl = ljgap__files_unit_scale(xunit), lx = 0, ly = 0, per = 0;
    if (fl > 0 && att_num(f, &f->x.length, &lx) && isfinite(lx) && lx > 0) {
        map->size_x = lx * fl;
        if (ny == 1)
            map->size_y = map->size_x / (double)nx;
        else if (att_num(f, &f->y.length, &ly) && isfinite(ly) && ly > 0)
            map->size_y = ly * fl;
        else
            map->size_x = 0;
    }
    if (att_num(f, &f->x.periodic, &per) && per != 0) map->periodic = 1;
    read_info(f, map);
done:
    free(f);
    return rc;
}

const ljgap__files_format ljgap__files_netcdf = {
    .name = "netcdf",
    .extensions = ".nc",
    .media_type = "application/netcdf",
    .probe = nc_probe,
    .read = nc_read,
};
