/* psd.c -- POST /v1/psd: a measured height map's PSD as the answer (issue 15, core/topo/topo.c),
 * and an instrument file as its input (issue 28, ljgap__handle_file below).
 *
 * The runner of the psd endpoint, out of handler.c: the bins, the fit and the reliable band of
 * ljgap_topo_compute written as docs/api.md fixes them, and the psd object ready for the adhesion
 * endpoints (a table of the reliable bins, with the fitted tail when the fit stands for the
 * spectrum up to its end). With a material, the theory's domain of that band and the object
 * from its k1; the same writers serve psd/combine (combine.c) through answer.h.
 */
#include "answer.h"
#include "clock.h"
#include "files.h" /* the instrument files' readers */
#include "handler.h"
#include "ljgap_topo.h"
#include "problems.h"
#include "topo_text.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define K1_MARGIN 1.1 /* the proposed k1 keeps this factor above k0/χ, off the pole of (14) */
#define SLOPE_WARN 3  /* an rms slope above this asks whether the units are right */

/* Does the fit stand for the spectrum up to the table's end, soundly, with an exponent below
 * -2? Then the tail continues it. Up to the end: every reliable bin above the fit's band lies
 * within TAIL_BINS_SIGMA errors (and TAIL_BINS_REL) of the fitted law, so that a cutoff, a noise
 * floor or the tip's trace above the band stops the tail while a band that merely stops a bin
 * or two short of the end does not. */
#define TAIL_BINS_SIGMA 3
#define TAIL_BINS_REL 0.1
static int fit_gives_tail(const ljgap_topo_result *r)
{
    if (!r->has_fit || !r->fit.sound || !(2 * r->fit.D.value - 8 < -2)) return 0;
    for (size_t i = r->rel_first; i <= r->rel_last && i < r->n; i++) {
        if (r->k[i] <= r->fit.kmax * (1 + 1e-9)) continue;
        double law = r->fit.C.value * pow(r->k[i], 2 * r->fit.D.value - 8);
        if (!(fabs(log(r->P[i] / law)) <= TAIL_BINS_SIGMA * r->P_err[i] / r->P[i] + TAIL_BINS_REL))
            return 0;
    }
    return 1;
}

/* The psd object of a table (k, P, P_err: n knots, log-log interpolated) with the tail P ∝ k^q
 * when q is finite: /v1/psd's (put_psd_object) and /v1/psd/combine's. Its variance (with the
 * tail) into *m0 (NAN when it cannot be formed). */
void ljgap__ans_table_psd(job *j, const double *k, const double *P, const double *P_err, size_t n,
                         double q, double q_err, double *m0)
{
    cJSON *o = ljgap__ans_put(j, j->ans, "psd", cJSON_CreateObject());
    int tail = isfinite(q);
    ljgap_psd psd = {0}; /* ljgap_psd_table leaves it untouched when it refuses the table */
    *m0 = NAN;
    ljgap__ans_put(j, o, "kind", cJSON_CreateString("table"));
    ljgap__ans_nums(j, o, "k", k, n, sizeof *k, "psd.k");
    ljgap__ans_nums(j, o, "P", P, n, sizeof *P, "psd.P");
    ljgap__ans_nums(j, o, "P_err", P_err, n, sizeof *P_err, "psd.P_err");
    if (tail) {
        cJSON *to = ljgap__ans_put(j, o, "tail", cJSON_CreateObject());
        ljgap__ans_num(j, to, "exponent", q, "psd.tail", -1);
        ljgap__ans_num(j, to, "exponent_err", q_err, "psd.tail.exponent_err", -1);
    }
    if (ljgap_psd_table(&psd, k, P, n, tail, tail ? q : 0) == LJGAP_OK) *m0 = psd.m0;
    ljgap_psd_free(&psd);
}

/* The psd object for /v1/adhesion with "units":"SI": the reliable bins from k_from on as a
 * table that keeps their variance (ljgap_topo_table), with P_err and the fitted power law as
 * the tail when fit_gives_tail; the fitted power law itself from k_from when no reliable bin
 * reaches beyond it; null (and a warning) when neither can be formed. Its variance into *m0
 * (m², NAN when null). */
