/* request_psd.c -- the psd object of a request into an ljgap__psd_spec (request.h).
 *
 * A power law {kind "power", D or H, k1, k2, one level of C, m0, h_rms} or a table {kind "table",
 * k, P, P_err, tail {exponent, exponent_err}}, dimensionless or, with a material and
 * "units":"SI", in SI (converted here, core/units.c, before the k1 > k0 check, which is a
 * statement about χk1; only a power law's C waits for ljgap__psd_from_spec, since it depends on
 * D, which a sweep may vary). The rules of the model (theory.md §1): 2 < D < 3, k1 > k0, k2 > k1,
 * positive finite levels; a table's k increasing and positive, P positive, at most PSD_TABLE_MAX
 * knots. The walk and its validators are request.c's (ljgap__v_*).
 */
#include "request.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PTR_LEN 96 /* room for every pointer built from known names */
#define PSD_TABLE_MAX 10000

static const char *const power_fields[] = {"kind",   "D",         "H",     "k1",    "k2",
                                           "C",      "m0",        "h_rms", "D_err", "C_err",
                                           "m0_err", "h_rms_err", NULL};
static const char *const table_fields[] = {"kind", "k", "P", "P_err", "P_corr", "tail", NULL};
static const char *const tail_fields[] = {"exponent", "exponent_err", NULL};

/* Level field of a power law: exactly one of C, m0, h_rms (in SI when mat is not NULL). */
static void parse_level(ljgap__verr *e, const cJSON *psd, const ljgap_material *mat,
                        ljgap__psd_spec *s)
{
    static const char *const names[] = {"C", "m0", "h_rms"};
    static const ljgap_level kinds[] = {LJGAP_LEVEL_C, LJGAP_LEVEL_M0, LJGAP_LEVEL_HRMS};
    int found = 0;
    for (int i = 0; i < 3; i++) {
        const cJSON *it = ljgap__v_member(psd, names[i]);
        char ptr[PTR_LEN];
        if (!it) continue;
        snprintf(ptr, sizeof ptr, "/psd/%s", names[i]);
        if (found++) {
            ljgap__verr_add(e, ptr, "the level is set twice: give only one of C, m0, h_rms");
            continue;
        }
        s->level = kinds[i];
        if (!ljgap__v_num_pos(e, it, ptr, &s->level_val) || !mat) continue;
        if (s->level == LJGAP_LEVEL_C) {
            s->c_si = 1;
            s->mat = *mat;
        } else if (s->level == LJGAP_LEVEL_M0) {
            s->level_val = ljgap_units_var_to_dimless(mat, s->level_val);
        } else {
            s->level_val = ljgap_units_len_to_dimless(mat, s->level_val);
        }
    }
    /* level_val > 0: it was read (or num_pos has already said why not) */
    if (found && s->level_val > 0 && s->level == LJGAP_LEVEL_M0)
        ljgap__v_in_core_range(e, "/psd/m0", "m0 (in units of ε²)", s->level_val, 0, LJGAP_M0_MAX);
    else if (found && s->level_val > 0 && s->level == LJGAP_LEVEL_HRMS)
        ljgap__v_in_core_range(e, "/psd/h_rms", "h_rms (in units of ε)", s->level_val, 0,
                              sqrt(LJGAP_M0_MAX));
    if (!found)
        ljgap__verr_add(e, "/psd",
                       "no level field: give exactly one of C, m0 (= 2π∫kP dk), "
                       "h_rms (= √m0)");
}

/* A power law's optional errors (1 σ, >= 0): D_err, and the error of the level it was given by
 * (C_err with C, m0_err with m0, h_rms_err with h_rms), converted like the level. */
