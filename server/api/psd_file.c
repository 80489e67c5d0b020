/* psd_file.c -- POST /v1/psd with an instrument file as the body (issue 28).
 *
 * The body is a file of one of the formats server/files/ reads (application/octet-stream or
 * the format's own media type), recognised by its content (the query's format= forces one);
 * channel= picks a channel by index or title (default: the height channel). The file gives
 * the grid, the physical size and the height unit; the rest of the request is the text
 * upload's query (topo_text.c: detrend, periodic, tip_radius, resolution, fit band,
 * material), validated by the same code with the same pointers. dx, dy: the file's size over
 * its grid; given in the query only when the file states no size (a dx beside a file that
 * states its size is refused at /topography/dx: two spacings for one map). periodic and
 * tip_radius: the query's, else the file's where it stores them (a stored tip radius so
 * feeds the reliable band).
 *
 * Missing points (NaN, a mask, a "no data" value): the PSD is that of the largest complete
 * rectangle of the map (files.h: ljgap_files_largest_rect), which is neither padded nor
 * interpolated, so the periodogram and its error statistics stay those of a complete map;
 * source.missing says how many points were missing and which rectangle was used, and a
 * warning says it too. A cropped map is not periodic.
 *
 * Problems: 415 unsupported-media-type listing the formats read (no reader recognises the
 * bytes, or format= names none), 422 bad-file with the format and the byte offset or member
 * (a recognised file cut short or corrupt), 422 validation at /channel (no such channel, or a
 * channel that is no height), 413 content-too-large (a map over the server's cap of points).
 */
#include "answer.h"
#include "clock.h"
#include "files.h"
#include "handler.h"
#include "problems.h"
#include "topo_text.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define HEIGHT_MAX 1e3 /* |height| in m, as request_topo.c's */

/* A problem with the format, offset and member of a bad file (problems.c's row for slug). */
static void file_problem(ljgap_reply *out, const char *slug, const char *detail,
                         const ljgap_files_err *e)
{
    const ljgap_problem_doc *k = ljgap_problem_find(slug);
    cJSON *p = cJSON_CreateObject();
    char type[80];
    snprintf(type, sizeof type, LJGAP_PROBLEM_BASE "%s", slug);
    if (!k || !p || !cJSON_AddStringToObject(p, "type", type) ||
        !cJSON_AddStringToObject(p, "title", k->title) ||
        !cJSON_AddNumberToObject(p, "status", k->status) ||
        !cJSON_AddStringToObject(p, "detail", detail) ||
        !cJSON_AddItemToObject(p, "errors", cJSON_CreateArray()) ||
        (e && e->format && !cJSON_AddStringToObject(p, "format", e->format)) ||
        (e && e->offset >= 0 && !cJSON_AddNumberToObject(p, "offset", (double)e->offset)) ||
        (e && e->member[0] && !cJSON_AddStringToObject(p, "member", e->member))) {
        cJSON_Delete(p);
        ljgap_ans_oom(out);
        return;
    }
    ljgap_ans_reply_json(out, k->status, CT_PROBLEM, p);
    cJSON_Delete(p);
}

/* A 422 validation problem with one error at ptr. */
static void one_error(ljgap_reply *out, const char *ptr, const char *detail)
{
    ljgap_verr ve = {cJSON_CreateArray(), 0, 0};
    if (!ve.errors) {
        ljgap_ans_oom(out);
        return;
    }
    ljgap_verr_add(&ve, ptr, "%s", detail);
    ljgap_ans_invalid(out, &ve);
    cJSON_Delete(ve.errors);
}

