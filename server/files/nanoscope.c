/* nanoscope.c -- Bruker / Veeco / Digital Instruments NanoScope files (.spm, .000, .001, .di).
 *
 * A text header of lines "\Key: value" in sections "\*Name", from "\*File list" to
 * "\*File list end" (lines end in CR LF), then the images as little-endian signed integers.
 * Each image is a "\*Ciao image list" section: "\Data offset" and "\Data length" (bytes from
 * the file's start), "\Bytes/pixel" (2 or 4), "\Samps/line" and "\Number of lines" (the
 * grid), "\Scan Size: X Y unit" (the physical size), "\@2:Image Data: S [Height] "Height""
 * (the channel's title, quoted) and "\@2:Z scale: V [Sens. Zsens] (0.0067 V/LSB) 440 V".
 * The height is the chain raw * hard scale * soft scale: the hard scale is the Z scale's
 * value over 65536 (the full 16-bit range spans it; the "(… V/LSB)" is the same number
 * rounded), over 65536 once more for 4-byte pixels (a 32-bit integer spans the same range),
 * and the soft scale the sensitivity the bracket names, "\@Sens. Zsens: V 18.3 nm/V" in the
 * scanner list, which also gives the unit (nm). Without a bracket the channel stays in the
 * hard unit (V: not a height). Old files (version 4) say "\Image data:" and "\Z scale:"
 * without the "@2:", and are read the same way.
 *
 * The file's first image row is the bottom of the scan; the map's rows run from the top (as
 * Gwyddion shows them), so rows are read in reverse. Read besides: "\Date" (ISO 8601) and the
 * instrument ("\Microscope" or "\Description" of the equipment list). Not read: force curves
 * and force volumes ("\*Force file list"), the "\@Z magnify" display factor, tip radius
 * (not stored), the scan's rotation and offset.
 */
#include "bytes.h"
#include "files_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define NAME "nanoscope"
#define MAX_LINES 20000 /* a header has a few hundred */

typedef struct {
    const char *key, *val; /* into the buffer */
    size_t klen, vlen;
    int section;  /* index of the section's own line */
    size_t where; /* byte offset of the line */
} line;

typedef struct {
    line *l;
    int n;
} header;

static int probe(const unsigned char *buf, size_t len)
{
    return len >= 11 && memcmp(buf, "\\*File list", 11) == 0;
}

/* The header's lines up to "\*File list end"; a section's line has key "*Name" and no value. */
static int parse_header(const unsigned char *buf, size_t len, header *h, ljgap__files_err *err)
{
    size_t p = 0;
    int section = -1;
    h->n = 0;
    if (!(h->l = malloc(MAX_LINES * sizeof *h->l))) return LJGAP_FILES_NOMEM;
    while (p < len) {
        const char *s = (const char *)buf + p;
        const char *nl = memchr(s, '\n', len - p);
        size_t n = nl ? (size_t)(nl - s) : len - p;
        size_t at = p;
        p += n + (nl != NULL);
        while (n && (s[n - 1] == '\r' || s[n - 1] == ' ' || s[n - 1] == 0x1a))
            n--;
        if (n == 0) continue;
        if (s[0] != '\\')
            return ljgap__files_fail(err, NAME, (long)at, NULL,
                                    "a header line does not start with a backslash");
        if (n < 2) continue; /* a lone backslash says nothing */
        if (n >= 15 && memcmp(s, "\\*File list end", 15) == 0) return 0;
        if (h->n >= MAX_LINES)
            return ljgap__files_fail(err, NAME, (long)at, NULL, "more than %d header lines",
                                    MAX_LINES);
        line *L = &h->l[h->n];
        L->key = s + 1;
        L->where = at;
        /* "\@2:Z scale: V ...": the key ends at the first ": " (or a ':' ending the line) */
        const char *colon = NULL;
        for (size_t i = 1; i < n && !colon; i++)
            if (s[i] == ':' && (i + 1 == n || s[i + 1] == ' ')) colon = s + i;
        if (s[1] == '*') {
            L->klen = n - 1, L->val = s + n, L->vlen = 0;
            section = h->n;
        } else if (colon) {
            L->klen = (size_t)(colon - s) - 1;
            L->val = colon + 1;
            L->vlen = n - (size_t)(colon - s) - 1;
            while (L->vlen && *L->val == ' ')
                L->val++, L->vlen--;
        } else {
            L->klen = n - 1, L->val = s + n, L->vlen = 0;
        }
        L->section = section;
        h->n++;
    }
    return ljgap__files_fail(err, NAME, (long)len, NULL,
                            "the header ends before its last line \\*File list end (truncated)");
}