static void parse_power_errors(ljgap__verr *e, const cJSON *psd, const ljgap_material *mat,
                               ljgap__psd_spec *s)
{
    static const char *const names[] = {"C_err", "m0_err", "h_rms_err"};
    static const char *const levels[] = {"C", "m0", "h_rms"};
    const cJSON *it = ljgap__v_member(psd, "D_err");
    if (it && ljgap__v_num(e, it, "/psd/D_err", &s->D_err) && !(s->D_err >= 0 && s->D_err < 1)) {
        ljgap__verr_add(e, "/psd/D_err",
                       "must be at least 0 and below 1 (D's standard error; got %g)", s->D_err);
        s->D_err = 0;
    }
    for (int i = 0; i < 3; i++) {
        char ptr[PTR_LEN];
        if (!(it = ljgap__v_member(psd, names[i]))) continue;
        snprintf(ptr, sizeof ptr, "/psd/%s", names[i]);
        if (!ljgap__v_member(psd, levels[i])) {
            ljgap__verr_add(e, ptr,
                           "%s is the error of %s, which is not given: give the error of "
                           "the level the PSD is set by",
                           names[i], levels[i]);
            continue;
        }
        if (!ljgap__v_num(e, it, ptr, &s->level_err)) continue;
        if (!(s->level_err >= 0)) {
            ljgap__verr_add(e, ptr, "must be at least 0 (a standard error; got %g)", s->level_err);
            s->level_err = 0;
        } else if (mat && i == 1) {
            s->level_err = ljgap_units_var_to_dimless(mat, s->level_err);
        } else if (mat && i == 2) {
            s->level_err = ljgap_units_len_to_dimless(mat, s->level_err);
        } /* C_err in SI is converted with C, when the PSD is built */
    }
}

static void parse_power(ljgap__verr *e, const cJSON *psd, const ljgap_material *mat,
                        ljgap__psd_spec *s)
{
    const cJSON *D = ljgap__v_member(psd, "D"), *H = ljgap__v_member(psd, "H"), *k1, *k2;
    double chi = mat ? ljgap_units_chi(mat) : 1;
    int k1_ok;
    ljgap__v_only_fields(e, psd, "/psd", power_fields);
    if (D && H) {
        ljgap__verr_add(e, "/psd/H", "give D or H (D = 3 - H), not both");
    } else if (D) {
        if (ljgap__v_num(e, D, "/psd/D", &s->D)) ljgap__v_D(e, "/psd/D", s->D, NULL);
    } else if (H) {
        double h;
        if (ljgap__v_num(e, H, "/psd/H", &h)) ljgap__v_D(e, "/psd/H", s->D = 3.0 - h, &h);
    } else {
        ljgap__verr_add(e, "/psd/D", "missing required field \"D\" (or H = 3 - D)");
    }
    k1 = ljgap__v_required(e, psd, "/psd", "k1", "the lowest wavenumber of the PSD");
    k1_ok = k1 && ljgap__v_k1(e, k1, "/psd/k1", chi, &s->k1);
    if (k1_ok)
        k1_ok = ljgap__v_in_core_range(e, "/psd/k1", "k1 (in units of 1/χ)", s->k1, 0, LJGAP_K_MAX);
    if (!k1_ok) s->k1 = NAN; /* so later checks against k1 do not pile up */
    k2 = ljgap__v_member(psd, "k2");
    s->k2 = INFINITY;
    if (k2 && !cJSON_IsNull(k2)) {
        if (!ljgap__v_num_pos(e, k2, "/psd/k2", &s->k2))
            s->k2 = NAN;
        else if (k1_ok && !(s->k2 * chi > s->k1))
            ljgap__verr_add(e, "/psd/k2", "k2 = %g must be greater than k1 = %g", s->k2,
                           s->k1 / chi);
        s->k2 *= chi;
        if (isfinite(s->k2))
            ljgap__v_in_core_range(e, "/psd/k2", "k2 (in units of 1/χ; null for ∞)", s->k2, 0,
                                  LJGAP_K_MAX);
    }
    parse_level(e, psd, mat, s);
    parse_power_errors(e, psd, mat, s);
}

/* Numbers of a table column (pointer base) into a new array of n entries. */
static double *table_column(ljgap__verr *e, const cJSON *arr, const char *base, size_t n)
{
    double *x = malloc(n * sizeof *x);
    const cJSON *it;
    size_t i = 0;
    char ptr[PTR_LEN];
    if (!x) {
        e->oom = 1;
        return NULL;
    }
    cJSON_ArrayForEach(it, arr)
    {
        snprintf(ptr, sizeof ptr, "%s/%zu", base, i);
        if (!ljgap__v_num_pos(e, it, ptr, &x[i])) x[i] = NAN;
        i++;
    }
    return x;
}

