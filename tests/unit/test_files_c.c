/* test_files_c.c -- the readers of Igor binary waves (server/files/ibw.c), Park Systems TIFF
 * (park_tiff.c) and Sensofar PLu (plu.c), linked directly (without the registry of files.c).
 *
 * Each format's files are written here by a small writer that follows the format's
 * documentation (WaveMetrics' IgorBin.h, Park's tags and image header, Sensofar's PLu header),
 * with heights that are exact in the stored type, and read back exactly: every point (rows in
 * the order the format's y axis implies), the size, the unit conversion, the channels and the
 * default (height) channel, a channel by index and by title, an unknown channel, missing points,
 * the metadata (instrument, date, tip radius). Then the failures: every truncation of every file
 * gives LJGAP_FILES_BAD with an offset inside the file and no map (run under ASan/UBSan: no read
 * past the buffer), wrong checksums, types, versions, sizes, TOOBIG; and each probe claims only
 * its own format (a plain TIFF is not Park's); every byte of a small file of each format
 * changed (the Igor checksum repaired, so that the headers' fields are reached): a whole map or
 * an error, never a crash. tests/files/check_c.sh compares the same readers
 * with Gwyddion on files written by tests/files/gen_c.py.
 *
 *   build/tests/test_files_c                         the tests
 *   build/tests/test_files_c --dump FORMAT FILE [CH]  "nx ny size_x size_y z_unit missing
 *                                                     channel" then one height a line (for
 *                                                     check_c.sh)
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "files.h"
#include "files_c_write.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const ljgap__files_format *const readers[] = {&ljgap__files_ibw, &ljgap__files_park_tiff,
                                                    &ljgap__files_plu};

static void map_free(ljgap__files_map *m)
{
    free(m->z);
    m->z = NULL;
}

static const char *const asylum_labels[] = {"AmplitudeRetrace", "HeightRetrace", "PhaseRetrace"};
#define ASYLUM_NOTE                                                                                \
    "ScanSize: 2e-07\rMicroscopeModel: Cypher S\rDate: 2024-05-06\rTime: 1:02:03 PM\r"             \
    "TipRadius: 7e-09\rPhaseUnit: deg\r"

/* An Asylum scan: nl layers (titled as asylum_labels) of nx x ny float32 heights, steps of
 * 10 nm, the units in the note. */
static igor_spec asylum_spec(size_t nx, size_t ny, size_t nl)
{
    return (igor_spec){.type = 2,
                       .nx = nx,
                       .ny = ny,
                       .nl = nl,
                       .dx = 1e-8,
                       .dy = 1e-8,
                       .data_unit = "",
                       .dim_unit = "m",
                       .note = ASYLUM_NOTE,
                       .labels = asylum_labels};
}

/* A one-layer wave of the type, heights and steps in metres, steps of d. */
static igor_spec plain_spec(unsigned type, size_t nx, size_t ny, double d)
{
    return (igor_spec){.type = type,
                       .nx = nx,
                       .ny = ny,
                       .nl = 1,
                       .dx = d,
                       .dy = d,
                       .data_unit = "m",
                       .dim_unit = "m"};
}

/* A Park Systems version 2 file (float32 µm heights, gain 1, one Topography channel). */
static park_spec park_small(size_t xres, size_t yres)
{
    return (park_spec){.version = 2,
                       .dtype = 2,
                       .xres = xres,
                       .yres = yres,
                       .gain = 1,
                       .zscale = 1,
                       .unit = "um",
                       .source = "Topography",
                       .park = 1};
}

/* Makes the 16-bit words of an Igor version 5 file's headers (384 bytes) sum to 0 again. */
static void igor_checksum(unsigned char *p, size_t n)
{
    wbuf c = {.p = p, .n = n, .cap = n};
    unsigned sum = 0;
    put_uint_at(&c, 2, 0, 2);
    for (size_t i = 0; i < 384; i += 2)
        sum += p[i] | (unsigned)p[i + 1] << 8;
    put_uint_at(&c, 2, (0x10000 - (sum & 0xffff)) & 0xffff, 2);
}

/* The reader refuses the bytes with code and leaves no map; its error report. */
static ljgap__files_err refused(const ljgap__files_format *f, const unsigned char *p, size_t n,
                                const char *channel, int code)
{
    ljgap__files_map m;
    ljgap__files_err e;
    assert_int_equal(f->read(p, n, channel, &m, &e), code);
    assert_null(m.z);
    return e;
}

