/* combine.c -- POST /v1/psd/combine: several measured PSDs of one surface as one (issue 25).
 *
 * Request: {"psds": [psd, psd, ...], "points_per_decade": 10, "material": {...}}, each psd a table
 * as /v1/psd answers it: {"kind":"table", "k":[1/m], "P":[m⁴], "P_err":[m⁴], "tail":{"exponent":q,
 * "exponent_err":e}} (kind and tail optional; P_err required: the weights need it). Every bad
 * value is a 422 problem at its pointer (/psds/2/P_err/7). The core (ljgap_combine.h) does the
 * work; the answer (docs/api.md, docs/topography.md):
 *   k, P, inputs (how many psds cover each point), sources [{k_min, k_max, points}], gaps
 *   [{k_min, k_max}], agreement {chi2, dof, p, inflated}, fit {D, H, C, k_min, k_max, points,
 *   chi2_red, corr_lnC_D} or null, tail_from ("psds/I", "fit" or null), psd {kind, k, P, P_err,
 *   tail {exponent, exponent_err}}, error {P, chi2 [per point], fit {D, H, C}}, meta.
 * A combination whose bands hold fewer than two grid points is a 422 outside-model problem at
 * /psds. An optional "material" (request.c's, as /v1/psd's) adds domain and si as /v1/psd
 * gives them (handler.c's ljgap__ans_domain_begin/_end, ljgap__ans_si) and starts the psd object
 * at domain.k1.
 */
#include "answer.h"
#include "handler.h" /* ljgap__combine_body */
#include "ljgap_combine.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TABLE_MAX 10000 /* points of one psd, as a table psd anywhere */
#define PTR 64

struct ljgap__combine_spec {
    size_t m;
    double per_decade;
    ljgap_combine_input in[LJGAP_COMBINE_MAX];
    double *col[LJGAP_COMBINE_MAX][3]; /* owned k, P, P_err of each */
};

void ljgap__combine_spec_free(struct ljgap__combine_spec *s)
{
    if (!s) return;
    for (size_t i = 0; i < LJGAP_COMBINE_MAX; i++)
        for (int c = 0; c < 3; c++)
            free(s->col[i][c]);
    free(s);
}

static const char *const combine_fields[] = {"psds", "points_per_decade", "material", NULL};
static const char *const psd_fields[] = {"kind", "k", "P", "P_err", "P_corr", "tail", NULL};
static const char *const tail_fields[] = {"exponent", "exponent_err", NULL};
static const char *const col_names[3] = {"k", "P", "P_err"};

/* Column c of psds[i] (n numbers at base/NAME/j) into a new array; NULL when any is bad. P: the
 * P column, for P_err's (NULL when it was bad). */
static double *column(ljgap__verr *e, const cJSON *arr, const char *base, int c, size_t n,
                      const double *P)
{
    double *x = malloc(n * sizeof *x);
    const cJSON *it;
    char ptr[PTR];
    size_t j = 0, bad = 0;
    if (!x) {
        e->oom = 1;
        return NULL;
    }
    cJSON_ArrayForEach(it, arr)
    {
        snprintf(ptr, sizeof ptr, "%s/%s/%zu", base, col_names[c], j);
        if (!ljgap__v_num(e, it, ptr, &x[j])) {
            x[j] = NAN; /* read by the next one's checks */
            bad++;
        } else if (c < 2 && !(x[j] > 0)) {
            ljgap__verr_add(e, ptr, "%s must be positive (got %g)", col_names[c], x[j]);
            bad++;
        } else if (c == 2 && !(x[j] >= 0)) {
            ljgap__verr_add(e, ptr, "P_err must be zero or positive (got %g)", x[j]);
            bad++;
        } else if (c == 2 && P && P[j] > 0 && !(x[j] / P[j] <= LJGAP_COMBINE_REL_ERR_MAX)) {
            ljgap__verr_add(e, ptr, "P_err = %g is more than %g times P = %g: no information", x[j],
                           LJGAP_COMBINE_REL_ERR_MAX, P[j]);
            bad++;
        } else if (c == 0 && j && x[j - 1] > 0 && !(x[j] > x[j - 1])) {
            ljgap__verr_add(e, ptr, "k must be strictly increasing: k[%zu] = %g follows k[%zu] = %g",
                           j, x[j], j - 1, x[j - 1]);
            bad++;
        }
        j++;
    }
    if (bad) {
        free(x);
        return NULL;
    }
    return x;
}