/* The table's optional P_err: one standard error per P, each finite and >= 0, converted like P
 * (server/uncert/input_error.c propagates them into the answers' input_error). */
static void parse_table_errors(ljgap__verr *e, const cJSON *psd, const ljgap_material *mat,
                               size_t nP, ljgap__psd_spec *s)
{
    const cJSON *pe = ljgap__v_member(psd, "P_err"), *it;
    char ptr[PTR_LEN];
    size_t i = 0, ne;
    if (!pe) return;
    ne = ljgap__v_array_of(e, pe, "/psd/P_err", 2, PSD_TABLE_MAX, "the standard errors of P");
    if (ne == 0) return;
    if (nP > 0 && ne != nP) {
        ljgap__verr_add(e, "/psd/P_err", "has %zu entries but P has %zu: give one error per P", ne,
                       nP);
        return;
    }
    if (!(s->P_err = malloc(ne * sizeof *s->P_err))) {
        e->oom = 1;
        return;
    }
    cJSON_ArrayForEach(it, pe)
    {
        snprintf(ptr, sizeof ptr, "/psd/P_err/%zu", i);
        s->P_err[i] = NAN;
        if (ljgap__v_num(e, it, ptr, &s->P_err[i]) && !(s->P_err[i] >= 0))
            ljgap__verr_add(e, ptr, "must be at least 0 (a standard error; got %g)", s->P_err[i]);
        else if (mat)
            s->P_err[i] = ljgap_units_P_to_dimless(mat, s->P_err[i]);
        i++;
    }
}

/* The table's optional P_corr: the correlation of the errors of knots i and i + 1 (n - 1 entries,
 * each in [-1, 1]); it qualifies P_err, which must be given. */
static void parse_table_corr(ljgap__verr *e, const cJSON *psd, size_t nP, ljgap__psd_spec *s)
{
    const cJSON *pc = ljgap__v_member(psd, "P_corr"), *it;
    char ptr[PTR_LEN];
    size_t i = 0, nc;
    if (!pc) return;
    if (!ljgap__v_member(psd, "P_err")) {
        ljgap__verr_add(e, "/psd/P_corr", "the correlations of the knots' errors need P_err");
        return;
    }
    nc = ljgap__v_array_of(e, pc, "/psd/P_corr", 1, PSD_TABLE_MAX - 1,
                          "the correlations of neighbouring knots' errors");
    if (nc == 0) return;
    if (nP > 0 && nc != nP - 1) {
        ljgap__verr_add(e, "/psd/P_corr",
                       "has %zu entries but P has %zu: give one correlation per pair of "
                       "neighbouring knots (%zu)",
                       nc, nP, nP - 1);
        return;
    }
    if (!(s->P_corr = malloc(nc * sizeof *s->P_corr))) {
        e->oom = 1;
        return;
    }
    cJSON_ArrayForEach(it, pc)
    {
        snprintf(ptr, sizeof ptr, "/psd/P_corr/%zu", i);
        s->P_corr[i] = 0;
        if (ljgap__v_num(e, it, ptr, &s->P_corr[i]) && !(fabs(s->P_corr[i]) <= 1)) {
            ljgap__verr_add(e, ptr, "a correlation lies in [-1, 1] (got %g)", s->P_corr[i]);
            s->P_corr[i] = 0;
        }
        i++;
    }
}