/* Does the key (without a leading "@N:") equal name, case-insensitively? */
static int key_is(const line *L, const char *name)
{
    const char *k = L->key;
    size_t n = L->klen, m = strlen(name);
    if (n > 3 && k[0] == '@' && k[1] >= '0' && k[1] <= '9' && k[2] == ':') k += 3, n -= 3;
    return n == m && strncasecmp(k, name, m) == 0;
}

static int is_section(const header *h, int i, const char *name)
{
    return i >= 0 && h->l[i].key[0] == '*' && h->l[i].klen - 1 == strlen(name) &&
           strncasecmp(h->l[i].key + 1, name, h->l[i].klen - 1) == 0;
}

/* The value of key in section sec (-2: any section) as a string, or NULL. */
static const line *find(const header *h, int sec, const char *key)
{
    for (int i = 0; i < h->n; i++)
        if ((sec == -2 || h->l[i].section == sec) && h->l[i].key[0] != '*' && key_is(&h->l[i], key))
            return &h->l[i];
    return NULL;
}

static void value(const line *L, char *out, size_t size)
{
    size_t n = L->vlen < size - 1 ? L->vlen : size - 1;
    memcpy(out, L->val, n);
    out[n] = '\0';
}

/* A whole number at key in section sec, or -1 (absent, negative or absurd). */
static long long number(const header *h, int sec, const char *key)
{
    const line *L = find(h, sec, key);
    char v[64], *end;
    if (!L) return -1;
    value(L, v, sizeof v);
    long long x = strtoll(v, &end, 10);
    /* beyond 2^48 (256 TiB) no offset, length or count is real: as absent, so no sum of them
     * overflows */
    return end != v && x >= 0 && x <= (1LL << 48) ? x : -1;
}

/* "\@Sens. Zsens: V 18.3 nm/V": the factor 18.3 and the unit nm (hard unit V); 0 when bad. */
static double sensitivity(const header *h, const char *quantity, char *unit, size_t usize,
                          const char *hard_unit)
{
    char want[80], v[128], u[40] = "";
    double x;
    snprintf(want, sizeof want, "@%s", quantity);
    const line *L = find(h, -2, want);
    if (!L) return 0;
    value(L, v, sizeof v);
    if (sscanf(v, "V %lf %39s", &x, u) < 1 || !isfinite(x)) return 0;
    char *slash = strchr(u, '/');
    if (slash) {
        *slash = '\0';
        if (strcmp(slash + 1, hard_unit) != 0) return 0;
    }
    snprintf(unit, usize, "%s", u[0] ? u : hard_unit);
    return x;
}

/* "02:44:18 PM Fri Sep 25 2009" as ISO 8601 (unchanged text when not that form). */
static void iso_date(const char *v, char *out, size_t size)
{
    static const char *const months[] = {"Jan", "Feb", "Mar", "Apr", "May", "Jun",
                                         "Jul", "Aug", "Sep", "Oct", "Nov", "Dec"};
    int H, M, S, d, y;
    char ap[4], wd[8], mon[8];
    if (sscanf(v, "%d:%d:%d %3s %7s %7s %d %d", &H, &M, &S, ap, wd, mon, &d, &y) == 8)
        for (int m = 0; m < 12; m++)
            if (strcasecmp(mon, months[m]) == 0 && H >= 0 && H <= 12 && M >= 0 && M < 60 &&
                S >= 0 && S < 61 && d >= 1 && d <= 31 && y > 1900 && y < 10000) {
                if (strcasecmp(ap, "PM") == 0 && H < 12) H += 12;
                if (strcasecmp(ap, "AM") == 0 && H == 12) H = 0;
                snprintf(out, size, "%04d-%02d-%02dT%02d:%02d:%02d", y, m + 1, d, H, M, S);
                return;
            }
    ljgap__files_text(out, size, v, strlen(v));
}