static void parse_tail(ljgap__verr *e, const cJSON *tail, const char *base, ljgap_combine_input *in)
{
    char ptr[PTR], eptr[PTR];
    const cJSON *q, *qe;
    snprintf(ptr, sizeof ptr, "%s/tail", base);
    if (!cJSON_IsObject(tail)) {
        ljgap__verr_add(e, ptr, "must be an object {\"exponent\": q, \"exponent_err\": e}");
        return;
    }
    ljgap__v_only_fields(e, tail, ptr, tail_fields);
    q = ljgap__v_required(e, tail, ptr, "exponent", "P ∝ k^q beyond the last point, q < -2");
    qe = cJSON_GetObjectItemCaseSensitive(tail, "exponent_err");
    snprintf(eptr, sizeof eptr, "%s/tail/exponent", base);
    if (q && ljgap__v_num(e, q, eptr, &in->tail_q)) {
        if (in->tail_q < -2)
            in->has_tail = 1;
        else
            ljgap__verr_add(e, eptr,
                           "q = %g must be below -2, or the tail carries infinite variance",
                           in->tail_q);
    }
    snprintf(eptr, sizeof eptr, "%s/tail/exponent_err", base);
    in->tail_q_err = 0;
    if (qe && ljgap__v_num(e, qe, eptr, &in->tail_q_err) && !(in->tail_q_err >= 0))
        ljgap__verr_add(e, eptr, "must be zero or positive (got %g)", in->tail_q_err);
}

/* An input's P_corr (/v1/psd's neighbouring knots' correlations, n - 1 in [-1, 1]): checked, not
 * used (the combination takes the bins as independent and interpolates their errors as if fully
 * correlated, the conservative bound: docs/topography.md). */
static void check_corr(ljgap__verr *e, const cJSON *pc, const char *base, size_t n)
{
    char ptr[PTR];
    const cJSON *it;
    size_t j = 0, nc;
    double r;
    snprintf(ptr, sizeof ptr, "%s/P_corr", base);
    if (!(nc = ljgap__v_array(e, pc, ptr, 1, TABLE_MAX, "one correlation per pair of neighbours")))
        return;
    if (n && nc != n - 1) {
        ljgap__verr_add(e, ptr, "has %zu entries but k has %zu: give one per pair of neighbours", nc,
                       n);
        return;
    }
    cJSON_ArrayForEach(it, pc)
    {
        snprintf(ptr, sizeof ptr, "%s/P_corr/%zu", base, j++);
        if (ljgap__v_num(e, it, ptr, &r) && !(fabs(r) <= 1))
            ljgap__verr_add(e, ptr, "a correlation lies in [-1, 1] (got %g)", r);
    }
}

/* psds[i] (pointer base) into s->in[i]. */
static void parse_one(ljgap__verr *e, const cJSON *psd, const char *base,
                      struct ljgap__combine_spec *s, size_t i)
{
    const cJSON *col[3], *kind, *tail;
    size_t n[3] = {0, 0, 0};
    char ptr[PTR];
    if (!cJSON_IsObject(psd)) {
        ljgap__verr_add(e, base,
                       "must be a psd object {\"kind\":\"table\", \"k\", \"P\", \"P_err\", "
                       "\"tail\"} as /v1/psd answers it");
        return;
    }
    ljgap__v_only_fields(e, psd, base, psd_fields);
    if ((kind = cJSON_GetObjectItemCaseSensitive(psd, "kind")) &&
        !(cJSON_IsString(kind) && strcmp(kind->valuestring, "table") == 0)) {
        snprintf(ptr, sizeof ptr, "%s/kind", base);
        ljgap__verr_add(e, ptr,
                       "must be \"table\": only measured tables (k, P, P_err) can be combined");
    }
    col[0] = ljgap__v_required(e, psd, base, "k", "increasing wavenumbers, 1/m");
    col[1] = ljgap__v_required(e, psd, base, "P", "the PSD at each k, m⁴");
    col[2] = ljgap__v_required(e, psd, base, "P_err",
                              "the standard error of each P, m⁴: the weights need it");
    for (int c = 0; c < 3; c++) {
        if (!col[c]) continue;
        snprintf(ptr, sizeof ptr, "%s/%s", base, col_names[c]);
        n[c] = ljgap__v_array(e, col[c], ptr, 2, TABLE_MAX, "one entry per point");
    }
    for (int c = 1; c < 3; c++)
        if (n[0] && n[c] && n[c] != n[0]) {
            snprintf(ptr, sizeof ptr, "%s/%s", base, col_names[c]);
            ljgap__verr_add(e, ptr, "has %zu entries but k has %zu: give one per k", n[c], n[0]);
            n[c] = 0;
        }
    if ((tail = cJSON_GetObjectItemCaseSensitive(psd, "tail")))
        parse_tail(e, tail, base, &s->in[i]);
    if ((tail = cJSON_GetObjectItemCaseSensitive(psd, "P_corr"))) check_corr(e, tail, base, n[0]);
    if (!n[0] || n[1] != n[0] || n[2] != n[0]) return;
    for (int c = 0; c < 3; c++)
        s->col[i][c] = column(e, col[c], base, c, n[0], s->col[i][1]);
    s->in[i].n = n[0];
    s->in[i].k = s->col[i][0];
    s->in[i].P = s->col[i][1];
    s->in[i].P_err = s->col[i][2];
}