static void put_psd_object(job *j, const ljgap_topo_result *r, double k_from, double *m0)
{
    double q = 2 * r->fit.D.value - 8;
    int tail = fit_gives_tail(r);
    ljgap_topo_tab t;
    int st = ljgap_topo_table(r, k_from, tail ? q : NAN, &t);
    cJSON *o;
    ljgap_psd psd;
    *m0 = NAN;
    if (st == LJGAP_ENOMEM) {
        j->oom = 1;
        return;
    }
    if (st == LJGAP_OK) {
        ljgap__ans_table_psd(j, t.k, t.P, t.P_err, t.n, tail ? q : NAN, 2 * r->fit.D.err, m0);
        /* the knots' errors are correlated with their neighbours' (the table's solve): the
         * adhesion endpoints sample them with it (input_error) */
        ljgap__ans_nums(j, cJSON_GetObjectItemCaseSensitive(j->ans, "psd"), "P_corr", t.corr,
                       t.n - 1, sizeof *t.corr, "psd.P_corr");
        if (!tail)
            ljgap_warn(
                &j->rq.warn, "the psd object has no tail: %s, so the table ends at k = %g 1/m",
                !r->has_fit     ? "there is no power-law fit"
                : !r->fit.sound ? "the fit is no sound power law with 2 < D < 3"
                                : "the bins above the fit band are no power law (a cutoff, a noise "
                                  "floor or the tip's trace?) and are kept as measured",
                t.k[t.n - 1]);
    } else if (r->has_fit && r->fit.sound && q < -2) {
        o = ljgap__ans_put(j, j->ans, "psd", cJSON_CreateObject());
        ljgap__ans_put(j, o, "kind", cJSON_CreateString("power"));
        ljgap__ans_num(j, o, "D", r->fit.D.value, "psd.D", -1);
        ljgap__ans_num(j, o, "k1", k_from, "psd.k1", -1);
        ljgap__ans_num(j, o, "C", r->fit.C.value, "psd.C", -1);
        ljgap_warn(&j->rq.warn,
                   "the theory's band starts at k1 = %g 1/m, beyond the reliable bins: the psd "
                   "object is the fitted power law, extrapolated",
                   k_from);
        if (ljgap_psd_power(&psd, r->fit.D.value, k_from, INFINITY, LJGAP_LEVEL_C,
                            r->fit.C.value) == LJGAP_OK)
            *m0 = psd.m0;
    } else {
        ljgap__ans_put(j, j->ans, "psd", cJSON_CreateNull());
        ljgap_warn(&j->rq.warn,
                   "no psd object: the reliable bins above k = %g 1/m form no table (there "
                   "are none, or one carries no power) and the fit gives no sound power law "
                   "with 2 < D < 3 to extrapolate",
                   k_from);
    }
    ljgap_topo_tab_free(&t);
}

/* With a material: where the band [kf, kl] (its name: "reliable band", ...) lies against the
 * theory's k > k0/χ and the k1 it proposes (kf, or K1_MARGIN k0/χ when that is higher) into
 * d and the answer's "domain"; the caller then writes the psd object from d->k1 and ends with
 * ljgap__ans_domain_end and the object's variance. /v1/psd's and /v1/psd/combine's. */
void ljgap__ans_domain_begin(job *j, double kf, double kl, const char *band, ljgap__domain *d)
{
    const ljgap_material *m = &j->rq.mat;
    double chi = ljgap_units_chi(m);
    d->kd = ljgap_k0() / chi;
    d->kf = kf;
    d->kl = kl;
    d->band = band;
    d->k1 = fmax(kf, K1_MARGIN * d->kd);
    d->inside = kl <= d->kd ? 0 : kf > d->kd ? 1 : log(kl / d->kd) / log(kl / kf);
    d->obj = ljgap__ans_put(j, j->ans, "domain", cJSON_CreateObject());
    ljgap__ans_num(j, d->obj, "k0", d->kd, "domain.k0", -1);
    ljgap__ans_put(j, d->obj, "inside",
                  cJSON_CreateString(d->inside == 1   ? "all"
                                     : d->inside == 0 ? "none"
                                                      : "part"));
    ljgap__ans_num(j, d->obj, "fraction", d->inside, "domain.fraction", -1);
    ljgap__ans_num(j, d->obj, "k1", d->k1, "domain.k1", -1);
    ljgap__ans_num(j, d->obj, "k1_dimensionless", d->k1 * chi, "domain.k1_dimensionless", -1);
}

