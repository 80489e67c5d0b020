/* test_files.c -- the instrument-file readers (server/files/) and POST /v1/psd with a file
 * (server/api/psd.c, ljgap__handle_file).
 *
 * Small files are written here from each format's documentation (independently of
 * tests/files/gen.py, which writes others for the Gwyddion cross-check): a NanoScope file of two
 * channels, a GSF, a GWY with a mask, xyz columns with a hole. Each is read back exactly, then
 * every prefix of it is read from a buffer of exactly that length (a sanitizer build sees a
 * read past it) and must be refused, never read. The registry: detection, forcing, unknown
 * formats, channels by index, title and default. Missing points: the largest complete rectangle
 * of a map with a known hole, and the PSD of a file with that hole equal, bin for bin, to the
 * PSD of that rectangle sent as a text matrix. The handler's problems: 415 listing the formats,
 * 422 bad-file with format and offset, 422 at /channel and at /topography/dx.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "files.h"
#include "handler.h"

#include <cjson/cJSON.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- a growing byte buffer ---- */
typedef struct {
    unsigned char *b;
    size_t n, cap;
} buf;

static void put(buf *o, const void *p, size_t n)
{
    if (o->n + n > o->cap) {
        o->cap = 2 * (o->n + n) + 256;
        o->b = realloc(o->b, o->cap);
        assert_non_null(o->b);
    }
    memcpy(o->b + o->n, p, n);
    o->n += n;
}
static void puts_(buf *o, const char *s)
{
    put(o, s, strlen(s) + 1);
} /* with its NUL */
static void putf(buf *o, const char *fmt, ...)
{
    char s[512];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(s, sizeof s, fmt, ap);
    va_end(ap);
    put(o, s, (size_t)n);
}
static void put_u32(buf *o, uint32_t v)
{
    unsigned char c[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                          (unsigned char)(v >> 24)};
    put(o, c, 4);
}
static void put_f64(buf *o, double d)
{
    uint64_t u;
    memcpy(&u, &d, 8);
    put_u32(o, (uint32_t)u);
    put_u32(o, (uint32_t)(u >> 32));
}

/* a height that looks like a surface: a few waves and a deterministic jitter */
static double height(size_t i, size_t j)
{
    uint32_t h = (uint32_t)(i * 2654435761u) ^ (uint32_t)(j * 40503u + 977u);
    h ^= h >> 13, h *= 0x5bd1e995u, h ^= h >> 15;
    return 1e-8 * sin(0.37 * (double)i + 0.11 * (double)j) + 4e-9 * cos(0.05 * (double)(i * j)) +
           1e-9 * ((double)(h % 2001) / 1000.0 - 1);
}

/* ---- the files ---- */

#define NX 20
#define NY 17

/* NanoScope 5: Height (16-bit, Sens. Zsens 20 nm/V) and Phase (no sensitivity: V). */
static buf nanoscope(int16_t raw[2][NY][NX])
{
    buf o = {0}, h = {0};
    const size_t hdr = 4096, n = (size_t)NX * NY * 2;
    for (int c = 0; c < 2; c++)
        for (int j = 0; j < NY; j++)
            for (int i = 0; i < NX; i++)
                raw[c][j][i] = (int16_t)((i * 977 + j * 131 + c * 7) % 60001 - 30000);
    putf(&h, "\\*File list\r\n\\Version: 0x05120005\r\n\\Data length: %zu\r\n", hdr);
    putf(&h, "\\Date: 11:05:00 AM Tue Mar 05 2013\r\n\\*Scanner list\r\n");
    putf(&h, "\\@Sens. Zsens: V 20 nm/V\r\n");
    for (int c = 0; c < 2; c++) {
        putf(&h, "\\*Ciao image list\r\n\\Data offset: %zu\r\n\\Data length: %zu\r\n", hdr + c * n,
             n);
        putf(&h, "\\Bytes/pixel: 2\r\n\\Samps/line: %d\r\n\\Number of lines: %d\r\n", NX, NY);
        putf(&h, "\\Scan Size: 2 1.7 ~m\r\n");
        putf(
            &h,
            c ? "\\@2:Image Data: S [Phase] \"Phase\"\r\n\\@2:Z scale: V (0.001 V/LSB) 65.536 V\r\n"
              : "\\@2:Image Data: S [Height] \"Height\"\r\n"
                "\\@2:Z scale: V [Sens. Zsens] (0.0001 V/LSB) 6.5536 V\r\n");
    }
    putf(&h, "\\*File list end\r\n");
    put(&o, h.b, h.n);
    while (o.n < hdr)
        put(&o, "", 1);
    for (int c = 0; c < 2; c++)
        for (int j = 0; j < NY; j++)
            for (int i = 0; i < NX; i++) {
                unsigned char le[2] = {(unsigned char)(raw[c][j][i] & 0xff),
                                       (unsigned char)((uint16_t)raw[c][j][i] >> 8)};
                put(&o, le, 2);
            }
    free(h.b);
    return o;
}

