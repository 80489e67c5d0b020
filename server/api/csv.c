/* csv.c -- the CSV form of traction, pdf, sweep and simulation answers (csv.h).
 *
 * Written from the JSON answer itself (the cJSON tree the handler built, or the stored result
 * of a simulation job), so the two forms cannot disagree: the arrays that run along the points
 * become columns, every other field becomes one comment line named by its JSON path, with the
 * matching member of "error" as its ± error (for the si object's fields, of si's own "error",
 * placed as the handler places it). Nothing here computes: every number, the SI errors too, is
 * read from the answer.
 */
#include "csv.h"
#include "problems.h" /* ljgap__reply_problem */

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "textbuf.h"

/* The unit of a field, by its name (the last path component without an index). */
static const struct {
    const char *name, *unit;
} units[] = {
    {"g_ave", "eps"},
    {"g", "eps"},
    {"g_eq", "eps"},
    {"g_at_max", "eps"},
    {"mean", "eps"},
    {"sigma", "sigma0"},
    {"sigma_max", "sigma0"},
    {"sigma_std", "sigma0"},
    {"sigma_out", "sigma0"},
    {"residual", "sigma0"},
    {"tol", "sigma0"},
    {"dgamma_eff", "dgamma"},
    {"m0", "eps^2"},
    {"m0_grid", "eps^2"},
    {"m0_realized", "eps^2"},
    {"k0", "1/chi"},
    {"k2", "1/chi"},
    {"k_last", "1/chi"},
    {"L", "chi"},
    {"phi", "1/eps"},
    {"elapsed_ms", "ms"},
    {"chi_m", "m"},
    {"sigma0_Pa", "Pa"},
    {"E_star_Pa", "Pa"},
    {"g_eq_m", "m"},
    {"g_at_max_m", "m"},
    {"sigma_max_Pa", "Pa"},
    {"dgamma_eff_J_m2", "J/m^2"},
    {"m0_m2", "m^2"},
    {"g_ave_m", "m"},
    {"sigma_Pa", "Pa"},
    {"k2_per_m", "1/m"},
    {"g_m", "m"},
    {"phi_per_m", "1/m"},
};

static const char *unit_of(const char *name)
{
    for (size_t i = 0; i < sizeof units / sizeof units[0]; i++)
        if (strcmp(units[i].name, name) == 0) return units[i].unit;
    return NULL;
}

/* The fewest digits (15..17) that read back as v. */
static void put_number(ljgap__textbuf *b, double v)
{
    char s[40];
    for (int prec = 15; prec <= 17; prec++) {
        snprintf(s, sizeof s, "%.*g", prec, v);
        if (strtod(s, NULL) == v) break;
    }
    ljgap__textbuf_printf(b, "%s", s);
}

/* A cell (or a comment's value): number, empty for null ("inf" for an infinite cut-off), true
 * or false, or a string with control characters blanked so it stays on its line. */
static void put_value(ljgap__textbuf *b, const cJSON *v, const char *name, int cell)
{
    if (cJSON_IsNumber(v)) {
        put_number(b, v->valuedouble);
    } else if (cJSON_IsBool(v)) {
        ljgap__textbuf_printf(b, "%s", cJSON_IsTrue(v) ? "true" : "false");
    } else if (cJSON_IsString(v)) {
        for (const char *c = v->valuestring; *c; c++)
            ljgap__textbuf_put(b, (unsigned char)*c < 0x20 || *c == 0x7f ? " " : c, 1);
    } else if (cJSON_IsNull(v) && name && (!strcmp(name, "k2") || !strcmp(name, "k2_per_m"))) {
        ljgap__textbuf_printf(b, "inf"); /* null = an infinite cut-off, by contract */
    } else if (!cell) {
        ljgap__textbuf_printf(b, "null");
    }
}