void ljgap__combine_parse(ljgap__verr *e, const cJSON *root, ljgap__request *rq)
{
    const cJSON *psds, *it;
    struct ljgap__combine_spec *s;
    char base[16]; /* "/psds/15" */
    size_t m, i = 0;
    rq->method = "inverse-variance";
    ljgap__v_only_fields(e, root, "", combine_fields);
    if (!(s = rq->combine = calloc(1, sizeof *s))) {
        e->oom = 1;
        return;
    }
    s->per_decade = 10;
    if ((it = cJSON_GetObjectItemCaseSensitive(root, "points_per_decade")) &&
        ljgap__v_num(e, it, "/points_per_decade", &s->per_decade) &&
        !(s->per_decade >= 2 && s->per_decade <= 100))
        ljgap__verr_add(e, "/points_per_decade", "%g is outside [2, 100]", s->per_decade);
    psds = ljgap__v_required(e, root, "", "psds",
                            "the measurements' psd objects, as /v1/psd answers them");
    if (!psds || !(m = ljgap__v_array(e, psds, "/psds", LJGAP_COMBINE_MIN, LJGAP_COMBINE_MAX,
                                     "psd objects of one surface, each with k, P and P_err")))
        return;
    s->m = m;
    cJSON_ArrayForEach(it, psds)
    {
        snprintf(base, sizeof base, "/psds/%zu", i);
        parse_one(e, it, base, s, i++);
    }
}

/* ---- the answer ---- */

static void put_fit(job *j, cJSON *err, const ljgap_combine_result *r)
{
    cJSON *fit, *efit;
    if (!r->has_fit) {
        ljgap__ans_put(j, j->ans, "fit", cJSON_CreateNull());
        ljgap__ans_put(j, err, "fit", cJSON_CreateNull());
        return;
    }
    fit = ljgap__ans_put(j, j->ans, "fit", cJSON_CreateObject());
    efit = ljgap__ans_put(j, err, "fit", cJSON_CreateObject());
    ljgap__ans_num(j, fit, "D", r->fit.D.value, "fit.D", -1);
    ljgap__ans_num(j, fit, "H", 3 - r->fit.D.value, "fit.H", -1);
    ljgap__ans_num(j, fit, "C", r->fit.C.value, "fit.C", -1);
    ljgap__ans_num(j, fit, "k_min", r->fit.kmin, "fit.k_min", -1);
    ljgap__ans_num(j, fit, "k_max", r->fit.kmax, "fit.k_max", -1);
    ljgap__ans_put(j, fit, "points", cJSON_CreateNumber((double)r->fit.bins));
    ljgap__ans_num(j, fit, "chi2_red", r->fit.chi2_red, "fit.chi2_red", -1);
    ljgap__ans_num(j, fit, "corr_lnC_D", r->fit.corr, "fit.corr_lnC_D", -1);
    ljgap__ans_num(j, efit, "D", r->fit.D.err, "error.fit.D", -1);
    ljgap__ans_num(j, efit, "H", r->fit.D.err, "error.fit.H", -1);
    ljgap__ans_num(j, efit, "C", r->fit.C.err, "error.fit.C", -1);
}

/* The psd object: the combined table from k_from on (its log-log interpolation cut there, so
 * the variance above k_from is kept) with its errors and the tail; null with a warning when
 * k_from is at or beyond the table's last point. Its variance into *m0 (NAN: null). */
