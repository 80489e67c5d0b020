/* test_files_b.c -- the X3P, Digital Surf, MetroPro and netCDF readers (server/files/, issue 28),
 * each on files this test writes from the format's description:
 *
 *   - exact read-back: grid, size in metres, every height (the format's formula applied to the
 *     stored values), the missing points (NaN, a valid-point bit, a "no data" value, a mask,
 *     a _FillValue), the metadata (instrument, date, units, periodic, tip radius), channels by
 *     index and title, an unknown channel (LJGAP_FILES_CHANNEL);
 *   - variants: .sur 16 and 32 bits, comment and private zones, DSCOMPRESSED, two objects,
 *     the inversions;
 *     MetroPro formats 1 and 3, phase resolutions, the sign flag, an intensity frame; X3P
 *     stored and deflated members, float NaN and integer valid bits, a profile, an inline
 *     DataList; netCDF CDF-1 and CDF-2, (x, y) and (y, x), a profile, a mask variable;
 *   - every prefix of every file (each length from 0 to len - 1) is LJGAP_FILES_BAD with the
 *     format named and an offset within the file or a member named; every single byte of every
 *     file inverted in turn never crashes, and what reads comes out consistent (missing = the
 *     NaN count, finite sizes) -- run it under ASan/UBSan for the "never a read past the
 *     buffer" guarantee;
 *   - the errors each reader names: bits per point, phase resolution, a CRC mismatch in a
 *     member, a missing member, an HDF5 netCDF-4 file, a grid over the point limit (TOOBIG);
 *   - probes: each recognises its files and none of the others'.
 * The independent cross-checks (Gwyddion, python3-netcdf4) are tests/files/check_b.sh.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "check.h"
#include "files.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

/* ---- a byte buffer to write files into ---- */

typedef struct {
    unsigned char *p; /* bytes */
    size_t n, cap;    /* used, allocated */
} wbuf;

static void put(wbuf *w, const void *src, size_t n)
{
    if (w->n + n > w->cap) {
        w->cap = (w->n + n) * 2 + 64;
        w->p = realloc(w->p, w->cap);
        assert_non_null(w->p);
    }
    memcpy(w->p + w->n, src, n);
    w->n += n;
}

static void putu(wbuf *w, uint64_t v, size_t n, int be)
{
    unsigned char b[8];
    for (size_t i = 0; i < n; i++)
        b[be ? n - 1 - i : i] = (unsigned char)(v >> (8 * i));
    put(w, b, n);
}

static void putf64(wbuf *w, double d, int be)
{
    uint64_t u;
    memcpy(&u, &d, 8);
    putu(w, u, 8, be);
}

static void zeros(wbuf *w, size_t n)
{
    while (n--)
        putu(w, 0, 1, 0);
}

/* writes at a fixed offset (the buffer is at least that long) */
static void poke(wbuf *w, size_t at, uint64_t v, size_t n, int be)
{
    for (size_t i = 0; i < n; i++)
        w->p[at + (be ? n - 1 - i : i)] = (unsigned char)(v >> (8 * i));
}

static void pokef32(wbuf *w, size_t at, float f, int be)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    poke(w, at, u, 4, be);
}

static void poketext(wbuf *w, size_t at, const char *s)
{
    memcpy(w->p + at, s, strlen(s));
}

static void map_release(ljgap__files_map *m)
{
    free(m->z);
    m->z = NULL;
}

/* A pseudo-random stream (the values need not be random, only varied). */
static uint32_t rnd_state = 12345;
static int32_t rnd(int32_t lim)
{
    rnd_state = rnd_state * 1103515245u + 12345u;
    return (int32_t)((rnd_state >> 8) % (uint32_t)(2 * lim + 1)) - lim;
}

/* ---- the robustness sweeps every format goes through ---- */

static void sweep(const ljgap__files_format *f, const wbuf *w)
{
    /* every prefix: bad, named, located */
    for (size_t len = 0; len < w->n; len++) {
        unsigned char *cut = malloc(len ? len : 1); /* exact size: ASan sees any overread */
        memcpy(cut, w->p, len);
        ljgap__files_map m;
        ljgap__files_err e;
        memset(&e, 0, sizeof e);
        int rc = f->read(cut, len, NULL, &m, &e);
        if (rc != LJGAP_FILES_BAD)
            fail_msg("%s cut at %zu of %zu: rc %d (%s)", f->name, len, w->n, rc, e.msg);
        assert_non_null(e.format);
        assert_string_equal(e.format, f->name);
        assert_true(e.offset >= 0 || e.member[0]);
        assert_true(e.offset <= (long)len);
        assert_true(e.msg[0]);
        map_release(&m);
        free(cut);
    }
    /* every byte inverted: no crash; what reads is consistent */
    unsigned char *buf = malloc(w->n);
    for (size_t at = 0; at < w->n; at++) {
        memcpy(buf, w->p, w->n);
        buf[at] ^= 0xff;
        ljgap__files_map m;
        ljgap__files_err e;
        int rc = f->read(buf, w->n, NULL, &m, &e);
        if (rc == 0) {
            size_t nan = 0;
            for (size_t k = 0; k < m.nx * m.ny; k++)
                nan += isnan(m.z[k]), assert_false(isinf(m.z[k]));
            assert_int_equal(nan, m.missing);
            assert_true(isfinite(m.size_x) && isfinite(m.size_y));
        } else {
            assert_true(rc >= LJGAP_FILES_UNKNOWN && rc <= LJGAP_FILES_TOOBIG);
            assert_true(e.msg[0]);
        }
        map_release(&m);
    }
    free(buf);
}