/* A Park map of nx x ny points: gain (raw zscale + zoff) in units of q, stored bottom row
 * first, within tol (0: exactly). */
static void check_park_points(const ljgap__files_map *m, size_t nx, size_t ny, double gain,
                              double zscale, double zoff, double q, double tol)
{
    assert_int_equal(m->nx, nx);
    assert_int_equal(m->ny, ny);
    for (size_t j = 0; j < m->ny; j++)
        for (size_t i = 0; i < m->nx; i++)
            assert_true(fabs(m->z[(m->ny - 1 - j) * m->nx + i] -
                             gain * (park_raw(i, j) * zscale + zoff) * q) <= tol);
}

static void check_igor_points(const ljgap__files_map *m, size_t c, double q)
{
    for (size_t j = 0; j < m->ny; j++)
        for (size_t i = 0; i < m->nx; i++)
            assert_true(m->z[(m->ny - 1 - j) * m->nx + i] == igor_value(i, j, c) * q);
}

static void test_ibw_asylum(void **state)
{
    (void)state;
    igor_spec s = asylum_spec(24, 16, 3);
    s.dy = 2e-8;
    wbuf b = igor5(&s);
    ljgap__files_map m;
    ljgap__files_err e;
    assert_true(ljgap__files_ibw.probe(b.p, b.n));
    assert_int_equal(ljgap__files_ibw.read(b.p, b.n, NULL, &m, &e), 0);
    assert_string_equal(m.format, "ibw");
    assert_int_equal(m.n_channels, 3);
    assert_string_equal(m.channels[0], "AmplitudeRetrace");
    assert_string_equal(m.channels[2], "PhaseRetrace");
    assert_int_equal(m.channel_index, 1); /* the height channel by default */
    assert_string_equal(m.channel, "HeightRetrace");
    assert_int_equal(m.nx, 24);
    assert_int_equal(m.ny, 16);
    assert_true(fabs(m.size_x - 24e-8) < 1e-20 && fabs(m.size_y - 32e-8) < 1e-20);
    assert_string_equal(m.z_unit, "m");
    check_igor_points(&m, 1, 1.0);
    assert_int_equal(m.missing, 0);
    assert_string_equal(m.instrument, "Asylum Research Cypher S");
    assert_string_equal(m.acquired, "2024-05-06T13:02:03");
    assert_true(m.tip_radius == 7e-9);
    map_free(&m);
    /* by index and by title; Phase keeps its own unit, unconverted */
    assert_int_equal(ljgap__files_ibw.read(b.p, b.n, "2", &m, &e), 0);
    assert_string_equal(m.channel, "PhaseRetrace");
    assert_string_equal(m.z_unit, "deg");
    check_igor_points(&m, 2, 1.0);
    map_free(&m);
    assert_int_equal(ljgap__files_ibw.read(b.p, b.n, "amplituderetrace", &m, &e), 0);
    assert_int_equal(m.channel_index, 0);
    check_igor_points(&m, 0, 1.0);
    map_free(&m);
    refused(&ljgap__files_ibw, b.p, b.n, "3", LJGAP_FILES_CHANNEL);
    e = refused(&ljgap__files_ibw, b.p, b.n, "Friction", LJGAP_FILES_CHANNEL);
    assert_non_null(strstr(e.msg, "Friction"));
    free(b.p);
}

/* An integer as Igor's type stores it (wrapped modulo its width, as the writer truncates). */
static double as_stored(double v, unsigned type)
{
    int64_t k = (int64_t)v;
    switch (type) {
    case 0x08:
        return (int8_t)k;
    case 0x48:
        return (uint8_t)k;
    case 0x10:
        return (int16_t)k;
    case 0x50:
        return (uint16_t)k;
    case 0x20:
        return (int32_t)k;
    default:
        return (uint32_t)k;
    }
}