static void parse_table(ljgap__verr *e, const cJSON *psd, const ljgap_material *mat,
                        ljgap__psd_spec *s)
{
    const cJSON *k, *P, *tail;
    size_t nk = 0, nP = 0;
    char ptr[PTR_LEN];
    ljgap__v_only_fields(e, psd, "/psd", table_fields);
    k = ljgap__v_required(e, psd, "/psd", "k", "increasing wavenumbers");
    P = ljgap__v_required(e, psd, "/psd", "P", "the PSD at each k");
    if (k) nk = ljgap__v_array_of(e, k, "/psd/k", 2, PSD_TABLE_MAX, "table wavenumbers");
    if (P) nP = ljgap__v_array_of(e, P, "/psd/P", 2, PSD_TABLE_MAX, "table PSD values");
    if (nk > 1 && nP > 0 && nP != nk)
        ljgap__verr_add(e, "/psd/P", "has %zu entries but k has %zu: give one P per k", nP, nk);
    if (nk > 1 && nP == nk) {
        s->k = table_column(e, k, "/psd/k", nk);
        s->P = table_column(e, P, "/psd/P", nk);
        s->n = nk;
        for (size_t i = 0; mat && s->k && s->P && i < nk; i++) {
            s->k[i] = ljgap_units_k_to_dimless(mat, s->k[i]);
            s->P[i] = ljgap_units_P_to_dimless(mat, s->P[i]);
        }
        for (size_t i = 1; s->k && i < nk; i++) {
            snprintf(ptr, sizeof ptr, "/psd/k/%zu", i);
            if (isfinite(s->k[i]) && isfinite(s->k[i - 1]) && !(s->k[i] > s->k[i - 1]))
                ljgap__verr_add(e, ptr,
                               "k must be strictly increasing: k[%zu] = %g follows "
                               "k[%zu] = %g",
                               i, s->k[i], i - 1, s->k[i - 1]);
        }
        if (s->k && isfinite(s->k[0]) && !(s->k[0] > ljgap_k0()))
            ljgap__verr_add(e, "/psd/k/0",
                           "the table starts at k = %g, at or below k0 = %.5f: "
                           "%s",
                           s->k[0], ljgap_k0(), ljgap__v_k0_why());
    }
    parse_table_errors(e, psd, mat, nP, s);
    parse_table_corr(e, psd, nP, s);
    tail = ljgap__v_member(psd, "tail");
    if (tail && !cJSON_IsObject(tail)) {
        ljgap__verr_add(e, "/psd/tail", "must be an object {\"exponent\": q}");
    } else if (tail) {
        const cJSON *q;
        ljgap__v_only_fields(e, tail, "/psd/tail", tail_fields);
        q = ljgap__v_required(e, tail, "/psd/tail", "exponent", "P ∝ k^q beyond the last point");
        s->has_tail = 1;
        if (q && ljgap__v_num(e, q, "/psd/tail/exponent", &s->tail_q) && !(s->tail_q < -2))
            ljgap__verr_add(e, "/psd/tail/exponent",
                           "q = %g must be below -2, or the tail "
                           "carries infinite variance",
                           s->tail_q);
        if ((q = ljgap__v_member(tail, "exponent_err")) &&
            ljgap__v_num(e, q, "/psd/tail/exponent_err", &s->tail_q_err) && !(s->tail_q_err >= 0)) {
            ljgap__verr_add(e, "/psd/tail/exponent_err",
                           "must be at least 0 (the exponent's standard error; got %g)",
                           s->tail_q_err);
            s->tail_q_err = 0;
        }
    }
}

void ljgap__request_parse_psd_spec(ljgap__verr *e, const cJSON *root, const ljgap_material *mat,
                                  ljgap__psd_spec *s)
{
    static const char *const kinds[] = {"power", "table", NULL};
    const cJSON *psd = ljgap__v_required(e, root, "", "psd", "the surface's power spectral density");
    const cJSON *kind;
    if (!psd) return;
    if (!cJSON_IsObject(psd)) {
        ljgap__verr_add(e, "/psd", "must be an object {\"kind\": \"power\" | \"table\", ...}");
        return;
    }
    kind = ljgap__v_required(e, psd, "/psd", "kind", "\"power\" or \"table\"");
    if (!kind) return;
    switch (ljgap__v_pick(e, kind, "/psd/kind", kinds, "kind", "\"power\" or \"table\"")) {
    case 0:
        s->kind = LJGAP_PSD_POWER;
        parse_power(e, psd, mat, s);
        break;
    case 1:
        s->kind = LJGAP_PSD_TABLE;
        parse_table(e, psd, mat, s);
        break;
    }
}