/* GSF of nx x ny float heights (NaN where hole(i, j)), size nx * 1e-8 by ny * 1e-8 m. */
static buf gsf(size_t nx, size_t ny, int (*hole)(size_t, size_t))
{
    buf o = {0};
    putf(&o,
         "Gwyddion Simple Field 1.0\nXRes = %zu\nYRes = %zu\nXReal = %.17g\nYReal = %.17g\n"
         "XYUnits = m\nZUnits = m\nTitle = Height\n",
         nx, ny, nx * 1e-8, ny * 1e-8);
    size_t pad = 4 - o.n % 4;
    put(&o, "\0\0\0\0", pad);
    for (size_t j = 0; j < ny; j++)
        for (size_t i = 0; i < nx; i++) {
            float f = hole && hole(i, j) ? NAN : (float)height(i, j);
            uint32_t u;
            memcpy(&u, &f, 4);
            put_u32(&o, u);
        }
    return o;
}

static void gwy_field(buf *o, const double *z, int nx, int ny, const char *unit)
{
    buf c = {0};
    puts_(&c, "xres"), put(&c, "i", 1), put_u32(&c, (uint32_t)nx);
    puts_(&c, "yres"), put(&c, "i", 1), put_u32(&c, (uint32_t)ny);
    puts_(&c, "xreal"), put(&c, "d", 1), put_f64(&c, 3e-6);
    puts_(&c, "yreal"), put(&c, "d", 1), put_f64(&c, 3e-6 * ny / nx);
    for (int u = 0; u < 2; u++) {
        buf s = {0};
        puts_(&s, "unitstr"), put(&s, "s", 1), puts_(&s, u ? unit : "m");
        puts_(&c, u ? "si_unit_z" : "si_unit_xy"), put(&c, "o", 1);
        puts_(&c, "GwySIUnit"), put_u32(&c, (uint32_t)s.n), put(&c, s.b, s.n);
        free(s.b);
    }
    puts_(&c, "data"), put(&c, "D", 1), put_u32(&c, (uint32_t)(nx * ny));
    for (int k = 0; k < nx * ny; k++)
        put_f64(&c, z[k]);
    puts_(o, "GwyDataField"), put_u32(o, (uint32_t)c.n), put(o, c.b, c.n);
    free(c.b);
}

/* GWY: /0/data "Height" in m with /0/mask marking a 2 x 3 block, /1/data "Error" in V. */
static buf gwy(double z[NY * NX], double mask[NY * NX])
{
    buf o = {0}, c = {0};
    for (int j = 0; j < NY; j++)
        for (int i = 0; i < NX; i++) {
            z[j * NX + i] = height((size_t)i, (size_t)j);
            mask[j * NX + i] = j >= 4 && j < 6 && i >= 9 && i < 12;
        }
    puts_(&c, "/1/data"), put(&c, "o", 1), gwy_field(&c, z, NX, NY, "V");
    puts_(&c, "/1/data/title"), put(&c, "s", 1), puts_(&c, "Error");
    puts_(&c, "/0/data/title"), put(&c, "s", 1), puts_(&c, "Height");
    puts_(&c, "/0/show"), put(&c, "b", 1), put(&c, "\1", 1);
    puts_(&c, "/0/mask"), put(&c, "o", 1), gwy_field(&c, mask, NX, NY, "");
    puts_(&c, "/0/data"), put(&c, "o", 1), gwy_field(&c, z, NX, NY, "m");
    put(&o, "GWYP", 4);
    puts_(&o, "GwyContainer"), put_u32(&o, (uint32_t)c.n), put(&o, c.b, c.n);
    free(c.b);
    return o;
}