void ljgap__ans_domain_end(job *j, const ljgap__domain *d, double m0)
{
    if (isfinite(m0)) {
        ljgap__ans_num(j, d->obj, "h_rms", sqrt(m0), "domain.h_rms", -1);
        ljgap__ans_num(j, d->obj, "m0_dimensionless", ljgap_units_var_to_dimless(&j->rq.mat, m0),
                      "domain.m0_dimensionless", -1);
    } else {
        ljgap__ans_put(j, d->obj, "h_rms", cJSON_CreateNull());
        ljgap__ans_put(j, d->obj, "m0_dimensionless", cJSON_CreateNull());
    }
    if (d->inside < 1)
        ljgap_warn(&j->rq.warn,
                   "%s of the %s (k = %g to %g 1/m) lies below k0/χ = %g 1/m, "
                   "outside the theory's domain: the psd object starts at k1 = %g 1/m",
                   d->inside == 0 ? "all" : "part", d->band, d->kf, d->kl, d->kd, d->k1);
}

/* With a material: the domain of the reliable band and the psd object from its k1. */
static void put_domain(job *j, const ljgap_topo_result *r)
{
    ljgap__domain d;
    double m0;
    ljgap__ans_domain_begin(j, r->rel_kmin, r->k[r->rel_last], "reliable band", &d);
    put_psd_object(j, r, d.k1, &m0);
    ljgap__ans_domain_end(j, &d, m0);
}