static void put_psd(job *j, const ljgap_combine_result *r, double k_from, double *m0)
{
    char from[24];
    size_t i = 0, n;
    double *k, *P, *E, q = r->tail_from >= -1 ? r->tail_q : NAN;
    *m0 = NAN;
    snprintf(from, sizeof from, "psds/%d", r->tail_from);
    ljgap__ans_put(j, j->ans, "tail_from",
                  r->tail_from >= 0    ? cJSON_CreateString(from)
                  : r->tail_from == -1 ? cJSON_CreateString("fit")
                                       : cJSON_CreateNull());
    if (!(k_from < r->k[r->n - 1] * (1 - 1e-12))) {
        ljgap__ans_put(j, j->ans, "psd", cJSON_CreateNull());
        ljgap_warn(&j->rq.warn,
                   "no psd object: the theory's band starts at k1 = %g 1/m, at or beyond the "
                   "combined table's last point k = %g 1/m",
                   k_from, r->k[r->n - 1]);
        return;
    }
    while (i + 1 < r->n && r->k[i + 1] <= k_from * (1 + 1e-12))
        i++; /* k[i] <= k_from < k[i + 1], or k_from below the table (i = 0) */
    n = r->n - i;
    k = malloc(n * sizeof *k);
    P = malloc(n * sizeof *P);
    E = malloc(n * sizeof *E);
    if (!k || !P || !E) {
        j->oom = 1;
        goto end;
    }
    memcpy(k, r->k + i, n * sizeof *k);
    memcpy(P, r->P + i, n * sizeof *P);
    memcpy(E, r->P_err + i, n * sizeof *E);
    if (k_from > r->k[i] * (1 + 1e-12)) { /* the cut inside [k[i], k[i+1]]: log-log */
        double t = log(k_from / r->k[i]) / log(r->k[i + 1] / r->k[i]);
        double rel = (1 - t) * r->P_err[i] / r->P[i] + t * r->P_err[i + 1] / r->P[i + 1];
        k[0] = k_from;
        P[0] = exp((1 - t) * log(r->P[i]) + t * log(r->P[i + 1]));
        E[0] = P[0] * rel;
    }
    ljgap__ans_table_psd(j, k, P, E, n, q, r->tail_q_err, m0);
end:
    free(k);
    free(P);
    free(E);
}

int ljgap__run_combine(job *j)
{
    struct ljgap__combine_spec *s = j->rq.combine;
    ljgap_combine_opts o;
    ljgap_combine_result r;
    cJSON *a, *err, *x;
    double m0;
    int st;
    ljgap_combine_opts_default(&o);
    o.per_decade = s->per_decade;
    o.cancel = j->cancel;
    st = ljgap_combine(s->in, s->m, &o, &r, &j->rq.warn);
    if (st == LJGAP_EINVAL) {
        j->bad_ptr = "/psds";
        j->bad_head = "the measurements cannot be combined";
    }
    if (st) {
        ljgap_combine_result_free(&r);
        return st;
    }
    ljgap__ans_nums(j, j->ans, "k", r.k, r.n, sizeof *r.k, "k");
    ljgap__ans_nums(j, j->ans, "P", r.P, r.n, sizeof *r.P, "P");
    a = ljgap__ans_put(j, j->ans, "inputs", cJSON_CreateArray());
    for (size_t i = 0; a && i < r.n; i++)
        ljgap__ans_put(j, a, NULL, cJSON_CreateNumber(r.inputs[i]));
    a = ljgap__ans_put(j, j->ans, "sources", cJSON_CreateArray());
    for (size_t i = 0; a && i < r.m; i++) {
        x = ljgap__ans_put(j, a, NULL, cJSON_CreateObject());
        ljgap__ans_num(j, x, "k_min", r.src[i].k_min, "sources.k_min", (long)i);
        ljgap__ans_num(j, x, "k_max", r.src[i].k_max, "sources.k_max", (long)i);
        ljgap__ans_put(j, x, "points", cJSON_CreateNumber((double)r.src[i].points));
    }
    a = ljgap__ans_put(j, j->ans, "gaps", cJSON_CreateArray());
    for (size_t i = 0; a && i < r.ngaps; i++) {
        x = ljgap__ans_put(j, a, NULL, cJSON_CreateObject());
        ljgap__ans_num(j, x, "k_min", r.gap[i][0], "gaps.k_min", (long)i);
        ljgap__ans_num(j, x, "k_max", r.gap[i][1], "gaps.k_max", (long)i);
    }
    x = ljgap__ans_put(j, j->ans, "agreement", cJSON_CreateObject());
    ljgap__ans_num(j, x, "chi2", r.chi2_total, "agreement.chi2", -1);
    ljgap__ans_put(j, x, "dof", cJSON_CreateNumber((double)r.dof));
    ljgap__ans_num(j, x, "p", r.p_value, "agreement.p", -1);
    ljgap__ans_put(j, x, "inflated", cJSON_CreateNumber((double)r.inflated));
    err = ljgap__ans_put(j, j->ans, "error", cJSON_CreateObject());
    ljgap__ans_nums(j, err, "P", r.P_err, r.n, sizeof *r.P_err, "error.P");
    ljgap__ans_nums(j, err, "chi2", r.chi2, r.n, sizeof *r.chi2, "error.chi2");
    put_fit(j, err, &r);
    if (j->rq.has_material) {
        ljgap__domain d;
        ljgap__ans_domain_begin(j, r.k[0], r.k[r.n - 1], "combined band", &d);
        put_psd(j, &r, d.k1, &m0);
        ljgap__ans_domain_end(j, &d, m0);
    } else {
        put_psd(j, &r, 0, &m0);
    }
    ljgap__ans_si(j);
    ljgap_combine_result_free(&r);
    return LJGAP_OK;
}