static void test_ibw_types(void **state)
{
    (void)state;
    ljgap__files_map m;
    ljgap__files_err e;
    /* big endian doubles, a 2-D wave (one channel, titled by the wave's name), nm heights
     * given as extended units, µm steps */
    igor_spec s = {.be = 1,
                   .type = 4,
                   .nx = 7,
                   .ny = 5,
                   .dx = 0.5,
                   .dy = 0.25,
                   .data_unit = "",
                   .dim_unit = "um",
                   .data_eunits = "nm"};
    wbuf b = igor5(&s);
    assert_true(ljgap__files_ibw.probe(b.p, b.n));
    assert_int_equal(ljgap__files_ibw.read(b.p, b.n, NULL, &m, &e), 0);
    assert_int_equal(m.n_channels, 1);
    assert_string_equal(m.channel, "wave0");
    assert_string_equal(m.z_unit, "nm");
    assert_true(fabs(m.size_x - 3.5e-6) < 1e-18 && fabs(m.size_y - 1.25e-6) < 1e-18);
    check_igor_points(&m, 0, 1e-9);
    assert_string_equal(m.acquired, "2024-01-01T00:00:00"); /* the creation date */
    assert_string_equal(m.instrument, "");
    map_free(&m);
    free(b.p);
    /* Latin-1 texts (older Igor) come out as UTF-8: a µm step unit, a title with an umlaut */
    static const char *const latin1[] = {"H\xf6he"};
    igor_spec sl = {.type = 2,
                    .nx = 4,
                    .ny = 3,
                    .nl = 1,
                    .dx = 2,
                    .dy = 2,
                    .data_unit = "nm",
                    .dim_unit = "\xb5m",
                    .labels = latin1};
    b = igor5(&sl);
    assert_int_equal(ljgap__files_ibw.read(b.p, b.n, "h\xc3\xb6he", &m, &e), 0);
    assert_string_equal(m.channel, "H\xc3\xb6he");
    assert_true(fabs(m.size_x - 8e-6) < 1e-18);
    map_free(&m);
    free(b.p);
    /* every integer type, both byte orders */
    static const unsigned types[] = {0x08, 0x48, 0x10, 0x50, 0x20, 0x60};
    for (int be = 0; be < 2; be++)
        for (size_t t = 0; t < sizeof types / sizeof types[0]; t++) {
            igor_spec si = plain_spec(types[t], 6, 4, 1e-9);
            si.be = be;
            wbuf bi = igor5(&si);
            assert_int_equal(ljgap__files_ibw.read(bi.p, bi.n, NULL, &m, &e), 0);
            for (size_t j = 0; j < m.ny; j++)
                for (size_t i = 0; i < m.nx; i++)
                    assert_true(m.z[(m.ny - 1 - j) * m.nx + i] ==
                                as_stored(igor_value(i, j, 0), types[t]));
            map_free(&m);
            free(bi.p);
        }
}

static void test_ibw_nan_and_v2(void **state)
{
    (void)state;
    ljgap__files_map m;
    ljgap__files_err e;
    igor_spec s = plain_spec(2, 5, 4, 1e-8);
    wbuf b = igor5(&s);
    float nan = NAN; /* Igor's blank at (2, 1): row 4 - 1 - 1 = 2 of the map */
    memcpy(b.p + 384 + 4 * (1 * 5 + 2), &nan, 4);
    assert_int_equal(ljgap__files_ibw.read(b.p, b.n, NULL, &m, &e), 0);
    assert_int_equal(m.missing, 1);
    assert_true(isnan(m.z[2 * 5 + 2]));
    assert_true(m.z[2 * 5 + 3] == igor_value(3, 1, 0));
    map_free(&m);
    free(b.p);
    /* version 2, both byte orders: a profile, nm heights, µm steps, a note with a date */
    for (int be = 0; be < 2; be++) {
        wbuf v = igor2(be, 40, "Date: 2020-02-29\rTime: 23:59:58\r");
        assert_true(ljgap__files_ibw.probe(v.p, v.n));
        assert_int_equal(ljgap__files_ibw.read(v.p, v.n, NULL, &m, &e), 0);
        assert_int_equal(m.nx, 40);
        assert_int_equal(m.ny, 1);
        assert_true(fabs(m.size_x - 10e-6) < 1e-18);
        assert_true(m.size_y == 0);
        assert_string_equal(m.z_unit, "nm");
        assert_string_equal(m.acquired, "2020-02-29T23:59:58");
        for (size_t i = 0; i < 40; i++)
            assert_true(m.z[i] == igor_value(i, 0, 0) * 1e-9);
        map_free(&m);
        free(v.p);
    }
}