static int read_ok(const ljgap__files_format *f, const wbuf *w, const char *channel,
                   ljgap__files_map *m)
{
    ljgap__files_err e;
    memset(&e, 0, sizeof e);
    int rc = f->read(w->p, w->n, channel, m, &e);
    if (rc) print_error("%s: %d at %ld [%s]: %s\n", f->name, rc, e.offset, e.member, e.msg);
    return rc;
}

static int read_err(const ljgap__files_format *f, const wbuf *w, const char *channel,
                    ljgap__files_err *e)
{
    ljgap__files_map m;
    memset(e, 0, sizeof *e);
    int rc = f->read(w->p, w->n, channel, &m, e);
    map_release(&m);
    return rc;
}

/* ---- Digital Surf ---- */

typedef struct {
    int bits, nx, ny, holes, compressed;
    float dx, dy, dz, zoff;
    const char *ux, *uz, *name;
    size_t comment, priv;
} sur_spec;

/* One object: header, zones, points; vals receives the stored values (-> zmin - 2 = hole). */
static void sur_object(wbuf *w, const sur_spec *s, int nobj, int32_t *vals)
{
    size_t at = w->n, n = (size_t)s->nx * s->ny;
    int32_t lim = s->bits == 16 ? 30000 : 3000000, zmin = INT32_MAX;
    for (size_t k = 0; k < n; k++)
        vals[k] = rnd(lim), zmin = vals[k] < zmin ? vals[k] : zmin;
    if (s->holes)
        for (size_t k = 3; k < n; k += 17)
            vals[k] = zmin - 2;
    zeros(w, 512);
    poketext(w, at, s->compressed ? "DSCOMPRESSED" : "DIGITAL SURF");
    poke(w, at + 14, (uint64_t)nobj, 2, 0);
    poke(w, at + 16, 1, 2, 0), poke(w, at + 18, 2, 2, 0);
    poketext(w, at + 20, s->name);
    poke(w, at + 82, 9, 2, 0); /* interferometer */
    poke(w, at + 86, s->holes ? 1 : 0, 2, 0);
    poke(w, at + 98, (uint64_t)s->bits, 2, 0);
    poke(w, at + 100, (uint32_t)zmin, 4, 0), poke(w, at + 104, (uint32_t)lim, 4, 0);
    poke(w, at + 108, (uint64_t)s->nx, 4, 0), poke(w, at + 112, (uint64_t)s->ny, 4, 0);
    poke(w, at + 116, n, 4, 0);
    pokef32(w, at + 120, s->dx, 0), pokef32(w, at + 124, s->dy, 0), pokef32(w, at + 128, s->dz, 0);
    poketext(w, at + 180, s->ux), poketext(w, at + 196, s->ux), poketext(w, at + 212, s->uz);
    unsigned date[7] = {9, 8, 7, 6, 5, 2023, 2};
    for (int i = 0; i < 7; i++)
        poke(w, at + 306 + 2 * (size_t)i, date[i], 2, 0);
    poke(w, at + 334, s->comment, 2, 0), poke(w, at + 336, s->priv, 2, 0);
    pokef32(w, at + 474, s->zoff, 0);
    for (size_t i = 0; i < s->comment + s->priv; i++)
        putu(w, 'c', 1, 0);
    wbuf raw = {0};
    for (size_t k = 0; k < n; k++)
        putu(&raw, (uint32_t)vals[k], (size_t)s->bits / 8, 0);
    if (!s->compressed) {
        put(w, raw.p, raw.n);
    } else {
        uLongf zl = compressBound(raw.n);
        unsigned char *z = malloc(zl);
        assert_int_equal(compress(z, &zl, raw.p, raw.n), Z_OK);
        putu(w, 1, 4, 0), putu(w, raw.n, 4, 0), putu(w, zl, 4, 0);
        put(w, z, zl);
        poke(w, at + 324, 12 + zl, 4, 0);
        free(z);
    }
    free(raw.p);
}