/* The answer to a failed read (st: files.h's status). */
static void read_failed(ljgap_reply *out, int st, const ljgap_files_err *e)
{
    char detail[900], names[600];
    switch (st) {
    case LJGAP_FILES_UNKNOWN:
        ljgap_files_names(names, sizeof names);
        if (strncmp(e->msg, "no format", 9) == 0)
            snprintf(detail, sizeof detail, "%s", e->msg);
        else
            snprintf(detail, sizeof detail,
                     "the body is no file of a format read here (recognised by its content): "
                     "%s; a height matrix as text goes as text/plain",
                     names);
        file_problem(out, "unsupported-media-type", detail, NULL);
        return;
    case LJGAP_FILES_BAD:
        if (e->offset >= 0)
            snprintf(detail, sizeof detail, "a %s file that cannot be read, at byte %ld: %s",
                     e->format ? e->format : "?", e->offset, e->msg);
        else
            snprintf(detail, sizeof detail, "a %s file that cannot be read%s%s: %s",
                     e->format ? e->format : "?", e->member[0] ? ", member " : "", e->member,
                     e->msg);
        file_problem(out, "bad-file", detail, e);
        return;
    case LJGAP_FILES_CHANNEL:
        one_error(out, "/channel", e->msg);
        return;
    case LJGAP_FILES_TOOBIG:
        snprintf(detail, sizeof detail, "the %s file's map is too large: %s",
                 e->format ? e->format : "?", e->msg);
        file_problem(out, "content-too-large", detail, NULL);
        return;
    default:
        ljgap_ans_oom(out);
    }
}

/* "format" and "channel" out of the query (kept in *format, *channel); the rest into rest. */
static size_t split_params(const ljgap_param *p, size_t np, ljgap_param *rest,
                           const char **format, const char **channel)
{
    size_t k = 0;
    *format = *channel = NULL;
    for (size_t i = 0; i < np; i++) {
        const char *name = p[i].name ? p[i].name : "";
        if (strcmp(name, "format") == 0 && !*format)
            *format = p[i].value ? p[i].value : "";
        else if (strcmp(name, "channel") == 0 && !*channel)
            *channel = p[i].value ? p[i].value : "";
        else
            rest[k++] = p[i];
    }
    return k;
}

/* The answer's "source": what the file said, and which points were used. */
static cJSON *source_json(const ljgap_files_map *m, size_t x0, size_t y0, size_t w, size_t h)
{
    cJSON *s = cJSON_CreateObject(), *ch, *miss, *used;
    if (!s || !cJSON_AddStringToObject(s, "format", m->format) ||
        !cJSON_AddStringToObject(s, "channel", m->channel) ||
        !(ch = cJSON_AddArrayToObject(s, "channels")))
        goto oom;
    for (int i = 0; i < m->n_channels; i++)
        if (!cJSON_AddItemToArray(ch, cJSON_CreateString(m->channels[i]))) goto oom;
    cJSON *size = m->size_x > 0 ? cJSON_CreateArray() : cJSON_CreateNull();
    if (!cJSON_AddItemToObject(s, "size", size)) goto oom;
    if (m->size_x > 0 && (!cJSON_AddItemToArray(size, cJSON_CreateNumber(m->size_x)) ||
                          !cJSON_AddItemToArray(size, cJSON_CreateNumber(m->size_y))))
        goto oom;
    if (!(m->instrument[0] ? cJSON_AddStringToObject(s, "instrument", m->instrument)
                           : cJSON_AddNullToObject(s, "instrument")) ||
        !(m->acquired[0] ? cJSON_AddStringToObject(s, "acquired", m->acquired)
                         : cJSON_AddNullToObject(s, "acquired")) ||
        !(m->tip_radius > 0 ? cJSON_AddNumberToObject(s, "tip_radius", m->tip_radius)
                            : cJSON_AddNullToObject(s, "tip_radius")) ||
        !cJSON_AddNumberToObject(s, "nx", (double)m->nx) ||
        !cJSON_AddNumberToObject(s, "ny", (double)m->ny) ||
        !(m->z_unit[0] ? cJSON_AddStringToObject(s, "z_unit", m->z_unit)
                       : cJSON_AddNullToObject(s, "z_unit")) ||
        !(miss = cJSON_AddObjectToObject(s, "missing")) ||
        !cJSON_AddNumberToObject(miss, "count", (double)m->missing) ||
        !(used = cJSON_AddObjectToObject(miss, "used")) ||
        !cJSON_AddNumberToObject(used, "x0", (double)x0) ||
        !cJSON_AddNumberToObject(used, "y0", (double)y0) ||
        !cJSON_AddNumberToObject(used, "nx", (double)w) ||
        !cJSON_AddNumberToObject(used, "ny", (double)h))
        goto oom;
    return s;
oom:
    cJSON_Delete(s);
    return NULL;
}

