/* psd.c -- POST /v1/psd: a measured height map's PSD as the answer (issue 15, core/topo/topo.c).
 *
 * The runner of the psd endpoint, out of handler.c: the bins, the fit and the reliable band of
 * ljgap_topo_compute written as docs/api.md fixes them, and the psd object ready for the adhesion
 * endpoints (a table of the reliable bins, with the fitted tail when the fit stands for the
 * spectrum up to its end). With a material, the theory's domain of that band and the object
 * from its k1; the same writers serve psd/combine (combine.c) through answer.h.
 */
#include "answer.h"
#include "ljgap_topo.h"

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
void ljgap_ans_table_psd(job *j, const double *k, const double *P, const double *P_err, size_t n,
                         double q, double q_err, double *m0)
{
    cJSON *o = ljgap_ans_put(j, j->ans, "psd", cJSON_CreateObject());
    int tail = isfinite(q);
    ljgap_psd psd;
    *m0 = NAN;
    ljgap_ans_put(j, o, "kind", cJSON_CreateString("table"));
    ljgap_ans_nums(j, o, "k", k, n, sizeof *k, "psd.k");
    ljgap_ans_nums(j, o, "P", P, n, sizeof *P, "psd.P");
    ljgap_ans_nums(j, o, "P_err", P_err, n, sizeof *P_err, "psd.P_err");
    if (tail) {
        cJSON *to = ljgap_ans_put(j, o, "tail", cJSON_CreateObject());
        ljgap_ans_num(j, to, "exponent", q, "psd.tail", -1);
        ljgap_ans_num(j, to, "exponent_err", q_err, "psd.tail.exponent_err", -1);
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
        ljgap_ans_table_psd(j, t.k, t.P, t.P_err, t.n, tail ? q : NAN, 2 * r->fit.D.err, m0);
        if (!tail)
            ljgap_warn(
                &j->rq.warn, "the psd object has no tail: %s, so the table ends at k = %g 1/m",
                !r->has_fit     ? "there is no power-law fit"
                : !r->fit.sound ? "the fit is no sound power law with 2 < D < 3"
                                : "the bins above the fit band are no power law (a cutoff, a noise "
                                  "floor or the tip's trace?) and are kept as measured",
                t.k[t.n - 1]);
    } else if (r->has_fit && r->fit.sound && q < -2) {
        o = ljgap_ans_put(j, j->ans, "psd", cJSON_CreateObject());
        ljgap_ans_put(j, o, "kind", cJSON_CreateString("power"));
        ljgap_ans_num(j, o, "D", r->fit.D.value, "psd.D", -1);
        ljgap_ans_num(j, o, "k1", k_from, "psd.k1", -1);
        ljgap_ans_num(j, o, "C", r->fit.C.value, "psd.C", -1);
        ljgap_warn(&j->rq.warn,
                   "the theory's band starts at k1 = %g 1/m, beyond the reliable bins: the psd "
                   "object is the fitted power law, extrapolated",
                   k_from);
        if (ljgap_psd_power(&psd, r->fit.D.value, k_from, INFINITY, LJGAP_LEVEL_C,
                            r->fit.C.value) == LJGAP_OK)
            *m0 = psd.m0;
    } else {
        ljgap_ans_put(j, j->ans, "psd", cJSON_CreateNull());
        ljgap_warn(&j->rq.warn,
                   "no psd object: no reliable bin lies above k = %g 1/m and the "
                   "fit gives no sound power law with 2 < D < 3 to extrapolate",
                   k_from);
    }
    ljgap_topo_tab_free(&t);
}

/* With a material: where the band [kf, kl] (its name: "reliable band", ...) lies against the
 * theory's k > k0/χ and the k1 it proposes (kf, or K1_MARGIN k0/χ when that is higher) into
 * d and the answer's "domain"; the caller then writes the psd object from d->k1 and ends with
 * ljgap_ans_domain_end and the object's variance. /v1/psd's and /v1/psd/combine's. */