static void check_sur(const sur_spec *s, double fx, double fz)
{
    wbuf w = {0};
    int32_t *vals = malloc(sizeof *vals * (size_t)s->nx * s->ny);
    sur_object(&w, s, 1, vals);
    assert_true(ljgap__files_sur.probe(w.p, w.n));
    ljgap__files_map m;
    assert_int_equal(read_ok(&ljgap__files_sur, &w, NULL, &m), 0);
    assert_string_equal(m.format, "sur");
    assert_int_equal(m.nx, s->nx), assert_int_equal(m.ny, s->ny);
    assert_close(m.size_x, (double)s->dx * fx * s->nx, 1e-15 * m.size_x);
    assert_close(m.size_y, (double)s->dy * fx * s->ny, 1e-15 * m.size_y);
    size_t miss = 0;
    for (size_t k = 0; k < m.nx * m.ny; k++) {
        if (s->holes && k >= 3 && (k - 3) % 17 == 0) {
            assert_true(isnan(m.z[k]));
            miss++;
        } else {
            double want = ((double)vals[k] * s->dz + s->zoff) * fz;
            assert_close(m.z[k], want, 1e-15 * fabs(want));
        }
    }
    assert_int_equal(m.missing, miss);
    assert_string_equal(m.z_unit, strcmp(s->uz, "\xb5m") ? s->uz : "\xc2\xb5m");
    assert_string_equal(m.acquired, "2023-05-06T07:08:09");
    assert_string_equal(m.instrument, "interferometer");
    assert_string_equal(m.channel, s->name);
    map_release(&m);
    sweep(&ljgap__files_sur, &w);
    free(vals), free(w.p);
}

static void test_sur(void **state)
{
    sur_spec a = {16, 13, 9, 0, 0, 0.5f, 0.25f, 2.0f, 0, "\xb5m", "nm", "surface a", 0, 0};
    check_sur(&a, 1e-6, 1e-9);
    sur_spec b = {32, 11, 12, 1, 0, 10, 20, 0.001f, 3.5f, "nm", "\xb5m", "b", 9, 5};
    check_sur(&b, 1e-9, 1e-6);
    sur_spec c = {32, 15, 6, 1, 1, 0.1f, 0.1f, 1e-3f, 0, "mm", "um", "compressed", 0, 0};
    check_sur(&c, 1e-3, 1e-6);
    sur_spec d = {16, 16, 4, 0, 1, 1, 1, 1, 0, "m", "m", "c16", 3, 0};
    check_sur(&d, 1, 1);
}

static void test_sur_objects_and_errors(void **state)
{
    sur_spec a = {16, 5, 4, 0, 0, 1, 1, 1, 0, "um", "nm", "first", 0, 0};
    sur_spec b = {32, 3, 7, 0, 0, 2, 2, 1, 0, "um", "um", "second", 0, 0};
    int32_t va[20], vb[21];
    wbuf w = {0};
    sur_object(&w, &a, 2, va);
    sur_object(&w, &b, 2, vb);
    ljgap__files_map m;
    assert_int_equal(read_ok(&ljgap__files_sur, &w, "second", &m), 0);
    assert_int_equal(m.n_channels, 2);
    assert_string_equal(m.channels[0], "first");
    assert_int_equal(m.channel_index, 1);
    assert_int_equal(m.nx, 3), assert_int_equal(m.ny, 7);
    assert_close(m.z[6], vb[6] * 1e-6, 1e-20);
    map_release(&m);
    assert_int_equal(read_ok(&ljgap__files_sur, &w, "0", &m), 0);
    assert_int_equal(m.nx, 5);
    assert_close(m.z[6], va[6] * 1e-9, 1e-24);
    map_release(&m);
    ljgap__files_err e;
    assert_int_equal(read_err(&ljgap__files_sur, &w, "third", &e), LJGAP_FILES_CHANNEL);
    assert_int_equal(read_err(&ljgap__files_sur, &w, "2", &e), LJGAP_FILES_CHANNEL);
    /* inversion (290): 1 negates z, 2 also mirrors x, 3 also mirrors y */
    for (unsigned inv = 1; inv <= 3; inv++) {
        poke(&w, 290, inv, 2, 0);
        assert_int_equal(read_ok(&ljgap__files_sur, &w, NULL, &m), 0);
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 5; i++) {
                int si = inv == 2 ? 4 - i : i, sj = inv == 3 ? 3 - j : j;
                assert_close(m.z[j * 5 + i], -va[sj * 5 + si] * 1e-9, 1e-24);
            }
        map_release(&m);
    }
    poke(&w, 98, 8, 2, 0); /* 8 bits a point */
    assert_int_equal(read_err(&ljgap__files_sur, &w, NULL, &e), LJGAP_FILES_BAD);
    assert_int_equal(e.offset, 98);
    poke(&w, 98, 16, 2, 0);
    poke(&w, 116, 21, 4, 0); /* total points != nx * ny */
    assert_int_equal(read_err(&ljgap__files_sur, &w, NULL, &e), LJGAP_FILES_BAD);
    assert_int_equal(e.offset, 116);
    free(w.p);
}

/* ---- MetroPro ---- */