/* Reads b (format NULL: detected) into m; the status. */
static int read_buf(const buf *b, const char *format, const char *channel, ljgap__files_map *m,
                    ljgap__files_err *e)
{
    return ljgap__files_read(b->b, b->n, format, channel, m, e);
}

/* Every prefix of b, from a buffer of exactly its length, is refused (bad or unknown). */
static void every_prefix_refused(const buf *b)
{
    for (size_t n = 0; n < b->n; n++) {
        unsigned char *c = malloc(n ? n : 1);
        ljgap__files_map m;
        ljgap__files_err e;
        assert_non_null(c);
        memcpy(c, b->b, n);
        int st = ljgap__files_read(c, n, NULL, NULL, &m, &e);
        if (st != LJGAP_FILES_BAD && st != LJGAP_FILES_UNKNOWN)
            fail_msg("a prefix of %zu of %zu bytes gave status %d", n, b->n, st);
        assert_null(m.z);
        ljgap__files_map_free(&m);
        free(c);
    }
}

static void nanoscope_read_exactly(void **state)
{
    static int16_t raw[2][NY][NX];
    buf b = nanoscope(raw);
    ljgap__files_map m;
    ljgap__files_err e;
    assert_int_equal(read_buf(&b, NULL, NULL, &m, &e), 0);
    assert_string_equal(m.format, "nanoscope");
    assert_int_equal(m.nx, NX);
    assert_int_equal(m.ny, NY);
    assert_int_equal(m.n_channels, 2);
    assert_string_equal(m.channel, "Height");
    assert_string_equal(m.z_unit, "nm");
    assert_string_equal(m.acquired, "2013-03-05T11:05:00");
    assert_true(fabs(m.size_x - 2e-6) < 1e-18 && fabs(m.size_y - 1.7e-6) < 1e-18);
    /* raw * 6.5536 V / 65536 * 20 nm/V, the first row of the file at the bottom */
    for (int j = 0; j < NY; j++)
        for (int i = 0; i < NX; i++)
            assert_true(fabs(m.z[(NY - 1 - j) * NX + i] - raw[0][j][i] * 1e-4 * 20e-9) <=
                        1e-15 * fabs(raw[0][j][i] * 2e-12) + 1e-30);
    ljgap__files_map_free(&m);
    assert_int_equal(read_buf(&b, "nanoscope", "phase", &m, &e), 0);
    assert_string_equal(m.z_unit, "V");
    assert_int_equal(m.channel_index, 1);
    assert_true(fabs(m.z[NX * (NY - 1)] - raw[1][0][0] * 0.001) < 1e-12);
    ljgap__files_map_free(&m);
    every_prefix_refused(&b);
    free(b.b);
}

static int gsf_hole(size_t i, size_t j)
{
    return i == 3 && j == 5;
}

static void gsf_read_exactly(void **state)
{
    buf b = gsf(NX, NY, gsf_hole);
    ljgap__files_map m;
    ljgap__files_err e;
    assert_int_equal(read_buf(&b, NULL, NULL, &m, &e), 0);
    assert_string_equal(m.format, "gsf");
    assert_int_equal(m.missing, 1);
    assert_true(isnan(m.z[5 * NX + 3]));
    assert_true(m.z[5 * NX + 4] == (double)(float)height(4, 5));
    assert_true(fabs(m.size_x - NX * 1e-8) < 1e-20);
    ljgap__files_map_free(&m);
    every_prefix_refused(&b);
    free(b.b);
}