/* The title of image section sec: the quoted name of "Image Data", else its bracket. */
static void image_title(const header *h, int sec, char *out, size_t size)
{
    const line *L = find(h, sec, "Image Data");
    char v[160];
    if (!L) {
        snprintf(out, size, "image %d", sec);
        return;
    }
    value(L, v, sizeof v);
    char *q = strchr(v, '"'), *b = strchr(v, '[');
    if (q && strchr(q + 1, '"')) {
        *strchr(q + 1, '"') = '\0';
        ljgap__files_text(out, size, q + 1, strlen(q + 1));
    } else if (b && strchr(b + 1, ']')) {
        *strchr(b + 1, ']') = '\0';
        ljgap__files_text(out, size, b + 1, strlen(b + 1));
    } else {
        ljgap__files_text(out, size, v, strlen(v));
    }
}

/* The Z scale of image section sec: the factor from a raw integer to the channel's unit. */
static int z_scale(const header *h, int sec, int bpp, ljgap__files_map *map, double *q,
                   ljgap__files_err *err)
{
    const line *L = find(h, sec, "Z scale");
    char v[200], quantity[80] = "", hard_unit[16] = "", unit[40];
    double hard = NAN, lsb = NAN;
    if (!L) return ljgap__files_fail(err, NAME, -1, NULL, "an image without its \\@2:Z scale");
    value(L, v, sizeof v);
    char *p = v;
    if (*p == 'V' && p[1] == ' ') p += 2;
    char *b = strchr(p, '['), *e = b ? strchr(b, ']') : NULL;
    if (b && e) {
        *e = '\0';
        snprintf(quantity, sizeof quantity, "%s", b + 1);
        p = e + 1;
    }
    char *o = strchr(p, '('), *c = o ? strchr(o, ')') : NULL;
    if (o && c) {
        *c = '\0';
        lsb = strtod(o + 1, NULL);
        p = c + 1;
    }
    if (sscanf(p, "%lf %15s", &hard, hard_unit) < 2) {
        if (!isfinite(lsb))
            return ljgap__files_fail(err, NAME, (long)L->where, NULL,
                                    "the Z scale \"%.60s\" has no value", v);
        hard = lsb * 65536;
        snprintf(hard_unit, sizeof hard_unit, "V");
    }
    hard /= 65536;
    if (bpp == 4) hard /= 65536;
    double soft = 1;
    snprintf(unit, sizeof unit, "%s", hard_unit);
    if (quantity[0] && !(soft = sensitivity(h, quantity, unit, sizeof unit, hard_unit)))
        return ljgap__files_fail(err, NAME, (long)L->where, NULL,
                                "the Z scale names the sensitivity [%.40s], which the header "
                                "does not give as V <number> <unit>/%s",
                                quantity, hard_unit);
    if (!isfinite(hard) || !isfinite(soft))
        return ljgap__files_fail(err, NAME, (long)L->where, NULL, "the Z scale is not a number");
    double to_m = ljgap__files_unit_scale(unit);
    ljgap__files_text(map->z_unit, sizeof map->z_unit, unit, strlen(unit));
    *q = hard * soft * (to_m > 0 ? to_m : 1);
    if (!isfinite(*q * 2147483648.0))
        return ljgap__files_fail(err, NAME, (long)L->where, NULL,
                                "the Z scale times its sensitivity, %g, overflows", *q);
    return 0;
}

/* "\Scan Size: 500 500 nm" (or one number: square pixels) in metres. */
static void scan_size(const header *h, int sec, ljgap__files_map *map)
{
    const line *L = find(h, sec, "Scan Size");
    char v[100], u1[24] = "", u2[24] = "";
    double x = 0, y = 0;
    if (!L && !(L = find(h, -2, "Scan Size"))) return;
    value(L, v, sizeof v);
    int n = sscanf(v, "%lf %23s %23s", &x, u1, u2);
    if (n >= 2 && sscanf(u1, "%lf", &y) == 1 && n == 3) {
        snprintf(u1, sizeof u1, "%s", u2);
    } else {
        y = x * (double)map->ny / (double)map->nx;
    }
    double s = ljgap__files_unit_scale(u1);
    if (s > 0 && isfinite(x) && isfinite(y) && x > 0 && y > 0)
        map->size_x = x * s, map->size_y = y * s;
}