/* Sets topography[name] = x unless the query gave it. */
static int default_num(cJSON *topo, const char *name, double x)
{
    if (cJSON_GetObjectItemCaseSensitive(topo, name)) return 1;
    return cJSON_AddNumberToObject(topo, name, x) != NULL;
}

/* The file's spacings and stored options into the query's topography object; a problem
 * (pointer, detail) when the query's dx, dy clash with the file's size or are missing. */
static const char *file_defaults(cJSON *query, const ljgap_files_map *m, size_t w, size_t h,
                                 char *detail, size_t size)
{
    cJSON *topo = cJSON_GetObjectItemCaseSensitive(query, "topography");
    int has_dx = cJSON_GetObjectItemCaseSensitive(topo, "dx") != NULL;
    int has_dy = cJSON_GetObjectItemCaseSensitive(topo, "dy") != NULL;
    if (m->size_x > 0) {
        double dx = m->size_x / (double)m->nx, dy = m->ny > 1 ? m->size_y / (double)m->ny : dx;
        if (has_dx || has_dy) {
            snprintf(detail, size,
                     "the %s file states its size, %g x %g m over %zu x %zu points (dx = %g m, "
                     "dy = %g m): leave out %s",
                     m->format, m->size_x, m->size_y, m->nx, m->ny, dx, dy,
                     has_dx ? "dx" : "dy");
            return has_dx ? "/topography/dx" : "/topography/dy";
        }
        if (!default_num(topo, "dx", dx) || !default_num(topo, "dy", dy)) return "";
    } else if (!has_dx) {
        snprintf(detail, size,
                 "the %s file does not state its physical size: give the spacing dx (m) in "
                 "the query (and dy when it differs)",
                 m->format);
        return "/topography/dx";
    }
    if (m->tip_radius > 0 && !default_num(topo, "tip_radius", m->tip_radius)) return "";
    /* a cropped map is not one period of anything */
    if (m->periodic && w == m->nx && h == m->ny &&
        !cJSON_GetObjectItemCaseSensitive(topo, "periodic") &&
        !cJSON_AddBoolToObject(topo, "periodic", 1))
        return "";
    return NULL;
}

/* The heights of the rectangle (x0, y0, w, h) of the map, each within ±HEIGHT_MAX; NULL with
 * a detail when one is not (else out of memory). */
static double *crop(ljgap_files_map *m, size_t x0, size_t y0, size_t w, size_t h, char *detail,
                    size_t size)
{
    /* the whole map: its heights are taken over, not copied */
    double *z = w == m->nx && h == m->ny ? m->z : malloc(w * h * sizeof *z);
    if (!z) return NULL;
    for (size_t j = 0; j < h; j++)
        for (size_t i = 0; i < w; i++) {
            double v = m->z[(y0 + j) * m->nx + x0 + i];
            if (!(fabs(v) <= HEIGHT_MAX)) {
                snprintf(detail, size,
                         "the height at row %zu, column %zu of the file is %g m, outside "
                         "[-1e3, 1e3] m (is its unit right?)",
                         y0 + j, x0 + i, v);
                if (z != m->z) free(z);
                return NULL;
            }
            z[j * w + i] = v;
        }
    if (z == m->z) m->z = NULL; /* now the request's */
    return z;
}