static void gwy_read_exactly(void **state)
{
    static double z[NY * NX], mask[NY * NX];
    buf b = gwy(z, mask);
    ljgap__files_map m;
    ljgap__files_err e;
    assert_int_equal(read_buf(&b, NULL, NULL, &m, &e), 0);
    assert_string_equal(m.format, "gwy");
    /* the channels in the order of their numbers, the height by its title */
    assert_string_equal(m.channels[0], "Height");
    assert_string_equal(m.channels[1], "Error");
    assert_int_equal(m.channel_index, 0);
    assert_int_equal(m.missing, 6);
    for (int k = 0; k < NX * NY; k++)
        assert_true(mask[k] > 0.5 ? isnan(m.z[k]) : m.z[k] == z[k]);
    ljgap__files_map_free(&m);
    assert_int_equal(read_buf(&b, NULL, "Error", &m, &e), 0);
    assert_int_equal(m.missing, 0);
    assert_string_equal(m.z_unit, "V");
    ljgap__files_map_free(&m);
    assert_int_equal(read_buf(&b, NULL, "7", &m, &e), LJGAP_FILES_CHANNEL);
    assert_non_null(strstr(e.msg, "0 \"Height\", 1 \"Error\""));
    ljgap__files_map_free(&m);
    every_prefix_refused(&b);
    free(b.b);
}

static void xyz_grid_found(void **state)
{
    buf b = {0};
    ljgap__files_map m;
    ljgap__files_err e;
    putf(&b, "# a header\nX, Y, Z\n");
    /* columns in reverse order, a missing point at (2, 1), spacing 0.5 um by 0.25 um */
    for (int j = 4; j >= 0; j--)
        for (int i = 5; i >= 0; i--)
            if (!(i == 2 && j == 1))
                putf(&b, "%.6e, %.6e, %.17g\n", 1e-3 + i * 5e-7, j * 2.5e-7, height(i, j));
    put(&b, "", 1);
    b.n--; /* text, no NUL */
    assert_int_equal(read_buf(&b, NULL, NULL, &m, &e), 0);
    assert_string_equal(m.format, "xyz");
    assert_int_equal(m.nx, 6);
    assert_int_equal(m.ny, 5);
    assert_int_equal(m.missing, 1);
    assert_true(isnan(m.z[1 * 6 + 2]));
    assert_true(m.z[4 * 6 + 5] == height(5, 4));
    assert_true(fabs(m.size_x - 3e-6) < 1e-15 && fabs(m.size_y - 1.25e-6) < 1e-15);
    ljgap__files_map_free(&m);
    free(b.b);
    /* coordinates rounded by the export (a spacing of 1/3 um written with 3 decimals) */
    b = (buf){0};
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++)
            putf(&b, "%.3f %.3f %g\n", i / 3.0, j / 3.0, height(i, j));
    assert_int_equal(read_buf(&b, NULL, NULL, &m, &e), 0);
    assert_int_equal(m.nx, 4);
    assert_int_equal(m.ny, 4);
    assert_int_equal(m.missing, 0);
    ljgap__files_map_free(&m);
    free(b.b);
    /* a point cloud is no grid; a point given twice is an error */
    b = (buf){0};
    for (int k = 0; k < 50; k++)
        putf(&b, "%g %g %g\n", sin(k * 1.3), cos(k * 0.7), height(k, 0));
    assert_int_equal(read_buf(&b, NULL, NULL, &m, &e), LJGAP_FILES_BAD);
    free(b.b);
    b = (buf){0};
    putf(&b, "0 0 1\n1 0 2\n0 1 3\n1 1 4\n1 1 5\n");
    assert_int_equal(read_buf(&b, NULL, NULL, &m, &e), LJGAP_FILES_BAD);
    assert_non_null(strstr(e.msg, "twice"));
    free(b.b);
}