static void mp_file(wbuf *w, int fmt, int nx, int ny, int res, int buckets, int sign,
                    int32_t *phase, uint16_t *inten)
{
    size_t hs = fmt == 3 ? 4096 : 834, n = (size_t)nx * ny;
    zeros(w, hs);
    poke(w, 0, fmt == 1 ? 0x881B036F : fmt == 2 ? 0x881B0370 : 0x881B0371, 4, 1);
    poke(w, 4, (uint64_t)fmt, 2, 1), poke(w, 6, hs, 4, 1);
    if (buckets) poke(w, 52, (uint64_t)nx, 2, 1), poke(w, 54, (uint64_t)ny, 2, 1);
    poke(w, 56, (uint64_t)buckets, 2, 1), poke(w, 60, 2 * n * (size_t)buckets, 4, 1);
    poke(w, 68, (uint64_t)nx, 2, 1), poke(w, 70, (uint64_t)ny, 2, 1), poke(w, 72, 4 * n, 4, 1);
    poke(w, 76, 1700000000, 4, 1);
    pokef32(w, 164, 0.5f, 1), pokef32(w, 168, 632.8e-9f, 1), pokef32(w, 176, 1.25f, 1);
    pokef32(w, 184, 2.5e-7f, 1);
    poke(w, 218, (uint64_t)res, 2, 1), poke(w, 232, (uint64_t)sign, 2, 1);
    poke(w, 238, 5, 2, 1), poke(w, 242, 77, 2, 1);
    for (size_t k = 0; k < n * (size_t)buckets; k++) {
        inten[k] = (uint16_t)(rnd(30000) + 30000);
        if (k == 4) inten[k] = 65500;
        putu(w, inten[k], 2, 1);
    }
    for (size_t k = 0; k < n; k++) {
        phase[k] = k % 13 == 5 ? 2147483647 : rnd(300000);
        putu(w, (uint32_t)phase[k], 4, 1);
    }
}

static void check_mp(int fmt, int res, int buckets, int sign)
{
    int nx = 9, ny = 7;
    int32_t phase[63];
    uint16_t inten[63];
    wbuf w = {0};
    mp_file(&w, fmt, nx, ny, res, buckets, sign, phase, inten);
    assert_true(ljgap__files_metropro.probe(w.p, w.n));
    ljgap__files_map m;
    assert_int_equal(read_ok(&ljgap__files_metropro, &w, NULL, &m), 0);
    double R = res == 0 ? 4096 : res == 1 ? 32768 : 131072;
    double q = (double)0.5f * (double)1.25f * (double)632.8e-9f / R * (sign ? -1 : 1);
    size_t miss = 0;
    for (size_t k = 0; k < 63; k++)
        if (phase[k] >= 2147483640)
            assert_true(isnan(m.z[k])), miss++;
        else
            assert_close(m.z[k], q * phase[k], 1e-15 * fabs(q * phase[k]));
    assert_int_equal(m.missing, miss);
    assert_close(m.size_x, (double)2.5e-7f * nx, 1e-22);
    assert_close(m.size_y, (double)2.5e-7f * ny, 1e-22);
    assert_string_equal(m.acquired, "2023-11-14T22:13:20Z");
    assert_string_equal(m.instrument, "Zygo NewView, serial 77");
    assert_string_equal(m.z_unit, "m");
    assert_int_equal(m.n_channels, 1 + buckets);
    map_release(&m);
    if (buckets) {
        assert_int_equal(read_ok(&ljgap__files_metropro, &w, "Intensity", &m), 0);
        for (size_t k = 0; k < 63; k++)
            if (inten[k] >= 65412)
                assert_true(isnan(m.z[k]));
            else
                assert_true(m.z[k] == inten[k]);
        assert_int_equal(m.missing, 1);
        map_release(&m);
    }
    if (fmt != 3) sweep(&ljgap__files_metropro, &w); /* format 3: the same code, 4 KiB longer */
    free(w.p);
}

static void test_metropro(void **state)
{
    check_mp(1, 0, 0, 0);
    check_mp(2, 1, 1, 1);
    check_mp(3, 2, 1, 0);
    int32_t phase[4];
    uint16_t inten[4];
    wbuf w = {0};
    mp_file(&w, 2, 2, 2, 3, 0, 0, phase, inten);
    ljgap__files_err e;
    assert_int_equal(read_err(&ljgap__files_metropro, &w, NULL, &e), LJGAP_FILES_BAD);
    assert_int_equal(e.offset, 218); /* phase resolution 3 */
    assert_int_equal(read_err(&ljgap__files_metropro, &w, "Intensity", &e), LJGAP_FILES_CHANNEL);
    poke(&w, 6, 4096, 4, 1); /* format 2 with a 4096-byte header */
    assert_int_equal(read_err(&ljgap__files_metropro, &w, NULL, &e), LJGAP_FILES_BAD);
    assert_int_equal(e.offset, 4);
    free(w.p);
}

/* ---- X3P ---- */

typedef struct {
    const char *name;          /* member path */
    const unsigned char *data; /* its bytes */
    size_t n;                  /* their count */
    int deflate;               /* stored or deflated */
} member;