void ljgap_handle_file(const char *endpoint, const ljgap_param *params, size_t nparams,
                       const unsigned char *body, size_t len, const ljgap_call *call,
                       ljgap_reply *out)
{
    double t0 = ljgap_clock_now();
    const ljgap_limits *lim = ljgap_handler_limits();
    ljgap_param *rest = NULL;
    const char *format, *channel, *ptr;
    ljgap_files_map m;
    ljgap_files_err e;
    ljgap_topo_spec heights = {0};
    ljgap_verr ve = {0};
    cJSON *query = NULL;
    char detail[700] = "";
    size_t x0 = 0, y0 = 0, w, h;
    job j;
    int form, st;
    memset(&j, 0, sizeof j);
    memset(out, 0, sizeof *out);
    memset(&m, 0, sizeof m);
    if (!ljgap_handler_has_text(endpoint)) {
        ljgap_ans_problem(out, P_NOT_FOUND, "only psd takes an instrument file", NULL);
        return;
    }
    if ((form = ljgap_ans_negotiate(call ? call->accept : NULL, 0, out)) < 0) return;
    if (!(rest = malloc((nparams ? nparams : 1) * sizeof *rest)) ||
        !(ve.errors = cJSON_CreateArray())) {
        ljgap_ans_oom(out);
        goto end;
    }
    size_t nrest = split_params(params, nparams, rest, &format, &channel);
    /* an unknown or repeated query parameter is refused before the file is read */
    if (!(query = ljgap_topo_params_json(rest, nrest, &ve))) {
        ljgap_ans_oom(out);
        goto end;
    }
    if (ve.n) {
        ljgap_ans_invalid(out, &ve);
        goto end;
    }
    if ((st = ljgap_files_read(body, len, format, channel, &m, &e))) {
        read_failed(out, st, &e);
        goto end;
    }
    double unit = m.z_unit[0] ? ljgap_files_unit_scale(m.z_unit) : 1;
    if (!(unit > 0)) {
        snprintf(detail, sizeof detail,
                 "channel %d \"%s\" of the %s file is in %s, not a length: choose a height "
                 "channel (channel=INDEX or TITLE)",
                 m.channel_index, m.channel, m.format, m.z_unit);
        one_error(out, "/channel", detail);
        goto end;
    }
    if (!m.z_unit[0])
        ljgap_warn(&j.rq.warn, "the %s file states no height unit: its heights are taken as m",
                   m.format);
    w = m.nx, h = m.ny;
    if (m.missing && ljgap_files_largest_rect(&m, &x0, &y0, &w, &h)) {
        ljgap_ans_oom(out);
        goto end;
    }
    if ((size_t)w * h > ljgap_limits_topo_cap(lim)) {
        snprintf(detail, sizeof detail,
                 "the map has %zu x %zu points, more than the %zu this server takes", w, h,
                 ljgap_limits_topo_cap(lim));
        file_problem(out, "content-too-large", detail, NULL);
        goto end;
    }
    if ((ptr = file_defaults(query, &m, w, h, detail, sizeof detail))) {
        if (!*ptr)
            ljgap_ans_oom(out);
        else
            one_error(out, ptr, detail);
        goto end;
    }
    if (!(heights.h = crop(&m, x0, y0, w, h, detail, sizeof detail))) {
        if (detail[0])
            one_error(out, "/topography/heights", detail);
        else
            ljgap_ans_oom(out);
        goto end;
    }
    heights.nx = w, heights.ny = h;
    /* parse_text starts a fresh request: the warnings so far go in after it */
    ljgap_warnings early = j.rq.warn;
    ljgap_request_parse_text(query, &heights, lim, &j.rq, &ve);
    if (ve.n || ve.oom) {
        ljgap_ans_invalid(out, &ve);
        goto end;
    }
    for (int i = 0; i < early.n; i++)
        ljgap_warn(&j.rq.warn, "%s", early.msg[i]);
    if (m.missing)
        ljgap_warn(&j.rq.warn,
                   "%zu of the %zu points of the map are missing: the PSD is that of the largest "
                   "complete rectangle, %zu x %zu points from column %zu, row %zu",
                   m.missing, m.nx * m.ny, w, h, x0, y0);
    if (!(j.rq.source = source_json(&m, x0, y0, w, h))) {
        ljgap_ans_oom(out);
        goto end;
    }
    ljgap_files_map_free(&m);
    ljgap_ans_run_job(&j, ljgap_run_psd, endpoint, form, call, t0, out);
end:
    ljgap_files_map_free(&m);
    free(heights.h);
    free(rest);
    cJSON_Delete(query);
    cJSON_Delete(ve.errors);
    ljgap_request_free(&j.rq);
}