static int read_nanoscope(const unsigned char *buf, size_t len, const char *channel,
                          ljgap__files_map *map, ljgap__files_err *err)
{
    header h = {0};
    int images[LJGAP_FILES_MAX_CHANNELS], n_img = 0, st, pick;
    const line *L;
    char v[LJGAP_FILES_TEXT];
    if ((st = parse_header(buf, len, &h, err))) goto end;
    for (int i = 0; i < h.n; i++)
        if (is_section(&h, i, "Ciao image list") && n_img < LJGAP_FILES_MAX_CHANNELS) {
            images[n_img++] = i;
            image_title(&h, i, v, sizeof v);
            ljgap__files_add_channel(map, v);
        }
    if (!n_img) {
        st =
            ljgap__files_fail(err, NAME, -1, NULL, "the header lists no image (\\*Ciao image list)");
        goto end;
    }
    /* a file cut short is bad even where it cuts a channel not asked for */
    for (int i = 0; i < n_img; i++) {
        long long o = number(&h, images[i], "Data offset"), w = number(&h, images[i], "Samps/line"),
                  r = number(&h, images[i], "Number of lines"),
                  p = number(&h, images[i], "Bytes/pixel");
        if (o >= 0 && w > 0 && r > 0 && w <= 65536 && r <= 65536 &&
            (unsigned long long)o + (unsigned long long)(w * r * (p == 4 ? 4 : 2)) > len) {
            st = ljgap__files_fail(err, NAME, (long)len, NULL,
                                  "image %d \"%s\" ends at byte %lld, the file has %zu (truncated)",
                                  i, map->channels[i], o + w * r * (p == 4 ? 4 : 2), len);
            goto end;
        }
    }
    if ((pick = ljgap__files_channel_pick(map, channel, err)) < 0) {
        st = LJGAP_FILES_CHANNEL;
        goto end;
    }
    map->channel_index = pick;
    snprintf(map->channel, sizeof map->channel, "%s", map->channels[pick]);
    int sec = images[pick];
    long long off = number(&h, sec, "Data offset"), dlen = number(&h, sec, "Data length"),
              bpp = number(&h, sec, "Bytes/pixel"), nx = number(&h, sec, "Samps/line"),
              ny = number(&h, sec, "Number of lines");
    if (off < 0 || dlen < 0 || nx <= 0 || ny <= 0) {
        st = ljgap__files_fail(err, NAME, (long)h.l[sec].where, NULL,
                              "image \"%s\" lacks its Data offset, Data length, Samps/line or "
                              "Number of lines",
                              map->channel);
        goto end;
    }
    if (bpp < 0) bpp = 2;
    if (bpp != 2 && bpp != 4) {
        st = ljgap__files_fail(err, NAME, (long)h.l[sec].where, NULL,
                              "%lld bytes a pixel: only 2 and 4 are read", bpp);
        goto end;
    }
    if (nx > 65536 || ny > 65536 || nx * ny * bpp > dlen) {
        st = ljgap__files_fail(err, NAME, (long)h.l[sec].where, NULL,
                              "%lld x %lld pixels of %lld bytes do not fit the Data length %lld",
                              nx, ny, bpp, dlen);
        goto end;
    }
    if ((st = ljgap__files_alloc(map, (size_t)nx, (size_t)ny, err))) goto end;
    double q = 1;
    if ((st = z_scale(&h, sec, (int)bpp, map, &q, err))) goto end;
    scan_size(&h, sec, map);
    ljgap__bytes b;
    ljgap__bytes_init(&b, buf, len);
    size_t need = (size_t)(nx * ny * bpp);
    if (!ljgap__bytes_at(&b, (size_t)off, need)) {
        st = ljgap__files_fail(err, NAME, (long)len, NULL,
                              "image \"%s\" needs bytes %lld to %lld, the file has %zu (truncated)",
                              map->channel, off, off + (long long)need, len);
        goto end;
    }
    ljgap__bytes_seek(&b, (size_t)off);
    for (long long j = 0; j < ny; j++) {
        double *row = map->z + (size_t)(ny - 1 - j) * (size_t)nx;
        for (long long i = 0; i < nx; i++)
            row[i] =
                q * (bpp == 2 ? (double)ljgap__bytes_i16(&b, 0) : (double)ljgap__bytes_i32(&b, 0));
    }
    if ((L = find(&h, -2, "Date"))) {
        value(L, v, sizeof v);
        iso_date(v, map->acquired, sizeof map->acquired);
    }
    if ((L = find(&h, -2, "Microscope")) || (L = find(&h, -2, "Description"))) {
        value(L, v, sizeof v);
        snprintf(map->instrument, sizeof map->instrument, "Bruker ");
        ljgap__files_text(map->instrument + 7, sizeof map->instrument - 7, v, strlen(v));
    }
end:
    free(h.l);
    return st;
}

const ljgap__files_format ljgap__files_nanoscope = {NAME, ".spm .000 .001 .di", NULL, probe,
                                                  read_nanoscope};