static void zip_write(wbuf *w, const member *mem, int count)
{
    wbuf cd = {0};
    for (int i = 0; i < count; i++) {
        uint32_t crc = (uint32_t)crc32(0, mem[i].data, (uInt)mem[i].n);
        unsigned char *z = NULL;
        size_t zl = mem[i].n;
        if (mem[i].deflate) {
            z_stream zs;
            memset(&zs, 0, sizeof zs);
            assert_int_equal(deflateInit2(&zs, 9, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY), Z_OK);
            zl = deflateBound(&zs, mem[i].n);
            z = malloc(zl);
            zs.next_in = (unsigned char *)mem[i].data, zs.avail_in = (uInt)mem[i].n;
            zs.next_out = z, zs.avail_out = (uInt)zl;
            assert_int_equal(deflate(&zs, Z_FINISH), Z_STREAM_END);
            zl = zs.total_out;
            deflateEnd(&zs);
        }
        size_t local = w->n, nl = strlen(mem[i].name);
        unsigned method = mem[i].deflate ? 8 : 0;
        putu(w, 0x04034b50, 4, 0), putu(w, 20, 2, 0), putu(w, 0, 2, 0), putu(w, method, 2, 0);
        putu(w, 0, 4, 0), putu(w, crc, 4, 0), putu(w, zl, 4, 0), putu(w, mem[i].n, 4, 0);
        putu(w, nl, 2, 0), putu(w, 0, 2, 0), put(w, mem[i].name, nl);
        put(w, z ? z : mem[i].data, zl);
        putu(&cd, 0x02014b50, 4, 0), putu(&cd, 20, 2, 0), putu(&cd, 20, 2, 0);
        putu(&cd, 0, 2, 0), putu(&cd, method, 2, 0), putu(&cd, 0, 4, 0), putu(&cd, crc, 4, 0);
        putu(&cd, zl, 4, 0), putu(&cd, mem[i].n, 4, 0), putu(&cd, nl, 2, 0);
        zeros(&cd, 8), putu(&cd, 0, 4, 0), putu(&cd, local, 4, 0), put(&cd, mem[i].name, nl);
        free(z);
    }
    size_t cdoff = w->n;
    put(w, cd.p, cd.n);
    putu(w, 0x06054b50, 4, 0), putu(w, 0, 4, 0), putu(w, (uint64_t)count, 2, 0);
    putu(w, (uint64_t)count, 2, 0), putu(w, cd.n, 4, 0), putu(w, cdoff, 4, 0), putu(w, 0, 2, 0);
    free(cd.p);
}

/* main.xml for a grid; link: a DataLink element or a DataList */
static char *x3p_xml(const char *feature, char type, int nx, int ny, int layers, double zinc,
                     double zoff, const char *data)
{
    char *x = malloc(8192 + strlen(data));
    sprintf(x,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<p:ISO5436_2 "
            "xmlns:p=\"http://www.opengps.eu/2008/ISO5436_2\">\n<Record1><Revision>ISO5436 - "
            "2000</Revision><FeatureType>%s</FeatureType><Axes>"
            "<CX><AxisType>I</AxisType><DataType>D</DataType><Increment>1.25e-7</Increment>"
            "<Offset>0</Offset></CX><CY><AxisType>I</AxisType><DataType>D</DataType>"
            "<Increment>2.5E-07</Increment><Offset>0</Offset></CY><CZ><AxisType>A</AxisType>"
            "<DataType>%c</DataType><Increment>%.17g</Increment><Offset>%.17g</Offset></CZ>"
            "</Axes></Record1>\n<Record2><Date>2021-06-07T08:09:10+02:00</Date><Instrument>"
            "<Manufacturer>Zeiss &amp; Co</Manufacturer><Model>M1</Model></Instrument>"
            "</Record2>\n<Record3><MatrixDimension><SizeX>%d</SizeX><SizeY>%d</SizeY>"
            "<SizeZ>%d</SizeZ></MatrixDimension>%s</Record3></p:ISO5436_2>\n",
            feature, type, zinc, zoff, nx, ny, layers, data);
    return x;
}

