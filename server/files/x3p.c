/* x3p.c -- ISO 25178-72 / ISO 5436-2 XML "X3P" files (the openGPS container).
 *
 * An X3P file is a zip archive (zip.c) with main.xml, the description, and the points, in a
 * binary member (Record3/DataLink/PointDataLink, usually bindata/data.bin) or inline as
 * Record3/DataList/Datum elements. main.xml, read with the few rules below (no DTD, no
 * namespaces beyond an element's prefix, the entities &amp; &lt; &gt; &quot; &apos;):
 *   Record1/FeatureType    SUR (a surface) or PRF (a profile); PCL (point clouds) is not read
 *   Record1/Axes/CX, CY    AxisType I (incremental: Increment, the spacing in metres, Offset);
 *                          A (absolute coordinates, a point cloud) is not read
 *   Record1/Axes/CZ        DataType I (int16), L (int32), F (float32), D (float64), little
 *                          endian; for the integer types z = Offset + Increment * value
 *   Record2                Date (ISO 8601), Instrument/Manufacturer and Model, ProbingSystem
 *   Record3                MatrixDimension SizeX, SizeY, SizeZ (layers: one channel each);
 *                          DataLink/PointDataLink, DataLink/ValidPointsLink (one bit a point,
 *                          least significant bit first, 1 = valid; float data also mark
 *                          invalid points as NaN)
 * Points run x fastest, then y, then the layer. Units are metres throughout. The md5 checksums
 * are not checked (zip's CRC-32 is); an error in a member names it in err->member.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "bytes.h"
#include "files_util.h"
#include "zip.h"

#define X3P "x3p"
#define XML_MAX (16u << 20) /* main.xml up to 16 MiB (an inline DataList) */

typedef struct {
    const char *s; /* the text */
    size_t n;      /* its length */
} span;

static int x3p_probe(const unsigned char *buf, size_t len)
{
    if (len < 30 || memcmp(buf, "PK\x03\x04", 4)) return 0;
    return memmem(buf, len, "main.xml", 8) != NULL;
}

/* The first element named tag (any prefix) inside in: its content (empty for <tag/>). */
static int xml_find(span in, const char *tag, span *out)
{
    size_t tl = strlen(tag);
    for (size_t i = 0; i + 1 < in.n; i++) {
        if (in.s[i] != '<' || in.s[i + 1] == '/' || in.s[i + 1] == '?' || in.s[i + 1] == '!')
            continue;
        size_t a = i + 1, e = a;
        while (e < in.n && !strchr(" \t\r\n/>", in.s[e]))
            e++;
        size_t nl = e - a; /* the full name, prefix included */
        const char *nm = in.s + a;
        int match = nl == tl ? !memcmp(nm, tag, tl)
                             : nl > tl && nm[nl - tl - 1] == ':' && !memcmp(nm + nl - tl, tag, tl);
        if (!match) continue;
        size_t g = e;
        while (g < in.n && in.s[g] != '>')
            g++;
        if (g >= in.n) return 0;
        if (in.s[g - 1] == '/') {
            out->s = in.s + g + 1, out->n = 0;
            return 1;
        }
        /* the closing tag </name> */
        for (size_t k = g + 1; k + 3 + nl <= in.n; k++)
            if (in.s[k] == '<' && in.s[k + 1] == '/' && !memcmp(in.s + k + 2, nm, nl) &&
                in.s[k + 2 + nl] == '>') {
                out->s = in.s + g + 1, out->n = k - (g + 1);
                return 1;
            }
        return 0;
    }
    return 0;
}