/* Every cut of a file before its end: BAD, an offset inside the file, no map. */
static void check_truncations(const ljgap__files_format *f, const unsigned char *p, size_t n,
                              size_t keep)
{
    ljgap__files_map m;
    ljgap__files_err e;
    for (size_t cut = 0; cut + keep < n; cut++) {
        unsigned char *t = malloc(cut ? cut : 1); /* exactly cut bytes: ASan sees overreads */
        assert_non_null(t);
        memcpy(t, p, cut);
        (void)f->probe(t, cut);
        memset(&e, 0, sizeof e);
        int rc = f->read(t, cut, NULL, &m, &e);
        if (rc != LJGAP_FILES_BAD)
            fprintf(stderr, "%s: cut at %zu of %zu: %d\n", f->name, cut, n, rc);
        assert_int_equal(rc, LJGAP_FILES_BAD);
        assert_null(m.z);
        assert_string_equal(e.format, f->name);
        assert_true(e.offset >= -1 && e.offset <= (long)cut);
        assert_true(e.msg[0] != 0);
        free(t);
    }
}

static void test_ibw_bad(void **state)
{
    (void)state;
    ljgap__files_map m;
    ljgap__files_err e;
    igor_spec s = asylum_spec(9, 7, 3);
    wbuf b = igor5(&s);
    check_truncations(&ljgap__files_ibw, b.p, b.n, 0);
    wbuf v = igor2(1, 9, "Date: 2020-02-29\r");
    check_truncations(&ljgap__files_ibw, v.p, v.n, 0);
    free(v.p);
    /* a wrong checksum: not claimed, and BAD when forced */
    b.p[64 + 100] ^= 1;
    assert_false(ljgap__files_ibw.probe(b.p, b.n));
    assert_int_equal(ljgap__files_ibw.read(b.p, b.n, NULL, &m, &e), LJGAP_FILES_BAD);
    assert_int_equal(e.offset, 0);
    b.p[64 + 100] ^= 1;
    /* inconsistent headers, each with its checksum repaired */
    struct {
        size_t at;
        uint64_t v;
        int size;
        int rc;
    } cases[] = {{64 + 12, 9 * 7 * 3 + 1, 4, LJGAP_FILES_BAD},     /* npnts */
                 {64 + 16, 0x03, 2, LJGAP_FILES_BAD},              /* complex */
                 {64 + 16, 0x00, 2, LJGAP_FILES_BAD},              /* text */
                 {4, 320 + 4 * 9 * 7 * 3 - 4, 4, LJGAP_FILES_BAD}, /* wfmSize */
                 {64 + 80, 2, 4, LJGAP_FILES_BAD},                 /* nDim[3] = 2 */
                 {16, 1u << 30, 4, LJGAP_FILES_BAD},               /* extended units past the end */
                 {64 + 68, 0, 4, LJGAP_FILES_BAD}};                /* nDim[0] = 0 */
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        wbuf c = igor5(&s);
        c.be = 0;
        put_uint_at(&c, cases[k].at, cases[k].v, cases[k].size);
        igor_checksum(c.p, c.n);
        assert_true(ljgap__files_ibw.probe(c.p, c.n));
        refused(&ljgap__files_ibw, c.p, c.n, NULL, cases[k].rc);
        free(c.p);
    }
    /* too many points: 4097 x 4097 int8, which is there in full */
    igor_spec big = plain_spec(8, 4097, 4097, 1);
    wbuf g = igor5(&big);
    refused(&ljgap__files_ibw, g.p, g.n, NULL, LJGAP_FILES_TOOBIG);
    free(g.p);
    free(b.p);
}