static void test_x3p(void **state)
{
    enum { NX = 7, NY = 5, N = NX * NY };
    /* float64 with NaN holes, stored */
    double d[2 * N];
    wbuf bin = {0};
    for (int k = 0; k < 2 * N; k++) {
        d[k] = k % 11 == 4 ? NAN : rnd(100000) * 1e-12;
        putf64(&bin, d[k], 0);
    }
    char *xml = x3p_xml("SUR", 'D', NX, NY, 2, 1, 0,
                        "<DataLink><PointDataLink>bindata/data.bin</PointDataLink></DataLink>");
    member mem[3] = {{"main.xml", (unsigned char *)xml, strlen(xml), 0},
                     {"bindata/data.bin", bin.p, bin.n, 0},
                     {"md5checksum.hex", (const unsigned char *)"x\n", 2, 0}};
    wbuf w = {0};
    zip_write(&w, mem, 3);
    assert_true(ljgap__files_x3p.probe(w.p, w.n));
    ljgap__files_map m;
    assert_int_equal(read_ok(&ljgap__files_x3p, &w, NULL, &m), 0);
    assert_int_equal(m.nx, NX), assert_int_equal(m.ny, NY);
    assert_close(m.size_x, 1.25e-7 * NX, 1e-22);
    assert_close(m.size_y, 2.5e-7 * NY, 1e-22);
    size_t miss = 0;
    for (int k = 0; k < N; k++)
        if (isnan(d[k]))
            assert_true(isnan(m.z[k])), miss++;
        else
            assert_true(m.z[k] == d[k]);
    assert_int_equal(m.missing, miss);
    assert_string_equal(m.instrument, "Zeiss & Co M1");
    assert_string_equal(m.acquired, "2021-06-07T08:09:10+02:00");
    assert_int_equal(m.n_channels, 2);
    map_release(&m);
    assert_int_equal(read_ok(&ljgap__files_x3p, &w, "1", &m), 0); /* the second layer */
    for (int k = 0; k < N; k++)
        assert_true(isnan(d[N + k]) ? isnan(m.z[k]) : m.z[k] == d[N + k]);
    map_release(&m);
    sweep(&ljgap__files_x3p, &w);
    ljgap__files_err e;
    w.p[30 + 8 + strlen(xml) + 30 + 16 + 5] ^= 1; /* in data.bin: its CRC no longer matches */
    int rc = read_err(&ljgap__files_x3p, &w, NULL, &e);
    assert_int_equal(rc, LJGAP_FILES_BAD);
    assert_string_equal(e.member, "bindata/data.bin");
    assert_non_null(strstr(e.msg, "CRC"));
    free(w.p), free(xml);
    w = (wbuf){0};

    /* int16 with valid bits, deflated; z = offset + increment * value */
    int16_t v[N];
    unsigned char valid[(N + 7) / 8] = {0};
    bin.n = 0;
    for (int k = 0; k < N; k++) {
        v[k] = (int16_t)rnd(3000);
        putu(&bin, (uint16_t)v[k], 2, 0);
        if (k % 6) valid[k / 8] |= (unsigned char)(1u << (k % 8));
    }
    xml = x3p_xml("SUR", 'I', NX, NY, 1, 1e-9, 2e-8,
                  "<DataLink><PointDataLink>bindata/data.bin</PointDataLink><ValidPointsLink>"
                  "bindata/valid.bin</ValidPointsLink></DataLink>");
    member mem2[3] = {{"main.xml", (unsigned char *)xml, strlen(xml), 1},
                      {"bindata/data.bin", bin.p, bin.n, 1},
                      {"bindata/valid.bin", valid, sizeof valid, 0}};
    zip_write(&w, mem2, 3);
    assert_int_equal(read_ok(&ljgap__files_x3p, &w, NULL, &m), 0);
    for (int k = 0; k < N; k++)
        if (k % 6 == 0)
            assert_true(isnan(m.z[k]));
        else
            assert_close(m.z[k], 2e-8 + 1e-9 * v[k], 1e-22);
    assert_int_equal(m.missing, (N + 5) / 6);
    map_release(&m);
    sweep(&ljgap__files_x3p, &w);
    /* no main.xml: the member is named */
    mem2[0].name = "other.xml";
    w.n = 0;
    zip_write(&w, mem2, 3);
    assert_int_equal(read_err(&ljgap__files_x3p, &w, NULL, &e), LJGAP_FILES_BAD);
    assert_string_equal(e.member, "main.xml");
    free(w.p), free(xml), free(bin.p);
}

static void test_x3p_profile_list_toobig(void **state)
{
    /* a profile with inline values (an empty Datum is a missing point) */
    char *xml = x3p_xml("PRF", 'D', 4, 1, 1, 1, 0,
                        "<DataList><Datum>1e-9</Datum><Datum/><Datum> -2.5e-9 </Datum>"
                        "<Datum>4E-9</Datum></DataList>");
    member mem[1] = {{"main.xml", (unsigned char *)xml, strlen(xml), 0}};
    wbuf w = {0};
    zip_write(&w, mem, 1);
    ljgap__files_map m;
    assert_int_equal(read_ok(&ljgap__files_x3p, &w, NULL, &m), 0);
    assert_int_equal(m.nx, 4), assert_int_equal(m.ny, 1);
    assert_true(m.z[0] == 1e-9 && isnan(m.z[1]) && m.z[2] == -2.5e-9 && m.z[3] == 4e-9);
    assert_int_equal(m.missing, 1);
    assert_close(m.size_x, 5e-7, 1e-22);
    map_release(&m);
    sweep(&ljgap__files_x3p, &w);
    free(xml);
    /* 5000 x 5000 points: over the limit */
    xml = x3p_xml("SUR", 'D', 5000, 5000, 1, 1, 0,
                  "<DataLink><PointDataLink>bindata/data.bin</PointDataLink></DataLink>");
    member big[1] = {{"main.xml", (unsigned char *)xml, strlen(xml), 0}};
    w.n = 0;
    zip_write(&w, big, 1);
    ljgap__files_err e;
    assert_int_equal(read_err(&ljgap__files_x3p, &w, NULL, &e), LJGAP_FILES_TOOBIG);
    free(xml);
    /* a deflated member far larger than the grid needs (a zip bomb) is not inflated */
    xml = x3p_xml("SUR", 'D', 2, 2, 1, 1, 0,
                  "<DataLink><PointDataLink>bindata/data.bin</PointDataLink></DataLink>");
    unsigned char *zeros_ = calloc(100000, 1);
    member bomb[2] = {{"main.xml", (unsigned char *)xml, strlen(xml), 0},
                      {"bindata/data.bin", zeros_, 100000, 1}};
    w.n = 0;
    zip_write(&w, bomb, 2);
    assert_true(w.n < 2000);
    assert_int_equal(read_err(&ljgap__files_x3p, &w, NULL, &e), LJGAP_FILES_TOOBIG);
    assert_string_equal(e.member, "bindata/data.bin");
    free(zeros_), free(xml), free(w.p);
}