/* "# path [unit] = value ± err" */
static void comment(ljgap__textbuf *b, const char *path, const char *name, const cJSON *v,
                    const cJSON *err)
{
    /* the model's relative differences (validity.c) are pure numbers, whatever their name */
    const char *u = strstr(path, "model.vs_discrete") ? NULL : unit_of(name);
    ljgap__textbuf_printf(b, "# %s", path);
    if (u && (cJSON_IsNumber(v) || cJSON_IsNull(v))) ljgap__textbuf_printf(b, " [%s]", u);
    ljgap__textbuf_printf(b, " = ");
    put_value(b, v, name, 0);
    if (cJSON_IsNumber(err)) {
        ljgap__textbuf_printf(b, " ± ");
        put_number(b, err->valuedouble);
    }
    ljgap__textbuf_printf(b, "\n");
}

/* One comment line per element of the array a: path[i] = value. */
static void comment_list(ljgap__textbuf *b, const char *path, const char *name, const cJSON *a)
{
    char p[200];
    int i = 0;
    for (const cJSON *c = a ? a->child : NULL; c; c = c->next, i++) {
        snprintf(p, sizeof p, "%s[%d]", path, i);
        comment(b, p, name, c, NULL);
    }
}

/* Comment lines for the scalar members of obj under prefix, each with the number of the same
 * name in err as its error; objects are walked into (err with them), arrays of strings are
 * listed, other arrays (the columns) and "error" itself are left out. */
static void comments(ljgap__textbuf *b, const char *prefix, const cJSON *obj, const cJSON *err)
{
    char p[160];
    for (const cJSON *c = obj ? obj->child : NULL; c; c = c->next) {
        const cJSON *e = cJSON_GetObjectItemCaseSensitive(err, c->string);
        if (!c->string || !strcmp(c->string, "error")) continue;
        snprintf(p, sizeof p, "%s%s%s", prefix, *prefix ? "." : "", c->string);
        if (cJSON_IsObject(c)) /* a nested object's errors: beside it, or in its own "error" */
            comments(b, p, c, e ? e : cJSON_GetObjectItemCaseSensitive(c, "error"));
        else if (cJSON_IsArray(c) && cJSON_IsString(c->child))
            comment_list(b, p, c->string, c);
        else if (!cJSON_IsArray(c))
            comment(b, p, c->string, c, e);
    }
}

/* ---- columns ---- */

typedef struct {
    const char *name;   /* header name */
    const char *unit;   /* header unit, or NULL */
    const cJSON *array; /* the values along the rows (missing cells are empty) */
    double factor;      /* 0: as they are; else each number times this */
} column;

#define MAX_COLS 32

static void put_header(ljgap__textbuf *b, const column *c, int n)
{
    for (int i = 0; i < n; i++) {
        ljgap__textbuf_printf(b, "%s%s", i ? "," : "", c[i].name);
        if (c[i].unit) ljgap__textbuf_printf(b, " [%s]", c[i].unit);
    }
    ljgap__textbuf_printf(b, "\n");
}

/* Rows 0 .. (length of the first column) - 1; prefix, when not NULL, is written first in
 * every row (the pdf's index and cut-off). */
static void put_rows(ljgap__textbuf *b, const char *prefix, const column *c, int n)
{
    int rows = cJSON_GetArraySize(c[0].array);
    const cJSON *cur[MAX_COLS];
    for (int k = 0; k < n; k++)
        cur[k] = c[k].array ? c[k].array->child : NULL;
    for (int i = 0; i < rows && !b->oom; i++) {
        if (prefix) ljgap__textbuf_printf(b, "%s", prefix);
        for (int k = 0; k < n; k++) {
            if (k) ljgap__textbuf_printf(b, ",");
            if (c[k].factor != 0 && cJSON_IsNumber(cur[k]))
                put_number(b, cur[k]->valuedouble * c[k].factor);
            else
                put_value(b, cur[k], c[k].name, 1);
            if (cur[k]) cur[k] = cur[k]->next;
        }
        ljgap__textbuf_printf(b, "\n");
    }
}

static const cJSON *get(const cJSON *o, const char *name)
{
    return cJSON_GetObjectItemCaseSensitive(o, name);
}

/* Appends a column (unit from the name unless given). */
static void add(column *c, int *n, const char *name, const char *unit, const cJSON *a, double f)
{
    if (*n >= MAX_COLS) return;
    c[*n] = (column){name, unit ? unit : unit_of(name), a, f};
    (*n)++;
}