static void test_park(void **state)
{
    (void)state;
    ljgap__files_map m;
    ljgap__files_err e;
    park_spec s = park_small(12, 7);
    s.gain = 0.5;
    wbuf b = park_tiff(&s);
    assert_true(ljgap__files_park_tiff.probe(b.p, b.n));
    assert_int_equal(ljgap__files_park_tiff.read(b.p, b.n, NULL, &m, &e), 0);
    assert_string_equal(m.format, "park-tiff");
    assert_int_equal(m.nx, 12);
    assert_int_equal(m.ny, 7);
    assert_true(fabs(m.size_x - 8e-6) < 1e-18 && fabs(m.size_y - 4e-6) < 1e-18);
    assert_string_equal(m.channel, "Topography");
    assert_int_equal(m.n_channels, 1);
    assert_string_equal(m.z_unit, "um");
    assert_string_equal(m.acquired, "2023-04-05T06:07:08");
    assert_string_equal(m.instrument, "Park Systems");
    check_park_points(&m, 12, 7, 0.5, 1, 0, 1e-6, 0); /* exactly */
    map_free(&m);
    assert_int_equal(ljgap__files_park_tiff.read(b.p, b.n, "0", &m, &e), 0);
    map_free(&m);
    assert_int_equal(ljgap__files_park_tiff.read(b.p, b.n, "topography", &m, &e), 0);
    map_free(&m);
    refused(&ljgap__files_park_tiff, b.p, b.n, "1", LJGAP_FILES_CHANNEL);
    check_truncations(&ljgap__files_park_tiff, b.p, b.n, 0);
    free(b.p);

    /* version 1: int16, z scale and offset, nm; version 2 int32 with swap_xy (the fast axis was
     * y): stored in image order all the same */
    static const struct {
        park_spec s;
        double tol;
    } more[] = {{{.version = 1,
                  .dtype = 0,
                  .xres = 9,
                  .yres = 5,
                  .gain = 2,
                  .zscale = 0.25,
                  .zoff = 3,
                  .unit = "nm",
                  .source = "Z Height",
                  .park = 1},
                 1e-24},
                {{.version = 2,
                  .dtype = 1,
                  .xres = 6,
                  .yres = 4,
                  .gain = 1,
                  .zscale = 1,
                  .unit = "nm",
                  .source = "Height",
                  .swap = 1,
                  .park = 1},
                 0}};
    for (size_t k = 0; k < sizeof more / sizeof more[0]; k++) {
        const park_spec *sk = &more[k].s;
        b = park_tiff(sk);
        assert_int_equal(ljgap__files_park_tiff.read(b.p, b.n, NULL, &m, &e), 0);
        assert_true(fabs(m.size_x - 8e-6) < 1e-18 && fabs(m.size_y - 4e-6) < 1e-18);
        check_park_points(&m, sk->xres, sk->yres, sk->gain, sk->zscale, sk->zoff, 1e-9,
                          more[k].tol);
        map_free(&m);
        free(b.p);
    }
}

static void test_park_bad(void **state)
{
    (void)state;
    ljgap__files_map m;
    ljgap__files_err e;
    park_spec s = park_small(4, 3);
    s.park = 0;
    wbuf b = park_tiff(&s); /* a plain TIFF: not Park's */
    assert_false(ljgap__files_park_tiff.probe(b.p, b.n));
    refused(&ljgap__files_park_tiff, b.p, b.n, NULL, LJGAP_FILES_BAD);
    free(b.p);
    s.park = 1; /* the same file as a big-endian TIFF: not Park's */
    b = park_tiff(&s);
    memcpy(b.p, "MM\0*", 4);
    assert_false(ljgap__files_park_tiff.probe(b.p, b.n));
    assert_int_equal(ljgap__files_park_tiff.read(b.p, b.n, NULL, &m, &e), LJGAP_FILES_BAD);
    free(b.p);
    s.short_header = 1;
    b = park_tiff(&s);
    assert_int_equal(ljgap__files_park_tiff.read(b.p, b.n, NULL, &m, &e), LJGAP_FILES_BAD);
    assert_non_null(strstr(e.msg, "header"));
    free(b.p);
    s.short_header = 0, s.dtype = 7;
    b = park_tiff(&s);
    assert_int_equal(ljgap__files_park_tiff.read(b.p, b.n, NULL, &m, &e), LJGAP_FILES_BAD);
    free(b.p);
    /* the data tag shorter than the grid, a directory that runs past the end, TOOBIG */
    s.dtype = 2;
    b = park_tiff(&s);
    size_t ifd = b.p[4] | (size_t)b.p[5] << 8;
    size_t data_entry = ifd + 2 + 12 * 12;
    b.p[data_entry + 4] -= 1;
    assert_int_equal(ljgap__files_park_tiff.read(b.p, b.n, NULL, &m, &e), LJGAP_FILES_BAD);
    assert_int_equal(e.offset, (long)data_entry);
    b.p[data_entry + 4] += 1;
    b.p[ifd] = 0xff;
    assert_false(ljgap__files_park_tiff.probe(b.p, b.n));
    assert_int_equal(ljgap__files_park_tiff.read(b.p, b.n, NULL, &m, &e), LJGAP_FILES_BAD);
    b.p[ifd] = 14;
    size_t head = b.p[data_entry + 12 + 8] | (size_t)b.p[data_entry + 12 + 9] << 8;
    put_uint_at(&b, head + 100, 5000, 4);
    put_uint_at(&b, head + 104, 5000, 4);
    refused(&ljgap__files_park_tiff, b.p, b.n, NULL, LJGAP_FILES_TOOBIG);
    free(b.p);
}