/* ---- netCDF (classic) ---- */

static void nc_name(wbuf *w, const char *s)
{
    size_t n = strlen(s);
    putu(w, n, 4, 1), put(w, s, n), zeros(w, (4 - n % 4) % 4);
}

static void nc_att_text(wbuf *w, const char *name, const char *text)
{
    nc_name(w, name), putu(w, 2, 4, 1);
    nc_name(w, text);
}

static void nc_att_double(wbuf *w, const char *name, double v)
{
    nc_name(w, name), putu(w, 6, 4, 1), putu(w, 1, 4, 1), putf64(w, v, 1);
}

/* heights (dims d0, d1: "x","y" or "y","x"; ny = 0 a profile), x, y (length in um), an
 * optional mask; version 1 or 2; h[i * ny + j] at x index i, y index j */
static void nc_file(wbuf *w, int version, int nx, int ny, int yx, const double *h,
                    const signed char *mask, int periodic)
{
    int prof = ny == 0, nv = 2 + !prof + (mask != NULL);
    size_t n = (size_t)nx * (prof ? 1 : ny), osz = version == 1 ? 4 : 8;
    put(w, "CDF", 3), putu(w, (uint64_t)version, 1, 0), putu(w, 0, 4, 1);
    putu(w, 10, 4, 1), putu(w, prof ? 1 : 2, 4, 1);
    nc_name(w, "x"), putu(w, (uint64_t)nx, 4, 1);
    if (!prof) nc_name(w, "y"), putu(w, (uint64_t)ny, 4, 1);
    putu(w, 12, 4, 1), putu(w, 1, 4, 1);
    nc_att_text(w, "json",
                "{\"acquisition_time\": \"2020-01-02T03:04:05\", \"instrument\": "
                "{\"name\": \"AFM \\\"X\", \"parameters\": {\"tip_radius\": "
                "{\"value\": 20.0, \"unit\": \"nm\"}}}}");
    putu(w, 11, 4, 1), putu(w, (uint64_t)nv, 4, 1);
    size_t begins[4];
    const char *names[4] = {"heights", "x", "y", "mask"};
    for (int v = 0; v < 4; v++) {
        if ((v == 2 && prof) || (v == 3 && !mask)) continue;
        nc_name(w, names[v]);
        int nd = v == 1 || v == 2 ? 1 : prof ? 1 : 2;
        putu(w, (uint64_t)nd, 4, 1);
        if (v == 2)
            putu(w, 1, 4, 1);
        else if (v == 1 || prof)
            putu(w, 0, 4, 1);
        else
            putu(w, yx ? 1 : 0, 4, 1), putu(w, yx ? 0 : 1, 4, 1);
        if (v == 0) {
            putu(w, 12, 4, 1), putu(w, 2, 4, 1);
            nc_att_text(w, "unit", "um");
            nc_att_double(w, "_FillValue", -9999.0);
        } else if (v == 1 || v == 2) {
            putu(w, 12, 4, 1), putu(w, 3, 4, 1);
            nc_att_double(w, "length", v == 1 ? 12.5 : 7.5);
            nc_att_double(w, "periodic", periodic);
            nc_att_text(w, "unit", "um");
        } else {
            putu(w, 0, 4, 1), putu(w, 0, 4, 1);
        }
        putu(w, v == 3 ? 1 : 6, 4, 1), putu(w, 0, 4, 1); /* type, vsize (unused) */
        begins[v] = w->n;
        putu(w, 0, osz, 1);
    }
    size_t at = w->n;
    poke(w, begins[0], at, osz, 1);
    for (size_t k = 0; k < n; k++) {
        size_t i = k / (prof ? 1 : ny), j = k % (prof ? 1 : ny); /* file order (x, y) */
        if (yx) j = k / nx, i = k % nx;                          /* file order (y, x) */
        putf64(w, h[i * (prof ? 1 : ny) + j], 1);
    }
    poke(w, begins[1], w->n, osz, 1);
    for (int i = 0; i < nx; i++)
        putf64(w, i * 12.5 / nx, 1);
    if (!prof) {
        poke(w, begins[2], w->n, osz, 1);
        for (int j = 0; j < ny; j++)
            putf64(w, j * 7.5 / ny, 1);
    }
    if (mask) {
        poke(w, begins[3], w->n, osz, 1);
        for (size_t k = 0; k < n; k++) { /* in the file's order, as the heights */
            size_t i = k / (prof ? 1 : ny), j = k % (prof ? 1 : ny);
            if (yx) j = k / nx, i = k % nx;
            putu(w, (uint8_t)mask[i * (prof ? 1 : ny) + j], 1, 0);
        } /* no padding after the last variable: a cut inside it would lose no data */
    }
}