static void csv_traction(ljgap__textbuf *b, const cJSON *ans)
{
    const cJSON *si = get(ans, "si"), *err = get(ans, "error");
    column c[MAX_COLS];
    int n = 0;
    ljgap__textbuf_printf(b, "# ljgap traction: the mean traction sigma against the mean gap "
                            "g_ave, one row per gap\n");
    comments(b, "", ans, err);
    add(c, &n, "g_ave", NULL, get(ans, "g_ave"), 0);
    add(c, &n, "sigma", NULL, get(ans, "sigma"), 0);
    add(c, &n, "sigma_err", "sigma0", get(err, "sigma"), 0);
    if (get(ans, "input_error")) /* the measurement's uncertainty, when the PSD has one */
        add(c, &n, "sigma_input_err", "sigma0", get(get(ans, "input_error"), "sigma"), 0);
    if (si) {
        add(c, &n, "g_ave_m", NULL, get(si, "g_ave_m"), 0);
        add(c, &n, "sigma_Pa", NULL, get(si, "sigma_Pa"), 0);
        add(c, &n, "sigma_Pa_err", "Pa", get(get(si, "error"), "sigma_Pa"), 0);
        if (get(si, "input_error"))
            add(c, &n, "sigma_Pa_input_err", "Pa", get(get(si, "input_error"), "sigma_Pa"), 0);
    }
    put_header(b, c, n);
    put_rows(b, NULL, c, n);
}

static void csv_pdf(ljgap__textbuf *b, const cJSON *ans)
{
    const cJSON *pdfs = get(ans, "pdfs"), *si = get(ans, "si");
    const cJSON *epdfs = get(get(ans, "error"), "pdfs"), *sipdfs = get(si, "pdfs");
    const cJSON *siepdfs = get(get(si, "error"), "pdfs");
    char p[64], pre[80];
    int np = cJSON_GetArraySize(pdfs);
    column c[MAX_COLS];
    int n = 0;
    ljgap__textbuf_printf(b, "# ljgap pdf: the gap PDF phi(g) for each cut-off k2, one row per "
                            "point; pdf is the index in pdfs[]\n");
    comments(b, "", ans, get(ans, "error"));
    for (int i = 0; i < np; i++) { /* phi_l1 has no value beside it: a line of its own */
        const cJSON *e = cJSON_GetArrayItem(epdfs, i), *se = cJSON_GetArrayItem(siepdfs, i);
        snprintf(p, sizeof p, "pdfs[%d]", i);
        comments(b, p, cJSON_GetArrayItem(pdfs, i), e);
        snprintf(p, sizeof p, "error.pdfs[%d].phi_l1", i);
        comment(b, p, "phi_l1", get(e, "phi_l1"), NULL);
        if ((e = cJSON_GetArrayItem(get(get(ans, "input_error"), "pdfs"), i))) {
            snprintf(p, sizeof p, "input_error.pdfs[%d].sigma", i);
            comment(b, p, "sigma", get(e, "sigma"), NULL);
        }
        if (!sipdfs) continue;
        snprintf(p, sizeof p, "si.pdfs[%d]", i);
        comments(b, p, cJSON_GetArrayItem(sipdfs, i), se);
        snprintf(p, sizeof p, "si.error.pdfs[%d].phi_l1", i);
        comment(b, p, "phi_l1", get(se, "phi_l1"), NULL);
        if ((se = cJSON_GetArrayItem(get(get(si, "input_error"), "pdfs"), i))) {
            snprintf(p, sizeof p, "si.input_error.pdfs[%d].sigma_Pa", i);
            comment(b, p, "sigma_Pa", get(se, "sigma_Pa"), NULL);
        }
    }
    ljgap__textbuf_printf(b, "pdf,k2 [1/chi],g [eps],phi [1/eps]%s\n",
                         si ? ",g_m [m],phi_per_m [1/m]" : "");
    for (int i = 0; i < np && !b->oom; i++) {
        const cJSON *pd = cJSON_GetArrayItem(pdfs, i), *sp = cJSON_GetArrayItem(sipdfs, i);
        ljgap__textbuf t = {0};
        n = 0;
        add(c, &n, "g", NULL, get(pd, "g"), 0);
        add(c, &n, "phi", NULL, get(pd, "phi"), 0);
        if (si) {
            add(c, &n, "g_m", NULL, get(sp, "g_m"), 0);
            add(c, &n, "phi_per_m", NULL, get(sp, "phi_per_m"), 0);
        }
        put_value(&t, get(pd, "k2"), "k2", 1);
        snprintf(pre, sizeof pre, "%d,%s,", i, t.s ? t.s : "");
        if (t.oom) b->oom = 1;
        free(t.s);
        put_rows(b, pre, c, n);
    }
}