static void test_plu(void **state)
{
    (void)state;
    ljgap__files_map m;
    ljgap__files_err e;
    wbuf b = plu_file(11, 6, 2, 3, 0);
    assert_true(ljgap__files_plu.probe(b.p, b.n));
    for (int l = 0; l < 2; l++) {
        assert_int_equal(ljgap__files_plu.read(b.p, b.n, l ? "layer 1" : NULL, &m, &e), 0);
        assert_string_equal(m.format, "plu");
        assert_int_equal(m.channel_index, l);
        assert_int_equal(m.n_channels, 2);
        assert_int_equal(m.nx, 11);
        assert_int_equal(m.ny, 6);
        assert_true(fabs(m.size_x - 5.5e-6) < 1e-18 && fabs(m.size_y - 4.5e-6) < 1e-18);
        assert_string_equal(m.z_unit, "um");
        assert_string_equal(m.instrument, "Sensofar PLu 3300");
        assert_string_equal(m.acquired, "2024-03-05T14:03:09");
        size_t missing = 0;
        for (size_t j = 0; j < 6; j++)
            for (size_t i = 0; i < 11; i++) {
                double z = m.z[j * 11 + i];
                if ((i + j + (size_t)l) % 7 == 3)
                    assert_true(isnan(z)), missing++;
                else
                    assert_true(z == (double)plu_value(i, j, (size_t)l) * 1e-6);
            }
        assert_int_equal(m.missing, missing);
        map_free(&m);
    }
    refused(&ljgap__files_plu, b.p, b.n, "2", LJGAP_FILES_CHANNEL);
    /* every cut before the last layer's min and max (which a reader does not need) */
    check_truncations(&ljgap__files_plu, b.p, b.n, 8);
    free(b.p);
    /* a profile (type 1, one row): no y size; version 2006 and 0 layers (read as 1) */
    b = plu_file(30, 1, 0, 1, 255);
    assert_int_equal(ljgap__files_plu.read(b.p, b.n, NULL, &m, &e), 0);
    assert_int_equal(m.ny, 1);
    assert_true(m.size_y == 0);
    map_free(&m);
    free(b.p);
    /* refused: multiple profiles (2), an unknown version, no date, TOOBIG */
    b = plu_file(4, 4, 1, 2, 0);
    assert_int_equal(refused(&ljgap__files_plu, b.p, b.n, NULL, LJGAP_FILES_BAD).offset, 428);
    free(b.p);
    b = plu_file(4, 4, 1, 3, 7);
    assert_int_equal(ljgap__files_plu.read(b.p, b.n, NULL, &m, &e), LJGAP_FILES_BAD);
    b.p[490] = 0, b.p[3] = '-';
    assert_false(ljgap__files_plu.probe(b.p, b.n));
    assert_int_equal(ljgap__files_plu.read(b.p, b.n, NULL, &m, &e), LJGAP_FILES_BAD);
    b.p[3] = ' ';
    put_uint_at(&b, 500, 5000, 4), put_uint_at(&b, 504, 5000, 4);
    refused(&ljgap__files_plu, b.p, b.n, NULL, LJGAP_FILES_TOOBIG);
    free(b.p);
}

/* Each probe claims its own format only. */
static void test_probes_disjoint(void **state)
{
    (void)state;
    igor_spec s = plain_spec(2, 4, 3, 1);
    park_spec p = park_small(4, 3);
    wbuf files[3] = {igor5(&s), park_tiff(&p), plu_file(4, 3, 1, 3, 0)};
    for (int f = 0; f < 3; f++) {
        for (int r = 0; r < 3; r++)
            assert_int_equal(readers[r]->probe(files[f].p, files[f].n), f == r);
        free(files[f].p);
    }
    static const unsigned char text[] = "0.1 0.2 0.3\n0.4 0.5 0.6\n";
    for (int r = 0; r < 3; r++)
        assert_false(readers[r]->probe(text, sizeof text - 1));
    for (int r = 0; r < 3; r++)
        assert_false(readers[r]->probe(text, 0));
}