int ljgap__run_psd(job *j)
{
    ljgap__topo_spec *t = &j->rq.topo;
    ljgap_topo_grid g = {t->nx, t->ny, t->dx, t->dy, t->periodic};
    ljgap_topo_opts o;
    ljgap_topo_result r;
    cJSON *err, *grid, *fit, *efit, *pr, *rel;
    double m0;
    int st;
    ljgap_topo_opts_default(&o);
    o.cancel = j->cancel;
    o.fit_kmin = t->fit_kmin;
    o.fit_kmax = t->fit_kmax;
    o.detrend = (ljgap_topo_detrend)t->detrend;
    o.tip_radius = t->tip_radius;
    o.resolution = t->resolution;
    st = ljgap_topo_compute(t->h, &g, &o, &r, &j->rq.warn);
    free(t->h); /* a large map: the answer needs the bins only */
    t->h = NULL;
    if (st == LJGAP_EINVAL || st == LJGAP_EFAIL) {
        j->bad_ptr = "/topography/heights";
        j->bad_head = "the height map cannot be analysed";
        return LJGAP_EINVAL;
    }
    if (st) return st;
    ljgap__ans_nums(j, j->ans, "k", r.k, r.n, sizeof *r.k, "k");
    ljgap__ans_nums(j, j->ans, "P", r.P, r.n, sizeof *r.P, "P");
    ljgap__ans_nums(j, j->ans, "modes", r.modes, r.n, sizeof *r.modes, "modes");
    ljgap__ans_num(j, j->ans, "h_rms", r.h_rms.value, "h_rms", -1);
    ljgap__ans_num(j, j->ans, "rms_slope", r.rms_slope.value, "rms_slope", -1);
    grid = ljgap__ans_put(j, j->ans, "grid", cJSON_CreateObject());
    ljgap__ans_put(j, grid, "nx", cJSON_CreateNumber((double)t->nx));
    ljgap__ans_put(j, grid, "ny", cJSON_CreateNumber((double)t->ny));
    ljgap__ans_num(j, grid, "dx", t->dx, "grid.dx", -1);
    ljgap__ans_num(j, grid, "dy", t->dy, "grid.dy", -1);
    ljgap__ans_put(j, grid, "periodic", cJSON_CreateBool(t->periodic));
    ljgap__ans_put(j, grid, "profile", cJSON_CreateBool(r.profile));
    ljgap__ans_put(j, grid, "detrend",
                  cJSON_CreateString(r.profile && r.detrend == LJGAP_DETREND_PLANE
                                         ? "line"
                                         : ljgap_topo_detrend_name(r.detrend)));
    ljgap__ans_put(j, grid, "window", cJSON_CreateString(t->periodic ? "none" : "hann"));
    ljgap__ans_num(j, grid, "k_min", r.k_fund, "grid.k_min", -1);
    ljgap__ans_num(j, grid, "k_max", r.k_nyq, "grid.k_max", -1);
    if (j->rq.source) { /* an instrument file: what it said (ljgap__handle_file) */
        ljgap__ans_put(j, j->ans, "source", j->rq.source);
        j->rq.source = NULL;
    }
    rel = ljgap__ans_put(j, j->ans, "reliable", cJSON_CreateObject());
    ljgap__ans_num(j, rel, "k_min", r.rel_kmin, "reliable.k_min", -1);
    ljgap__ans_num(j, rel, "k_max", r.rel_kmax, "reliable.k_max", -1);
    ljgap__ans_put(j, rel, "by",
                  cJSON_CreateString(r.rel_by == LJGAP_RELIABLE_TIP          ? "tip"
                                     : r.rel_by == LJGAP_RELIABLE_RESOLUTION ? "resolution"
                                     : r.rel_by == LJGAP_RELIABLE_NOISE      ? "noise"
                                                                             : "nyquist"));
    err = ljgap__ans_put(j, j->ans, "error", cJSON_CreateObject());
    ljgap__ans_nums(j, err, "P", r.P_err, r.n, sizeof *r.P_err, "error.P");
    ljgap__ans_num(j, err, "h_rms", r.h_rms.err, "error.h_rms", -1);
    ljgap__ans_num(j, err, "rms_slope", r.rms_slope.err, "error.rms_slope", -1);
    if (r.has_fit) {
        fit = ljgap__ans_put(j, j->ans, "fit", cJSON_CreateObject());
        efit = ljgap__ans_put(j, err, "fit", cJSON_CreateObject());
        ljgap__ans_num(j, fit, "D", r.fit.D.value, "fit.D", -1);
        ljgap__ans_num(j, fit, "H", 3 - r.fit.D.value, "fit.H", -1);
        ljgap__ans_num(j, fit, "C", r.fit.C.value, "fit.C", -1);
        ljgap__ans_num(j, fit, "k_min", r.fit.kmin, "fit.k_min", -1);
        ljgap__ans_num(j, fit, "k_max", r.fit.kmax, "fit.k_max", -1);
        ljgap__ans_put(j, fit, "bins", cJSON_CreateNumber((double)r.fit.bins));
        ljgap__ans_num(j, fit, "chi2_red", r.fit.chi2_red, "fit.chi2_red", -1);
        ljgap__ans_num(j, fit, "corr_lnC_D", r.fit.corr, "fit.corr_lnC_D", -1);
        ljgap__ans_put(j, fit, "band", cJSON_CreateString(r.fit.given ? "given" : "detected"));
        ljgap__ans_put(j, fit, "sound", cJSON_CreateBool(r.fit.sound));
        ljgap__ans_num(j, efit, "D", r.fit.D.err, "error.fit.D", -1);
        ljgap__ans_num(j, efit, "H", r.fit.D.err, "error.fit.H", -1);
        ljgap__ans_num(j, efit, "C", r.fit.C.err, "error.fit.C", -1);
        if (r.fit.noise_floor > 0) { /* a white floor fitted with the law (m⁴) */
            ljgap__ans_num(j, fit, "noise_floor", r.fit.noise_floor, "fit.noise_floor", -1);
            ljgap__ans_num(j, efit, "noise_floor", r.fit.noise_floor_err, "error.fit.noise_floor",
                          -1);
        } else {
            ljgap__ans_put(j, fit, "noise_floor", cJSON_CreateNull());
            ljgap__ans_put(j, efit, "noise_floor", cJSON_CreateNull());
        }
    } else {
        ljgap__ans_put(j, j->ans, "fit", cJSON_CreateNull());
        ljgap__ans_put(j, err, "fit", cJSON_CreateNull());
    }
    if (r.profile) {
        pr = ljgap__ans_put(j, j->ans, "profile", cJSON_CreateObject());
        ljgap__ans_nums(j, pr, "PP", r.PP, r.n, sizeof *r.PP, "profile.PP");
        ljgap__ans_num(j, pr, "alpha", r.alpha.value, "profile.alpha", -1);
        pr = ljgap__ans_put(j, err, "profile", cJSON_CreateObject());
        ljgap__ans_nums(j, pr, "PP", r.PP_err, r.n, sizeof *r.PP_err, "error.profile.PP");
        ljgap__ans_num(j, pr, "alpha", r.alpha.err, "error.profile.alpha", -1);
        ljgap_warn(&j->rq.warn,
                   "one profile: its 1-D PSD PP ∝ k^-%.3g was turned into the isotropic PSD P = "
                   "F(α) PP/k, which assumes an isotropic surface",
                   r.alpha.value);
    }
    if (r.rms_slope.value > SLOPE_WARN)
        ljgap_warn(&j->rq.warn,
                   "the rms slope is %.3g: are the heights and dx, dy in metres (the same unit)?",
                   r.rms_slope.value);
    if (j->rq.has_material)
        put_domain(j, &r);
    else
        put_psd_object(j, &r, 0, &m0);
    ljgap__ans_si(j);
    ljgap_topo_result_free(&r);
    return LJGAP_OK;
}