/* The text of the element at path ("Record1/Axes/CZ/DataType"), trimmed and unescaped. */
static int xml_text(span doc, const char *path, char *out, size_t size)
{
    char part[64];
    span cur = doc;
    out[0] = 0;
    while (*path) {
        size_t k = strcspn(path, "/");
        if (k >= sizeof part) return 0;
        memcpy(part, path, k), part[k] = 0;
        if (!xml_find(cur, part, &cur)) return 0;
        path += k + (path[k] == '/');
    }
    size_t a = 0, e = cur.n, o = 0;
    while (a < e && strchr(" \t\r\n", cur.s[a]))
        a++;
    while (e > a && strchr(" \t\r\n", cur.s[e - 1]))
        e--;
    static const struct {
        const char *ent;
        char c;
    } ents[] = {{"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
    for (size_t i = a; i < e && o + 1 < size; i++) {
        char c = cur.s[i];
        if (c == '&')
            for (size_t j = 0; j < 5; j++) {
                size_t l = strlen(ents[j].ent);
                if (i + l <= e && !memcmp(cur.s + i, ents[j].ent, l)) {
                    c = ents[j].c, i += l - 1;
                    break;
                }
            }
        out[o++] = (c == '\n' || c == '\r' || c == '\t') ? ' ' : c;
    }
    out[o] = 0;
    return 1;
}

/* A number at path: 1 with *v, 0 when absent (v untouched), -1 when not a finite number. */
static int xml_num(span doc, const char *path, double *v)
{
    char t[64], *end;
    if (!xml_text(doc, path, t, sizeof t)) return 0;
    double d = strtod(t, &end);
    if (end == t || *end || !isfinite(d)) return -1;
    *v = d;
    return 1;
}

static int x3p_fail(ljgap__files_err *err, const char *fmt, const char *what)
{
    return ljgap__files_fail(err, X3P, -1, "main.xml", fmt, what);
}

static int x3p_read(const unsigned char *buf, size_t len, const char *channel, ljgap__files_map *map,
                    ljgap__files_err *err)
{
    ljgap__files_map_init(map, X3P);
    unsigned char *xml = NULL, *data = NULL, *valid = NULL;
    size_t xlen = 0, dlen = 0, vlen = 0;
    int rc = ljgap__zip_extract(buf, len, "main.xml", XML_MAX, &xml, &xlen, X3P, err);
    if (rc) return rc;
    span doc = {(const char *)xml, xlen};
    char t[LJGAP_FILES_TEXT], t2[LJGAP_FILES_TEXT];

    if (!xml_find(doc, "ISO5436_2", &doc)) {
        rc = x3p_fail(err, "no %s root element", "ISO5436_2");
        goto done;
    }
    xml_text(doc, "Record1/FeatureType", t, sizeof t);
    if (strcmp(t, "SUR") && strcmp(t, "PRF")) {
        rc = x3p_fail(err, "feature type \"%s\": SUR (surfaces) and PRF (profiles) are read", t);
        goto done;
    }
    int profile = !strcmp(t, "PRF");
    const char *axes[2] = {"Record1/Axes/CX/", "Record1/Axes/CY/"};
    double inc[2] = {0, 0};
    for (int a = 0; a < 2 - profile; a++) {
        char p[64];
        snprintf(p, sizeof p, "%sAxisType", axes[a]);
        xml_text(doc, p, t, sizeof t);
        if (strcmp(t, "I")) {
            rc =
                x3p_fail(err, "axis type \"%s\" for x or y: only incremental axes (I) are read", t);
            goto done;
        }
        snprintf(p, sizeof p, "%sIncrement", axes[a]);
        if (xml_num(doc, p, &inc[a]) != 1 || !(inc[a] > 0)) {
            rc = x3p_fail(err, "%s is missing or not a positive number", p);
            goto done;
        }
    }
    xml_text(doc, "Record1/Axes/CZ/DataType", t, sizeof t);
    size_t w = !strcmp(t, "I")   ? 2
               : !strcmp(t, "L") ? 4
               : !strcmp(t, "F") ? 4
               : !strcmp(t, "D") ? 8
                                 : 0;
    char dtype = t[0];
    if (!w || t[1]) {
        rc = x3p_fail(err, "z data type \"%s\": I, L, F or D are read", t);
        goto done;
    }
    double zinc = 1, zoff = 0;
    if (dtype == 'I' || dtype == 'L') {
        if (xml_num(doc, "Record1/Axes/CZ/Increment", &zinc) < 0 ||
            xml_num(doc, "Record1/Axes/CZ/Offset", &zoff) < 0) {
            rc = x3p_fail(err, "%s: not a number", "Record1/Axes/CZ/Increment or Offset");
            goto done;
        }
    }
    double sx = 0, sy = 1, sz = 1;
    if (xml_num(doc, "Record3/MatrixDimension/SizeX", &sx) != 1 ||
        (!profile && xml_num(doc, "Record3/MatrixDimension/SizeY", &sy) != 1)) {
        rc = x3p_fail(err, "%s: the grid's size is missing", "Record3/MatrixDimension");
        goto done;
    }
    if (xml_num(doc, "Record3/MatrixDimension/SizeZ", &sz) < 0) sz = 0;
    if (profile && xml_num(doc, "Record3/MatrixDimension/SizeY", &sy) != 1) sy = 1;
    if (!(sx >= 1 && sy >= 1 && sz >= 1 && sx == floor(sx) && sy == floor(sy) && sz == floor(sz) &&
          sz <= LJGAP_FILES_MAX_CHANNELS && sx <= LJGAP_FILES_MAX_POINTS &&
          sy <= LJGAP_FILES_MAX_POINTS)) {
        rc = x3p_fail(err,
                      "%s: SizeX, SizeY and SizeZ must be whole numbers >= 1 (at most 32 "
                      "layers)",
                      "Record3/MatrixDimension");
        goto done;
    }
    size_t nx = (size_t)sx, ny = (size_t)sy, nl = (size_t)sz;
    for (size_t l = 0; l < nl; l++)
        snprintf(map->channels[l], LJGAP_FILES_TEXT, nl == 1 ? "Z" : "Z layer %zu", l);
    map->n_channels = (int)nl;
    int c = ljgap__files_channel_pick(map, channel, err);
    if (c < 0) {
        rc = LJGAP_FILES_CHANNEL;
        goto done;
    }
    map->channel_index = c;
    snprintf(map->channel, sizeof map->channel, "%s", map->channels[c]);
    rc = ljgap__files_alloc_at(map, nx, ny, err, -1);
    if (rc) goto done;
    size_t n = nx * ny, first = (size_t)c * n;

    char link[256];
    if (xml_text(doc, "Record3/DataLink/PointDataLink", link, sizeof link) && link[0]) {
        /* the whole member is inflated: all its layers within the limit of one map */
        if (n * w > (size_t)LJGAP_FILES_MAX_POINTS * 8 / nl) {
            rc = ljgap__files_report(err, LJGAP_FILES_TOOBIG, X3P, -1, link,
                                     "%zu layers of %zu x %zu points exceed the limit", nl, nx, ny);
            goto done;
        }
        rc = ljgap__zip_extract(buf, len, link, n * nl * w + 64, &data, &dlen, X3P, err);
        if (rc) goto done;
        if (dlen / w < n * nl) {
            rc = ljgap__files_fail(err, X3P, -1, link,
                                   "%zu bytes of points, %zu x %zu x %zu values of %zu bytes "
                                   "stated",
                                   dlen, nx, ny, nl, w);
            goto done;
        }
        if (xml_text(doc, "Record3/DataLink/ValidPointsLink", t2, sizeof t2) && t2[0]) {
            rc = ljgap__zip_extract(buf, len, t2, n * nl / 8 + 1, &valid, &vlen, X3P, err);
            if (rc) goto done;
            if (vlen < (n * nl + 7) / 8) {
                rc = ljgap__files_fail(
                    err, X3P, -1, t2, "%zu bytes of valid-point bits for %zu points", vlen, n * nl);
                goto done;
            }
        }
        ljgap__bytes b;
        ljgap__bytes_init(&b, data, dlen);
        ljgap__bytes_seek(&b, first * w);
        for (size_t k = 0; k < n; k++) {
            double v = dtype == 'I'   ? zoff + zinc * ljgap__bytes_i16(&b, 0)
                       : dtype == 'L' ? zoff + zinc * ljgap__bytes_i32(&b, 0)
                       : dtype == 'F' ? ljgap__bytes_f32(&b, 0)
                                      : ljgap__bytes_f64(&b, 0);
            size_t q = first + k;
            if (valid && !(valid[q / 8] >> (q % 8) & 1)) v = NAN;
            ljgap__files_put(map, k, v);
        }
    } else {
        span list, item;
        if (!xml_find(doc, "Record3", &list) || !xml_find(list, "DataList", &list)) {
            rc = x3p_fail(err, "%s: neither a DataLink nor a DataList", "Record3");
            goto done;
        }
        /* inline values: one Datum a point, empty when invalid */
        size_t k = 0;
        while (k < first + n && xml_find(list, "Datum", &item)) {
            if (k >= first) {
                char v[64], *end;
                size_t a = 0, e = item.n;
                while (a < e && strchr(" \t\r\n", item.s[a]))
                    a++;
                while (e > a && strchr(" \t\r\n", item.s[e - 1]))
                    e--;
                if (e - a >= sizeof v) e = a + sizeof v - 1;
                memcpy(v, item.s + a, e - a), v[e - a] = 0;
                double d = strtod(v, &end);
                if (end == v)
                    d = NAN;
                else if (*end) {
                    rc = x3p_fail(err, "a Datum \"%s\" that is not a number", v);
                    goto done;
                }
                if (dtype == 'I' || dtype == 'L') d = zoff + zinc * d;
                ljgap__files_put(map, k - first, d);
            }
            k++;
            size_t used = (size_t)(item.s + item.n - list.s);
            list.s += used, list.n -= used;
        }
        if (k < first + n) {
            rc = x3p_fail(err, "%s holds fewer values than the grid", "Record3/DataList");
            goto done;
        }
    }
    map->size_x = inc[0] * (double)nx;
    map->size_y = profile ? inc[0] : inc[1] * (double)ny;
    snprintf(map->z_unit, sizeof map->z_unit, "m");
    xml_text(doc, "Record2/Date", map->acquired, sizeof map->acquired);
    xml_text(doc, "Record2/Instrument/Manufacturer", t, sizeof t);
    xml_text(doc, "Record2/Instrument/Model", t2, sizeof t2);
    snprintf(map->instrument, sizeof map->instrument, "%.60s%s%.60s", t, t[0] && t2[0] ? " " : "",
             t2);
done:
    free(xml), free(data), free(valid);
    return rc;
}

const ljgap__files_format ljgap__files_x3p = {
    .name = "x3p",
    .extensions = ".x3p",
    .media_type = NULL,
    .probe = x3p_probe,
    .read = x3p_read,
};