void ljgap_ans_domain_begin(job *j, double kf, double kl, const char *band, ljgap_domain *d)
{
    const ljgap_material *m = &j->rq.mat;
    double chi = ljgap_units_chi(m);
    d->kd = ljgap_k0() / chi;
    d->kf = kf;
    d->kl = kl;
    d->band = band;
    d->k1 = fmax(kf, K1_MARGIN * d->kd);
    d->inside = kl <= d->kd ? 0 : kf > d->kd ? 1 : log(kl / d->kd) / log(kl / kf);
    d->obj = ljgap_ans_put(j, j->ans, "domain", cJSON_CreateObject());
    ljgap_ans_num(j, d->obj, "k0", d->kd, "domain.k0", -1);
    ljgap_ans_put(j, d->obj, "inside",
                  cJSON_CreateString(d->inside == 1   ? "all"
                                     : d->inside == 0 ? "none"
                                                      : "part"));
    ljgap_ans_num(j, d->obj, "fraction", d->inside, "domain.fraction", -1);
    ljgap_ans_num(j, d->obj, "k1", d->k1, "domain.k1", -1);
    ljgap_ans_num(j, d->obj, "k1_dimensionless", d->k1 * chi, "domain.k1_dimensionless", -1);
}

void ljgap_ans_domain_end(job *j, const ljgap_domain *d, double m0)
{
    if (isfinite(m0)) {
        ljgap_ans_num(j, d->obj, "h_rms", sqrt(m0), "domain.h_rms", -1);
        ljgap_ans_num(j, d->obj, "m0_dimensionless", ljgap_units_var_to_dimless(&j->rq.mat, m0),
                      "domain.m0_dimensionless", -1);
    } else {
        ljgap_ans_put(j, d->obj, "h_rms", cJSON_CreateNull());
        ljgap_ans_put(j, d->obj, "m0_dimensionless", cJSON_CreateNull());
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
    ljgap_domain d;
    double m0;
    ljgap_ans_domain_begin(j, r->rel_kmin, r->k[r->rel_last], "reliable band", &d);
    put_psd_object(j, r, d.k1, &m0);
    ljgap_ans_domain_end(j, &d, m0);
}

int ljgap_run_psd(job *j)
{
    ljgap_topo_spec *t = &j->rq.topo;
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
    ljgap_ans_nums(j, j->ans, "k", r.k, r.n, sizeof *r.k, "k");
    ljgap_ans_nums(j, j->ans, "P", r.P, r.n, sizeof *r.P, "P");
    ljgap_ans_nums(j, j->ans, "modes", r.modes, r.n, sizeof *r.modes, "modes");
    ljgap_ans_num(j, j->ans, "h_rms", r.h_rms.value, "h_rms", -1);
    ljgap_ans_num(j, j->ans, "rms_slope", r.rms_slope.value, "rms_slope", -1);
    grid = ljgap_ans_put(j, j->ans, "grid", cJSON_CreateObject());
    ljgap_ans_put(j, grid, "nx", cJSON_CreateNumber((double)t->nx));
    ljgap_ans_put(j, grid, "ny", cJSON_CreateNumber((double)t->ny));
    ljgap_ans_num(j, grid, "dx", t->dx, "grid.dx", -1);
    ljgap_ans_num(j, grid, "dy", t->dy, "grid.dy", -1);
    ljgap_ans_put(j, grid, "periodic", cJSON_CreateBool(t->periodic));
    ljgap_ans_put(j, grid, "profile", cJSON_CreateBool(r.profile));
    ljgap_ans_put(j, grid, "detrend",
                  cJSON_CreateString(r.profile && r.detrend == LJGAP_DETREND_PLANE
                                         ? "line"
                                         : ljgap_topo_detrend_name(r.detrend)));
    ljgap_ans_put(j, grid, "window", cJSON_CreateString(t->periodic ? "none" : "hann"));
    ljgap_ans_num(j, grid, "k_min", r.k_fund, "grid.k_min", -1);
    ljgap_ans_num(j, grid, "k_max", r.k_nyq, "grid.k_max", -1);
    if (j->rq.source) { /* an instrument file: what it said (psd_file.c) */
        ljgap_ans_put(j, j->ans, "source", j->rq.source);
        j->rq.source = NULL;
    }
    rel = ljgap_ans_put(j, j->ans, "reliable", cJSON_CreateObject());
    ljgap_ans_num(j, rel, "k_min", r.rel_kmin, "reliable.k_min", -1);
    ljgap_ans_num(j, rel, "k_max", r.rel_kmax, "reliable.k_max", -1);
    ljgap_ans_put(j, rel, "by",
                  cJSON_CreateString(r.rel_by == LJGAP_RELIABLE_TIP          ? "tip"
                                     : r.rel_by == LJGAP_RELIABLE_RESOLUTION ? "resolution"
                                     : r.rel_by == LJGAP_RELIABLE_NOISE      ? "noise"
                                                                             : "nyquist"));
    err = ljgap_ans_put(j, j->ans, "error", cJSON_CreateObject());
    ljgap_ans_nums(j, err, "P", r.P_err, r.n, sizeof *r.P_err, "error.P");
    ljgap_ans_num(j, err, "h_rms", r.h_rms.err, "error.h_rms", -1);
    ljgap_ans_num(j, err, "rms_slope", r.rms_slope.err, "error.rms_slope", -1);
    if (r.has_fit) {
        fit = ljgap_ans_put(j, j->ans, "fit", cJSON_CreateObject());
        efit = ljgap_ans_put(j, err, "fit", cJSON_CreateObject());
        ljgap_ans_num(j, fit, "D", r.fit.D.value, "fit.D", -1);
        ljgap_ans_num(j, fit, "H", 3 - r.fit.D.value, "fit.H", -1);
        ljgap_ans_num(j, fit, "C", r.fit.C.value, "fit.C", -1);
        ljgap_ans_num(j, fit, "k_min", r.fit.kmin, "fit.k_min", -1);
        ljgap_ans_num(j, fit, "k_max", r.fit.kmax, "fit.k_max", -1);
        ljgap_ans_put(j, fit, "bins", cJSON_CreateNumber((double)r.fit.bins));
        ljgap_ans_num(j, fit, "chi2_red", r.fit.chi2_red, "fit.chi2_red", -1);
        ljgap_ans_num(j, fit, "corr_lnC_D", r.fit.corr, "fit.corr_lnC_D", -1);
        ljgap_ans_put(j, fit, "band", cJSON_CreateString(r.fit.given ? "given" : "detected"));
        ljgap_ans_put(j, fit, "sound", cJSON_CreateBool(r.fit.sound));
        ljgap_ans_num(j, efit, "D", r.fit.D.err, "error.fit.D", -1);
        ljgap_ans_num(j, efit, "H", r.fit.D.err, "error.fit.H", -1);
        ljgap_ans_num(j, efit, "C", r.fit.C.err, "error.fit.C", -1);
        if (r.fit.noise_floor > 0) { /* a white floor fitted with the law (m⁴) */
            ljgap_ans_num(j, fit, "noise_floor", r.fit.noise_floor, "fit.noise_floor", -1);
            ljgap_ans_num(j, efit, "noise_floor", r.fit.noise_floor_err, "error.fit.noise_floor",
                          -1);
        } else {
            ljgap_ans_put(j, fit, "noise_floor", cJSON_CreateNull());
            ljgap_ans_put(j, efit, "noise_floor", cJSON_CreateNull());
        }
    } else {
        ljgap_ans_put(j, j->ans, "fit", cJSON_CreateNull());
        ljgap_ans_put(j, err, "fit", cJSON_CreateNull());
    }
    if (r.profile) {
        pr = ljgap_ans_put(j, j->ans, "profile", cJSON_CreateObject());
        ljgap_ans_nums(j, pr, "PP", r.PP, r.n, sizeof *r.PP, "profile.PP");
        ljgap_ans_num(j, pr, "alpha", r.alpha.value, "profile.alpha", -1);
        pr = ljgap_ans_put(j, err, "profile", cJSON_CreateObject());
        ljgap_ans_nums(j, pr, "PP", r.PP_err, r.n, sizeof *r.PP_err, "error.profile.PP");
        ljgap_ans_num(j, pr, "alpha", r.alpha.err, "error.profile.alpha", -1);
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
    ljgap_ans_si(j);
    ljgap_topo_result_free(&r);
    return LJGAP_OK;
}