/* ---- an instrument file as the body (issue 28) ----
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
 * rectangle of the map (files.h: ljgap__files_largest_rect), which is neither padded nor
 * interpolated, so the periodogram and its error statistics stay those of a complete map;
 * source.missing says how many points were missing and which rectangle was used, and a
 * warning says it too. A cropped map is not periodic.
 *
 * Problems: 415 unsupported-media-type listing the formats read (no reader recognises the
 * bytes), 422 validation at /format (format= names no format read here), 422 bad-file with the
 * format and the byte offset or member (a recognised file cut short or corrupt), 422 validation at
 * /channel (no such channel, or a channel that is no height), 413 content-too-large (a map over the
 * server's cap of points).
 */

#define HEIGHT_MAX 1e3 /* |height| in m, as request_topo.c's */

/* A problem with the format, offset and member of a bad file (problems.c's row for slug). */
static void file_problem(ljgap__reply *out, const char *slug, const char *detail,
                         const ljgap__files_err *e)
{
    const ljgap__problem_doc *k = ljgap__problem_find(slug);
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
        ljgap__ans_oom(out);
        return;
    }
    ljgap__ans_reply_json(out, k->status, CT_PROBLEM, p);
    cJSON_Delete(p);
}

/* A 422 validation problem with one error at ptr. */
static void one_error(ljgap__reply *out, const char *ptr, const char *detail)
{
    ljgap__verr ve = {cJSON_CreateArray(), 0, 0};
    if (!ve.errors) {
        ljgap__ans_oom(out);
        return;
    }
    ljgap__verr_add(&ve, ptr, "%s", detail);
    ljgap__ans_invalid(out, &ve);
    cJSON_Delete(ve.errors);
}

/* The answer to a failed read (st: files.h's status). */
static void read_failed(ljgap__reply *out, int st, const ljgap__files_err *e)
{
    char detail[900], names[600];
    switch (st) {
    case LJGAP_FILES_UNKNOWN:
        ljgap__files_names(names, sizeof names);
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
        ljgap__ans_oom(out);
    }
}