static void check_nc(int version, int nx, int ny, int yx, int with_mask, int periodic)
{
    int prof = ny == 0, rows = prof ? 1 : ny;
    double h[64];
    signed char mask[64] = {0};
    for (int k = 0; k < nx * rows; k++)
        h[k] = rnd(100000) * 1e-5;
    h[3] = -9999.0; /* the fill value */
    h[5] = NAN;
    if (with_mask) mask[7] = 1, mask[8] = 1;
    wbuf w = {0};
    nc_file(&w, version, nx, ny, yx, h, with_mask ? mask : NULL, periodic);
    assert_true(ljgap__files_netcdf.probe(w.p, w.n));
    ljgap__files_map m;
    assert_int_equal(read_ok(&ljgap__files_netcdf, &w, NULL, &m), 0);
    assert_int_equal(m.nx, nx), assert_int_equal(m.ny, rows);
    size_t miss = 0;
    for (int j = 0; j < rows; j++)
        for (int i = 0; i < nx; i++) {
            int k = i * rows + j; /* h's index: x i, y j */
            if (k == 3 || k == 5 || (with_mask && (k == 7 || k == 8)))
                assert_true(isnan(m.z[j * nx + i])), miss++;
            else
                assert_close(m.z[j * nx + i], h[k] * 1e-6, 1e-15 * fabs(h[k] * 1e-6));
        }
    assert_int_equal(m.missing, miss);
    assert_close(m.size_x, 12.5e-6, 1e-20);
    assert_close(m.size_y, prof ? 12.5e-6 / nx : 7.5e-6, 1e-20);
    assert_int_equal(m.periodic, periodic);
    assert_string_equal(m.z_unit, "um");
    assert_string_equal(m.acquired, "2020-01-02T03:04:05");
    assert_string_equal(m.instrument, "AFM \"X");
    assert_close(m.tip_radius, 20e-9, 1e-22);
    map_release(&m);
    sweep(&ljgap__files_netcdf, &w);
    free(w.p);
}

static void test_netcdf(void **state)
{
    check_nc(1, 6, 5, 0, 0, 1);
    check_nc(2, 6, 5, 1, 1, 0);
    check_nc(2, 9, 0, 0, 1, 0);
    ljgap__files_err e;
    wbuf w = {0};
    put(&w, "\x89HDF\r\n\x1a\n", 8), zeros(&w, 64);
    assert_true(ljgap__files_netcdf.probe(w.p, w.n));
    assert_int_equal(read_err(&ljgap__files_netcdf, &w, NULL, &e), LJGAP_FILES_BAD);
    assert_non_null(strstr(e.msg, "NETCDF3"));
    free(w.p);
    w = (wbuf){0};
    double h[30] = {0};
    nc_file(&w, 1, 6, 5, 0, h, NULL, 0);
    assert_int_equal(read_err(&ljgap__files_netcdf, &w, "elevation", &e), LJGAP_FILES_CHANNEL);
    memcpy(memmem(w.p, w.n, "heights", 7), "Heights", 7); /* no variable heights */
    assert_int_equal(read_err(&ljgap__files_netcdf, &w, NULL, &e), LJGAP_FILES_BAD);
    assert_non_null(strstr(e.msg, "heights"));
    free(w.p);
}

/* ---- probes ---- */

static void test_probes(void **state)
{
    const ljgap__files_format *f[4] = {&ljgap__files_x3p, &ljgap__files_sur, &ljgap__files_metropro,
                                      &ljgap__files_netcdf};
    wbuf w[4] = {{0}};
    int32_t vals[64];
    uint16_t inten[64];
    char *xml = x3p_xml("SUR", 'D', 1, 1, 1, 1, 0, "<DataList><Datum>1</Datum></DataList>");
    member mem[1] = {{"main.xml", (unsigned char *)xml, strlen(xml), 0}};
    zip_write(&w[0], mem, 1);
    sur_spec s = {16, 4, 4, 0, 0, 1, 1, 1, 0, "um", "um", "s", 0, 0};
    sur_object(&w[1], &s, 1, vals);
    mp_file(&w[2], 1, 4, 4, 0, 0, 0, vals, inten);
    double h[16] = {0};
    nc_file(&w[3], 1, 4, 4, 0, h, NULL, 0);
    for (int a = 0; a < 4; a++) {
        for (int b = 0; b < 4; b++)
            assert_int_equal(f[a]->probe(w[b].p, w[b].n) != 0, a == b);
        assert_false(f[a]->probe(w[a].p, 2));
        assert_false(f[a]->probe((const unsigned char *)"hello world, no magic here", 26));
    }
    for (int a = 0; a < 4; a++)
        free(w[a].p);
    free(xml);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sur),
        cmocka_unit_test(test_sur_objects_and_errors),
        cmocka_unit_test(test_metropro),
        cmocka_unit_test(test_x3p),
        cmocka_unit_test(test_x3p_profile_list_toobig),
        cmocka_unit_test(test_netcdf),
        cmocka_unit_test(test_probes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