static void registry_and_detection(void **state)
{
    const ljgap__files_format *const *f = ljgap__files_formats();
    ljgap__files_map m;
    ljgap__files_err e;
    int n = 0;
    for (; f[n]; n++) {
        for (int k = 0; k < n; k++)
            assert_true(strcmp(f[k]->name, f[n]->name) != 0);
        assert_ptr_equal(ljgap__files_find(f[n]->name), f[n]);
    }
    assert_true(n >= 4);
    assert_string_equal(f[n - 1]->name, "xyz"); /* the loosest last */
    static const unsigned char png[] = "\x89PNG\r\n\x1a\n\0\0\0\rIHDR";
    assert_int_equal(ljgap__files_read(png, sizeof png, NULL, NULL, &m, &e), LJGAP_FILES_UNKNOWN);
    assert_non_null(strstr(e.msg, "nanoscope"));
    assert_int_equal(ljgap__files_read(png, sizeof png, "tiff-of-nothing", NULL, &m, &e),
                     LJGAP_FILES_UNKNOWN);
    assert_int_equal(ljgap__files_read(png, sizeof png, "GWY", NULL, &m, &e), LJGAP_FILES_BAD);
    assert_string_equal(e.format, "gwy");
    assert_int_equal(e.offset, 0);
    assert_int_equal(ljgap__files_read(NULL, 0, NULL, NULL, &m, &e), LJGAP_FILES_UNKNOWN);
    ljgap__files_map_free(&m);
    ljgap__files_map_free(NULL);
    assert_true(ljgap__files_unit_scale("nm") == 1e-9 && ljgap__files_unit_scale("V") == 0);
}

/* the hole: rows 20 to 25 entirely (a band), and one point at (50, 60) */
static int band_hole(size_t i, size_t j)
{
    return (j >= 20 && j < 26) || (i == 50 && j == 60);
}

static void largest_rectangle(void **state)
{
    ljgap__files_map m = {0};
    size_t x0, y0, w, h;
    m.nx = 64, m.ny = 64;
    m.z = malloc(64 * 64 * sizeof *m.z);
    for (size_t j = 0; j < 64; j++)
        for (size_t i = 0; i < 64; i++)
            m.z[j * 64 + i] = band_hole(i, j) ? NAN : 1;
    assert_int_equal(ljgap__files_count_missing(&m), 6 * 64 + 1);
    assert_int_equal(ljgap__files_largest_rect(&m, &x0, &y0, &w, &h), 0);
    /* below the band: rows 26-63 (38) of 64 = 2432; beside (50, 60): rows 26-63 of 50 columns
     * (1900), or rows 26-59 (34) of 64 = 2176; above the band 20 x 64 = 1280 */
    assert_int_equal(x0, 0);
    assert_int_equal(y0, 26);
    assert_int_equal(w, 64);
    assert_int_equal(h, 34);
    for (size_t k = 0; k < 64 * 64; k++)
        m.z[k] = NAN;
    assert_int_equal(ljgap__files_largest_rect(&m, &x0, &y0, &w, &h), 0);
    assert_int_equal(w * h, 0);
    ljgap__files_map_free(&m);
}

static cJSON *answer(ljgap__reply *r, int status)
{
    cJSON *a = cJSON_ParseWithLength(r->body, r->len);
    if (r->status != status) fail_msg("status %d, not %d: %.400s", r->status, status, r->body);
    assert_non_null(a);
    return a;
}