/* "format" and "channel" out of the query (kept in *format, *channel); the rest into rest. */
static size_t split_params(const ljgap__param *p, size_t np, ljgap__param *rest, const char **format,
                           const char **channel)
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
static cJSON *source_json(const ljgap__files_map *m, size_t x0, size_t y0, size_t w, size_t h)
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
static const char *file_defaults(cJSON *query, const ljgap__files_map *m, size_t w, size_t h,
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
                     m->format, m->size_x, m->size_y, m->nx, m->ny, dx, dy, has_dx ? "dx" : "dy");
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
static double *crop(ljgap__files_map *m, size_t x0, size_t y0, size_t w, size_t h, char *detail,
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

void ljgap__handle_file(const char *endpoint, const ljgap__param *params, size_t nparams,
                       const unsigned char *body, size_t len, const ljgap__call *call,
                       ljgap__reply *out)
{
    double t0 = ljgap__clock_now();
    const ljgap__limits *lim = ljgap__handler_limits();
    ljgap__param *rest = NULL;
    const char *format, *channel, *ptr;
    ljgap__files_map m;
    ljgap__files_err e;
    ljgap__topo_spec heights = {0};
    ljgap__verr ve = {0};
    cJSON *query = NULL;
    char detail[700] = "";
    size_t x0 = 0, y0 = 0, w, h;
    job j;
    int form, st;
    memset(&j, 0, sizeof j);
    memset(out, 0, sizeof *out);
    memset(&m, 0, sizeof m);
    if (!ljgap__handler_has_text(endpoint)) {
        ljgap__ans_problem(out, P_NOT_FOUND, "only psd takes an instrument file", NULL);
        return;
    }
    if ((form = ljgap__ans_negotiate(call ? call->accept : NULL, 0, out)) < 0) return;
    if (!(rest = malloc((nparams ? nparams : 1) * sizeof *rest)) ||
        !(ve.errors = cJSON_CreateArray())) {
        ljgap__ans_oom(out);
        goto end;
    }
    size_t nrest = split_params(params, nparams, rest, &format, &channel);
    /* an unknown or repeated query parameter is refused before the file is read */
    if (!(query = ljgap__topo_params_json(rest, nrest, &ve))) {
        ljgap__ans_oom(out);
        goto end;
    }
    if (ve.n) {
        ljgap__ans_invalid(out, &ve);
        goto end;
    }
    if (format && *format && !ljgap__files_find(format)) {
        char names[600];
        ljgap__files_names(names, sizeof names);
        snprintf(detail, sizeof detail, "no format \"%.32s\": the formats read are %s", format,
                 names);
        one_error(out, "/format", detail);
        goto end;
    }
    if ((st = ljgap__files_read(body, len, format, channel, &m, &e))) {
        read_failed(out, st, &e);
        goto end;
    }
    double unit = m.z_unit[0] ? ljgap__files_unit_scale(m.z_unit) : 1;
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
    if (m.missing && ljgap__files_largest_rect(&m, &x0, &y0, &w, &h)) {
        ljgap__ans_oom(out);
        goto end;
    }
    if ((size_t)w * h > ljgap__limits_topo_cap(lim)) {
        snprintf(detail, sizeof detail,
                 "the map has %zu x %zu points, more than the %zu this server takes", w, h,
                 ljgap__limits_topo_cap(lim));
        file_problem(out, "content-too-large", detail, NULL);
        goto end;
    }
    if ((ptr = file_defaults(query, &m, w, h, detail, sizeof detail))) {
        if (!*ptr)
            ljgap__ans_oom(out);
        else
            one_error(out, ptr, detail);
        goto end;
    }
    if (!(heights.h = crop(&m, x0, y0, w, h, detail, sizeof detail))) {
        if (detail[0])
            one_error(out, "/topography/heights", detail);
        else
            ljgap__ans_oom(out);
        goto end;
    }
    heights.nx = w, heights.ny = h;
    /* parse_text starts a fresh request: the warnings so far go in after it */
    ljgap_warnings early = j.rq.warn;
    ljgap__request_parse_text(query, &heights, lim, &j.rq, &ve);
    if (ve.n || ve.oom) {
        ljgap__ans_invalid(out, &ve);
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
        ljgap__ans_oom(out);
        goto end;
    }
    ljgap__files_map_free(&m);
    ljgap__ans_run_job(&j, ljgap__run_psd, endpoint, form, call, t0, out);
end:
    ljgap__files_map_free(&m);
    free(heights.h);
    free(rest);
    cJSON_Delete(query);
    cJSON_Delete(ve.errors);
    ljgap__request_free(&j.rq);
}