/* ---- ljgap combine: the request from files ---- */

/* The psd object of one document (see handler.h): a /v1/psd answer's "psd" or a bare psd
 * object (k, P, P_err), as a new object; NULL with why in err. */
static cJSON *psd_of(const cJSON *doc, char *err, size_t errlen)
{
    const cJSON *psd;
    cJSON *o;
    if (!cJSON_IsObject(doc)) {
        snprintf(err, errlen, "not a JSON object");
        return NULL;
    }
    if (!cJSON_HasObjectItem(doc, "psd")) { /* a bare psd object */
        if (!cJSON_HasObjectItem(doc, "P_err")) {
            snprintf(err, errlen,
                     "neither a /v1/psd answer (with its \"psd\" object) nor a psd object "
                     "(k, P, P_err)");
            return NULL;
        }
        psd = doc;
    } else {
        psd = cJSON_GetObjectItemCaseSensitive(doc, "psd");
        if (!cJSON_IsObject(psd)) {
            snprintf(err, errlen,
                     "its \"psd\" is %s: the /v1/psd answer has no psd object (see its "
                     "meta.warnings) and cannot be combined",
                     cJSON_IsNull(psd) ? "null" : "not an object");
            return NULL;
        }
        if (!cJSON_HasObjectItem(psd, "P_err")) {
            snprintf(err, errlen,
                     "its \"psd\" object has no P_err (a %s psd, or an answer of an older "
                     "ljgapd): the weights need the errors; ask /v1/psd again",
                     cJSON_IsString(cJSON_GetObjectItemCaseSensitive(psd, "kind"))
                         ? cJSON_GetObjectItemCaseSensitive(psd, "kind")->valuestring
                         : "kindless");
            return NULL;
        }
    }
    if (!(o = cJSON_Duplicate(psd, 1))) snprintf(err, errlen, "out of memory");
    return o;
}

char *ljgap__combine_body(const char *const *docs, const size_t *lens, size_t n, double per_decade,
                         char *err, size_t errlen)
{
    cJSON *req = cJSON_CreateObject(), *arr = req ? cJSON_AddArrayToObject(req, "psds") : NULL;
    char *out = NULL, why[200];
    if (!arr ||
        (per_decade > 0 && !cJSON_AddNumberToObject(req, "points_per_decade", per_decade))) {
        snprintf(err, errlen, "out of memory");
        goto end;
    }
    for (size_t i = 0; i < n; i++) {
        cJSON *doc = cJSON_ParseWithLength(docs[i], lens[i]), *psd;
        if (!doc) {
            snprintf(err, errlen, "document %zu is not valid JSON", i + 1);
            goto end;
        }
        psd = psd_of(doc, why, sizeof why);
        cJSON_Delete(doc);
        if (!psd || !cJSON_AddItemToArray(arr, psd)) {
            cJSON_Delete(psd);
            snprintf(err, errlen, "document %zu: %s", i + 1, psd ? "out of memory" : why);
            goto end;
        }
    }
    if (!(out = cJSON_PrintUnformatted(req))) snprintf(err, errlen, "out of memory");
end:
    cJSON_Delete(req);
    return out;
}