/* The unit of a sweep's values: the varied field's, in SI when the psd was given in SI. */
static const char *vary_unit(const char *vary, int si_psd)
{
    if (!vary) return NULL;
    if (!strcmp(vary, "m0")) return si_psd ? "m^2" : "eps^2";
    if (!strcmp(vary, "k1") || !strcmp(vary, "k2")) return si_psd ? "1/m" : "1/chi";
    if (!strcmp(vary, "C")) return si_psd ? "m^(2D-4)" : "eps^2 chi^(2D-6)";
    return "1"; /* D */
}

static void csv_sweep(ljgap__textbuf *b, const cJSON *ans, int si_psd)
{
    /* the columns after values: each result's field, its error's column, from si.results? */
    static const struct {
        const char *name, *err;
        int si;
    } fields[] = {
        {"g_eq", "g_eq_err", 0},
        {"sigma_max", "sigma_max_err", 0},
        {"g_at_max", "g_at_max_err", 0},
        {"dgamma_eff", "dgamma_eff_err", 0},
        {"m0", NULL, 0},
        {"k0", NULL, 0},
        {"g_eq_m", "g_eq_m_err", 1},
        {"sigma_max_Pa", "sigma_max_Pa_err", 1},
        {"g_at_max_m", "g_at_max_m_err", 1},
        {"dgamma_eff_J_m2", "dgamma_eff_J_m2_err", 1},
        {"m0_m2", NULL, 1},
    };
    const cJSON *res = get(ans, "results"), *vary = get(ans, "vary"), *si = get(ans, "si");
    const cJSON *sires = get(si, "results");
    cJSON *cols = cJSON_CreateArray(); /* the results' fields, pulled out into arrays */
    column c[MAX_COLS];
    int n = 0, ok = cols != NULL, ie = 0;
    char ie_names[16][40]; /* NAME_input_err of the fields with an error */
    for (const cJSON *r = res ? res->child : NULL; r; r = r->next)
        ie |= get(r, "input_error") != NULL; /* the measurement's uncertainty: its columns */
    ljgap__textbuf_printf(b, "# ljgap sweep: the adhesion quantities for each value of the "
                            "varied PSD field, one row per value\n");
    comments(b, "", ans, NULL);
    for (int k = 0; k < 2; k++) { /* each result's model (validity.c), and its copy in si */
        const cJSON *list = k ? sires : res;
        int i = 0;
        for (const cJSON *r = list ? list->child : NULL; r; r = r->next, i++) {
            char p[64];
            snprintf(p, sizeof p, "%sresults[%d].model", k ? "si." : "", i);
            if (cJSON_IsObject(get(r, "model"))) comments(b, p, get(r, "model"), NULL);
        }
    }
    add(c, &n, "values", vary_unit(cJSON_GetStringValue(vary), si_psd), get(ans, "values"), 0);
    /* one array per field (and error): result i's member, or null when the value failed */
    for (size_t f = 0; ok && f < sizeof fields / sizeof fields[0]; f++) {
        const char *name = fields[f].name;
        const cJSON *src = fields[f].si ? sires : res;
        cJSON *a, *ea, *ia;
        if (fields[f].si && !si) break;
        a = cJSON_CreateArray();
        ea = fields[f].err ? cJSON_CreateArray() : NULL;
        ia = fields[f].err && ie ? cJSON_CreateArray() : NULL;
        ok = a && (!fields[f].err || ea) && (!(fields[f].err && ie) || ia) &&
             cJSON_AddItemToArray(cols, a) && (!ea || cJSON_AddItemToArray(cols, ea)) &&
             (!ia || cJSON_AddItemToArray(cols, ia));
        if (!ok) {
            cJSON_Delete(a);
            cJSON_Delete(ea);
            cJSON_Delete(ia);
            break;
        }
        for (const cJSON *r = src ? src->child : NULL; ok && r; r = r->next) {
            const cJSON *v = get(r, name), *e = get(get(r, "error"), name);
            const cJSON *u = get(get(r, "input_error"), name);
            ok =
                cJSON_AddItemToArray(a, v ? cJSON_Duplicate(v, 0) : cJSON_CreateNull()) &&
                (!ea || cJSON_AddItemToArray(ea, e ? cJSON_Duplicate(e, 0) : cJSON_CreateNull())) &&
                (!ia || cJSON_AddItemToArray(ia, u ? cJSON_Duplicate(u, 0) : cJSON_CreateNull()));
        }
        add(c, &n, name, NULL, a, 0);
        if (ea) add(c, &n, fields[f].err, unit_of(name), ea, 0);
        if (ia) {
            snprintf(ie_names[f], sizeof ie_names[0], "%s_input_err", name);
            add(c, &n, ie_names[f], unit_of(name), ia, 0);
        }
    }
    if (!ok) {
        b->oom = 1;
    } else {
        put_header(b, c, n);
        put_rows(b, NULL, c, n);
    }
    cJSON_Delete(cols);
}