/* Every byte of a small file of each format changed (to 0, 0xff, its complement, 0x7f): the
 * reader answers 0 with a whole map whose NaNs are its missing points, or an error and no map;
 * never a crash or a read past the buffer (ASan). */
static void test_mutations(void **state)
{
    (void)state;
    igor_spec s = asylum_spec(5, 4, 2);
    park_spec p = park_small(5, 4);
    wbuf files[3] = {igor5(&s), park_tiff(&p), plu_file(5, 4, 2, 3, 0)};
    long ok = 0, refused = 0;
    for (int f = 0; f < 3; f++) {
        size_t n = files[f].n;
        unsigned char *t = malloc(n);
        assert_non_null(t);
        for (size_t pos = 0; pos < n; pos++)
            for (int v = 0; v < 4; v++) {
                memcpy(t, files[f].p, n);
                t[pos] = v == 0 ? 0 : v == 1 ? 0xff : v == 2 ? (unsigned char)~t[pos] : 0x7f;
                if (f == 0 && pos < 384 && (pos < 2 || pos > 3)) /* past the checksum */
                    igor_checksum(t, n);
                (void)readers[f]->probe(t, n);
                ljgap__files_map m;
                ljgap__files_err e;
                int rc = readers[f]->read(t, n, v == 3 ? "1" : NULL, &m, &e);
                if (rc == 0) {
                    size_t nan = 0;
                    assert_non_null(m.z);
                    assert_true(m.nx > 0 && m.ny > 0);
                    for (size_t i = 0; i < m.nx * m.ny; i++)
                        nan += isnan(m.z[i]) != 0;
                    assert_int_equal(nan, m.missing);
                    assert_true(m.channel_index >= 0 && m.channel_index < m.n_channels);
                    map_free(&m), ok++;
                } else {
                    assert_true(rc == LJGAP_FILES_BAD || rc == LJGAP_FILES_CHANNEL ||
                                rc == LJGAP_FILES_TOOBIG);
                    assert_null(m.z);
                    refused++;
                }
            }
        free(t);
        free(files[f].p);
    }
    assert_true(ok > 0 && refused > 0);
}

/* ---- the dump for tests/files/check_c.sh ---- */

static int dump(const char *format, const char *path, const char *channel)
{
    FILE *f = fopen(path, "rb");
    if (!f) return perror(path), 2;
    size_t cap = 1 << 20, n = 0;
    unsigned char *buf = malloc(cap);
    for (size_t k; buf && (k = fread(buf + n, 1, cap - n, f)) > 0;)
        if ((n += k) == cap) buf = realloc(buf, cap *= 2);
    fclose(f);
    if (!buf) return 2;
    for (size_t r = 0; r < 3; r++) {
        if (strcmp(readers[r]->name, format)) continue;
        ljgap__files_map m;
        ljgap__files_err e;
        int rc = readers[r]->read(buf, n, channel, &m, &e);
        if (rc) {
            fprintf(stderr, "%s: %d %s (offset %ld)\n", path, rc, e.msg, e.offset);
            free(buf);
            return 1;
        }
        printf("%zu %zu %.17g %.17g %s %zu %s\n", m.nx, m.ny, m.size_x, m.size_y,
               m.z_unit[0] ? m.z_unit : "-", m.missing, m.channel);
        for (size_t i = 0; i < m.nx * m.ny; i++)
            printf("%.17g\n", m.z[i]);
        map_free(&m);
        free(buf);
        return 0;
    }
    fprintf(stderr, "unknown format %s\n", format);
    free(buf);
    return 2;
}

int main(int argc, char **argv)
{
    if (argc >= 4 && !strcmp(argv[1], "--dump")) return dump(argv[2], argv[3], argv[4]);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ibw_asylum),
        cmocka_unit_test(test_ibw_types),
        cmocka_unit_test(test_ibw_nan_and_v2),
        cmocka_unit_test(test_ibw_bad),
        cmocka_unit_test(test_park),
        cmocka_unit_test(test_park_bad),
        cmocka_unit_test(test_plu),
        cmocka_unit_test(test_probes_disjoint),
        cmocka_unit_test(test_mutations),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