static void psd_of_a_map_with_a_hole(void **state)
{
    const size_t N = 64;
    buf b = gsf(N, N, band_hole), t = {0};
    ljgap__reply rf, rt;
    ljgap__param q[] = {{"detrend", "plane"}};
    ljgap__handle_file("psd", q, 1, b.b, b.n, NULL, &rf);
    cJSON *a = answer(&rf, 200);
    cJSON *s = cJSON_GetObjectItem(a, "source"), *miss = cJSON_GetObjectItem(s, "missing"),
          *used = cJSON_GetObjectItem(miss, "used");
    assert_int_equal(cJSON_GetObjectItem(miss, "count")->valuedouble, 6 * 64 + 1);
    assert_int_equal(cJSON_GetObjectItem(used, "y0")->valuedouble, 26);
    assert_int_equal(cJSON_GetObjectItem(used, "ny")->valuedouble, 34);
    assert_int_equal(cJSON_GetObjectItem(used, "nx")->valuedouble, 64);
    assert_string_equal(cJSON_GetObjectItem(s, "format")->valuestring, "gsf");
    assert_non_null(strstr(rf.body, "largest complete rectangle"));
    /* the same rectangle as a text matrix, dx from the file's size */
    for (size_t j = 26; j < 60; j++) {
        for (size_t i = 0; i < N; i++)
            putf(&t, "%.17g ", (double)(float)height(i, j));
        putf(&t, "\n");
    }
    ljgap__param qt[] = {{"detrend", "plane"}, {"dx", "1e-8"}};
    ljgap__handle_text("psd", qt, 2, (const char *)t.b, t.n, NULL, &rt);
    cJSON *at = answer(&rt, 200);
    const char *same[] = {"k", "P", "modes", "h_rms", "rms_slope", "fit", "reliable", "psd"};
    for (size_t k = 0; k < sizeof same / sizeof *same; k++) {
        char *x = cJSON_PrintUnformatted(cJSON_GetObjectItem(a, same[k]));
        char *y = cJSON_PrintUnformatted(cJSON_GetObjectItem(at, same[k]));
        if (strcmp(x, y)) fail_msg("%s differs: %.200s / %.200s", same[k], x, y);
        free(x), free(y);
    }
    cJSON_Delete(a), cJSON_Delete(at);
    ljgap__reply_free(&rf), ljgap__reply_free(&rt);
    free(b.b), free(t.b);
}

static void file_problems(void **state)
{
    buf b = gsf(32, 32, NULL);
    ljgap__reply r;
    cJSON *a;
    ljgap__param dx[] = {{"dx", "1e-9"}}, ch[] = {{"channel", "Phase"}}, bad[] = {{"bogus", "1"}},
                fm[] = {{"format", "pdf"}};
    ljgap__handle_file("psd", NULL, 0, (const unsigned char *)"GIF89a....", 10, NULL, &r);
    a = answer(&r, 415);
    assert_non_null(strstr(cJSON_GetObjectItem(a, "detail")->valuestring, "gsf (.gsf)"));
    cJSON_Delete(a), ljgap__reply_free(&r);
    ljgap__handle_file("psd", fm, 1, b.b, b.n, NULL, &r);
    a = answer(&r, 422);
    assert_non_null(strstr(r.body, "\"pointer\":\"/format\""));
    cJSON_Delete(a), ljgap__reply_free(&r);
    ljgap__handle_file("psd", NULL, 0, b.b, b.n - 7, NULL, &r);
    a = answer(&r, 422);
    assert_string_equal(cJSON_GetObjectItem(a, "type")->valuestring, "/problems/bad-file");
    assert_string_equal(cJSON_GetObjectItem(a, "format")->valuestring, "gsf");
    assert_int_equal(cJSON_GetObjectItem(a, "offset")->valuedouble, (double)(b.n - 7));
    cJSON_Delete(a), ljgap__reply_free(&r);
    ljgap__handle_file("psd", dx, 1, b.b, b.n, NULL, &r);
    a = answer(&r, 422);
    assert_non_null(strstr(r.body, "\"pointer\":\"/topography/dx\""));
    cJSON_Delete(a), ljgap__reply_free(&r);
    ljgap__handle_file("psd", ch, 1, b.b, b.n, NULL, &r);
    a = answer(&r, 422);
    assert_non_null(strstr(r.body, "\"pointer\":\"/channel\""));
    cJSON_Delete(a), ljgap__reply_free(&r);
    /* an unknown query parameter is refused whatever the file */
    ljgap__handle_file("psd", bad, 1, (const unsigned char *)"x", 1, NULL, &r);
    a = answer(&r, 422);
    assert_non_null(strstr(r.body, "\"pointer\":\"/bogus\""));
    cJSON_Delete(a), ljgap__reply_free(&r);
    free(b.b);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(registry_and_detection),   cmocka_unit_test(nanoscope_read_exactly),
        cmocka_unit_test(gsf_read_exactly),         cmocka_unit_test(gwy_read_exactly),
        cmocka_unit_test(xyz_grid_found),           cmocka_unit_test(largest_rectangle),
        cmocka_unit_test(psd_of_a_map_with_a_hole), cmocka_unit_test(file_problems),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