static void csv_simulation(ljgap__textbuf *b, const cJSON *ans)
{
    const cJSON *err = get(ans, "error");
    column c[MAX_COLS];
    int n = 0;
    ljgap__textbuf_printf(b, "# ljgap simulations: the discrete numerical model's mean traction "
                            "against the mean gap, one row per gap\n");
    comments(b, "", ans, err);
    comment_list(b, "m0_realized", "m0_realized", get(ans, "m0_realized"));
    add(c, &n, "g_ave", NULL, get(ans, "g_ave"), 0);
    add(c, &n, "sigma", NULL, get(ans, "sigma"), 0);
    add(c, &n, "sigma_err", "sigma0", get(err, "sigma"), 0);
    add(c, &n, "sigma_std", NULL, get(ans, "sigma_std"), 0);
    add(c, &n, "sigma_out", NULL, get(ans, "sigma_out"), 0);
    add(c, &n, "residual", NULL, get(ans, "residual"), 0);
    add(c, &n, "jump", NULL, get(ans, "jump"), 0);
    put_header(b, c, n);
    put_rows(b, NULL, c, n);
}

int ljgap__csv_offers(const char *endpoint)
{
    static const char *const with_csv[] = {"traction", "pdf", "sweep", "simulations"};
    for (size_t i = 0; endpoint && i < sizeof with_csv / sizeof with_csv[0]; i++)
        if (strcmp(endpoint, with_csv[i]) == 0) return 1;
    return 0;
}

int ljgap__csv_render(const char *endpoint, const cJSON *ans, int si_psd, ljgap__reply *out)
{
    ljgap__textbuf b = {0};
    memset(out, 0, sizeof *out);
    if (!ljgap__csv_offers(endpoint) || !cJSON_IsObject(ans)) return -1;
    if (!strcmp(endpoint, "traction"))
        csv_traction(&b, ans);
    else if (!strcmp(endpoint, "pdf"))
        csv_pdf(&b, ans);
    else if (!strcmp(endpoint, "sweep"))
        csv_sweep(&b, ans, si_psd);
    else
        csv_simulation(&b, ans);
    if (b.oom) {
        free(b.s);
        return -1;
    }
    out->status = 200;
    out->body = b.s;
    out->len = b.len;
    out->content_type = LJGAP_CT_CSV;
    return 0;
}

int ljgap__csv_reply(const char *endpoint, ljgap__reply *r)
{
    cJSON *doc;
    ljgap__reply csv;
    if (r->status < 200 || r->status > 299 || strcmp(r->content_type, "application/json") != 0)
        return 0;
    doc = cJSON_ParseWithLength(r->body, r->len);
    if (!doc || ljgap__csv_render(endpoint, doc, 0, &csv) != 0) {
        cJSON_Delete(doc);
        ljgap__reply_free(r);
        ljgap__reply_problem(r, "out-of-memory", "the server ran out of memory");
        return -1;
    }
    cJSON_Delete(doc);
    ljgap__reply_free(r);
    *r = csv;
    return 0;
}
