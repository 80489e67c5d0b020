/* request.c -- validation of compute requests (docs/api.md) into ljgap__request.
 *
 * Bad input is the caller's: everything the contract rules out is caught here, before the
 * core runs, and reported with a JSON pointer (RFC 6901) and one clear sentence. The walk
 * does not stop at the first problem: every field is checked and every problem recorded
 * (up to LJGAP_MAX_ERRORS; the count of the rest goes into the problem's detail), so a
 * caller fixes a request in one round trip.
 *
 * Unknown fields, at the top level and inside psd, g_ave, grid and tail, are rejected
 * too: they are usually typos ("m_0", "tolerance") that would otherwise be silently
 * ignored. The contract may add fields later (api.md: "Fields may be added"); each one
 * added must then be listed in the tables below.
 *
 * The rules of the model itself (theory.md §1): 2 < D < 3 for the quasi-fractal PSD (6),
 * k1 > k0 ≈ 0.46978 (below k0 the gap transfer (14) has a pole, the negative-stiffness
 * instability of (19)), k2 > k1, and positive finite levels.
 *
 * Physical units (api.md "Physical units", theory.md §1 and §6): a "material" block gives E*
 * (directly, or from E1, ν1, E2, ν2 with 0 < E and -1 < ν <= 0.5), Δγ > 0 and ε > 0; with it,
 * "units":"SI" says the psd object is in SI (k in 1/m, C in m^(2D-4), m0 in m², h_rms in m,
 * table P in m⁴). The psd is converted here (core/units.c), before the k1 > k0 check, which
 * is a statement about χk1. Only a power law's C waits: its conversion depends on D, which a
 * sweep may vary, so ljgap__psd_from_spec converts it. Everything else (g_ave, grids, pdf
 * cut-offs) stays dimensionless.
 *
 * psd takes a height map instead (issue 15): request_topo.c checks it with the validators
 * below (ljgap__v_*).
 */
#include "request.h"
#include "textbuf.h" /* ljgap__utf8_span */

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Physical ranges of the material block and the contact sphere (SI). Far beyond any solid, but
 * bounded: with E*, Δγ, ε and R anywhere in double range, the contact answer's Tabor
 * parameters and Maugis-Dugdale error under- or overflowed to NaN (found by the fuzzer). */
#define E_MIN 1e3 /* moduli E*, E1, E2 (Pa): a soft gel to beyond diamond */
#define E_MAX 1e13
#define DGAMMA_MIN 1e-6 /* work of adhesion Δγ (J/m²) */
#define DGAMMA_MAX 1e3
#define EPS_MIN 1e-12 /* Lennard-Jones length ε (m) */
#define EPS_MAX 1e-6
#define R_MIN 1e-12 /* sphere radius R (m) */
#define R_MAX 1e6
#define PTR_LEN 96 /* room for every pointer built from known names */

static const char *const common_fields[] = {"psd",        "method",      "tol",  "vmax",
                                            "fixed_vmax", "samples",     "seed", "material",
                                            "units",      "input_error", NULL};
static const char *const contact_fields[] = {"R", NULL};
static const char *const material_fields[] = {"E_star", "E1",     "nu1",     "E2",
                                              "nu2",    "dgamma", "epsilon", NULL};
static const char *const traction_fields[] = {"g_ave", NULL};
static const char *const pdf_fields[] = {"g_ave", "k2", "grid", NULL};
static const char *const sweep_fields[] = {"vary", "values", NULL};
static const char *const range_fields[] = {"min", "max", "n", NULL};
/* A simulation takes the dimensionless psd and its own fields only (no method, material). */
static const char *const sim_fields[] = {"psd", "n",       "L", "realizations", "seed", "g_ave",
                                         "tol", "k_split", NULL};

void ljgap__verr_add(ljgap__verr *e, const char *ptr, const char *fmt, ...)
{
    char detail[400];
    va_list ap;
    cJSON *item = NULL;
    e->n++;
    if (e->n > LJGAP_MAX_ERRORS) return;
    va_start(ap, fmt);
    vsnprintf(detail, sizeof detail, fmt, ap);
    va_end(ap);
    item = cJSON_CreateObject();
    if (!item || !cJSON_AddStringToObject(item, "pointer", ptr) ||
        !cJSON_AddStringToObject(item, "detail", detail)) {
        e->oom = 1;
        cJSON_Delete(item);
        return;
    }
    cJSON_AddItemToArray(e->errors, item);
}

/* Bytes of s to quote in a message: at most max, whole characters only. */
static int quote_len(const char *s, size_t max)
{
    return (int)ljgap__utf8_span(s, strnlen(s, max));
}

/* Pointer base + "/" + key with ~ and / escaped (RFC 6901 §3); malloc'd, NULL on OOM. */
static char *ptr_key(const char *base, const char *key)
{
    size_t n = strlen(base) + 2;
    for (const char *c = key; *c; c++)
        n += (*c == '~' || *c == '/') ? 2 : 1;
    char *p = malloc(n), *o;
    if (!p) return NULL;
    o = p + sprintf(p, "%s/", base);
    for (const char *c = key; *c; c++) {
        if (*c == '~')
            *o++ = '~', *o++ = '0';
        else if (*c == '/')
            *o++ = '~', *o++ = '1';
        else
            *o++ = *c;
    }
    *o = '\0';
    return p;
}

static int in_list(const char *name, const char *const *list)
{
    for (; list && *list; list++)
        if (strcmp(name, *list) == 0) return 1;
    return 0;
}

/* Every member of obj (pointer base) must be named in a or b, and appear once. */
static void only_fields(ljgap__verr *e, const cJSON *obj, const char *base, const char *const *a,
                        const char *const *b)
{
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int known = in_list(it->string, a) || in_list(it->string, b);
        int dup = 0;
        /* only known names are looked for again: a bounded number of them */
        for (const cJSON *p = obj->child; known && p != it; p = p->next)
            dup = dup || strcmp(p->string, it->string) == 0;
        if (known && !dup) continue;
        char *ptr = ptr_key(base, it->string);
        if (!ptr) {
            e->oom = 1;
            return;
        }
        if (dup)
            ljgap__verr_add(e, ptr, "field \"%s\" appears more than once", it->string);
        else
            ljgap__verr_add(e, ptr,
                           "unknown field \"%.*s\" (a typo? it is not part of this "
                           "request in the v1 contract)",
                           quote_len(it->string, 60), it->string);
        free(ptr);
    }
}

static const cJSON *member(const cJSON *obj, const char *name)
{
    return cJSON_GetObjectItemCaseSensitive(obj, name);
}

/* obj[name], recording "missing" at base/name when absent. */
static const cJSON *required(ljgap__verr *e, const cJSON *obj, const char *base, const char *name,
                             const char *what)
{
    const cJSON *it = member(obj, name);
    if (!it) {
        char ptr[PTR_LEN];
        snprintf(ptr, sizeof ptr, "%s/%s", base, name);
        ljgap__verr_add(e, ptr, "missing required field \"%s\" (%s)", name, what);
    }
    return it;
}

/* A finite JSON number at it (pointer ptr) into *x; records the problem and returns 0 if not. */
static int num(ljgap__verr *e, const cJSON *it, const char *ptr, double *x)
{
    if (!cJSON_IsNumber(it)) {
        ljgap__verr_add(e, ptr, "must be a number");
        return 0;
    }
    if (!isfinite(it->valuedouble)) {
        ljgap__verr_add(e, ptr, "must be a finite number (this one overflows a double)");
        return 0;
    }
    *x = it->valuedouble;
    return 1;
}

/* A finite number > 0. */
static int num_pos(ljgap__verr *e, const cJSON *it, const char *ptr, double *x)
{
    if (!num(e, it, ptr, x)) return 0;
    if (!(*x > 0)) {
        ljgap__verr_add(e, ptr, "must be positive (got %g)", *x);
        return 0;
    }
    return 1;
}

/* An integer-valued number in [lo, hi]. */
static int num_int(ljgap__verr *e, const cJSON *it, const char *ptr, double lo, double hi, double *x)
{
    if (!num(e, it, ptr, x)) return 0;
    if (*x != floor(*x) || *x < lo || *x > hi) {
        ljgap__verr_add(e, ptr, "must be an integer from %.17g to %.17g (got %.17g)", lo, hi, *x);
        return 0;
    }
    return 1;
}

/* A JSON array of min..max entries at it; returns its size or 0 after recording why not. */
static size_t array_of(ljgap__verr *e, const cJSON *it, const char *ptr, size_t min, size_t max,
                       const char *what)
{
    if (!cJSON_IsArray(it)) {
        ljgap__verr_add(e, ptr, "must be an array (%s)", what);
        return 0;
    }
    size_t n = (size_t)cJSON_GetArraySize(it);
    if (n < min || n > max) {
        ljgap__verr_add(e, ptr, "has %zu entries; give %zu to %zu (%s)", n, min, max, what);
        return 0;
    }
    return n;
}

/* Index of the string at it (pointer ptr) in names (NULL-terminated), or -1 after recording
 * why not; what lists the choices for the message, field names the thing chosen. */
static int pick(ljgap__verr *e, const cJSON *it, const char *ptr, const char *const *names,
                const char *field, const char *what)
{
    if (!cJSON_IsString(it)) {
        ljgap__verr_add(e, ptr, "must be a string: %s", what);
        return -1;
    }
    for (int i = 0; names[i]; i++)
        if (strcmp(it->valuestring, names[i]) == 0) return i;
    ljgap__verr_add(e, ptr, "unknown %s \"%.*s\": expected %s", field,
                   quote_len(it->valuestring, 40), it->valuestring, what);
    return -1;
}

static const char *k0_why(void)
{
    return "below k0 the gap transfer (14) has a pole, the negative-stiffness instability "
           "of (19); the theory needs k1 > k0";
}

/* A lower cut-off: positive, finite and, times chi (1, or χ in m when given in 1/m), above k0.
 * *k1 receives the dimensionless value. */
static int check_k1(ljgap__verr *e, const cJSON *it, const char *ptr, double chi, double *k1)
{
    double raw;
    if (!num_pos(e, it, ptr, &raw)) return 0;
    *k1 = raw * chi;
    if (*k1 > ljgap_k0()) return 1;
    if (chi == 1)
        ljgap__verr_add(e, ptr, "k1 = %g is at or below k0 = %.5f: %s", *k1, ljgap_k0(), k0_why());
    else
        ljgap__verr_add(e, ptr, "k1 = %g 1/m gives χk1 = %g (χ = %g m), at or below k0 = %.5f: %s",
                       raw, *k1, chi, ljgap_k0(), k0_why());
    return 0;
}

/* D (or 3 - H, when h is the given H) must lie in (2, 3). */
static int check_D(ljgap__verr *e, const char *ptr, double D, const double *h)
{
    char given[80] = "";
    if (D > 2 && D < 3) return 1;
    if (h) snprintf(given, sizeof given, "H = %g gives ", *h);
    ljgap__verr_add(e, ptr,
                   "%sD = %g, outside (2, 3): the quasi-fractal PSD (6) needs 2 < D < 3 "
                   "(0 < H < 1)",
                   given, D);
    return 0;
}

/* x within the range the solvers accept (ljgap.h), else a problem at ptr naming it: the core
 * would refuse it too, but could only point at "/psd". what names x in the message. */
static int in_core_range(ljgap__verr *e, const char *ptr, const char *what, double x, double lo,
                         double hi)
{
    if (!(x >= lo && x <= hi)) {
        ljgap__verr_add(e, ptr, "%s = %g is outside [%g, %g], the range this service computes", what,
                       x, lo, hi);
        return 0;
    }
    return 1;
}

/* Uniform range {"min","max","n"} at it (pointer base): 0 < min < max, n integer 2..nmax. */
static int parse_range(ljgap__verr *e, const cJSON *it, const char *base, double nmax, double out[3])
{
    char ptr[PTR_LEN];
    const cJSON *lo, *hi, *n;
    int ok = 1;
    only_fields(e, it, base, range_fields, NULL);
    lo = required(e, it, base, "min", "the first mean gap");
    hi = required(e, it, base, "max", "the last mean gap");
    n = required(e, it, base, "n", "number of points");
    snprintf(ptr, sizeof ptr, "%s/min", base);
    ok &= lo && num_pos(e, lo, ptr, &out[0]);
    snprintf(ptr, sizeof ptr, "%s/max", base);
    if (hi && num_pos(e, hi, ptr, &out[1])) {
        if (ok && !(out[1] > out[0])) {
            ljgap__verr_add(e, ptr, "max = %g must be greater than min = %g", out[1], out[0]);
            ok = 0;
        }
    } else {
        ok = 0;
    }
    snprintf(ptr, sizeof ptr, "%s/n", base);
    ok &= n && num_int(e, n, ptr, 2, nmax, &out[2]);
    return ok;
}

/* A Poisson ratio in (-1, 0.5] at obj[name] (pointer /material/name). */
static int poisson(ljgap__verr *e, const cJSON *obj, const char *name, double *nu)
{
    char ptr[PTR_LEN];
    const cJSON *it = required(e, obj, "/material", name, "Poisson's ratio, -1 < ν <= 0.5");
    snprintf(ptr, sizeof ptr, "/material/%s", name);
    if (!it || !num(e, it, ptr, nu)) return 0;
    if (*nu > -1 && *nu <= 0.5) return 1;
    ljgap__verr_add(e, ptr, "ν = %g is outside (-1, 0.5], where an isotropic solid is stable", *nu);
    return 0;
}

/* A number in [lo, hi] at obj[name] (pointer /material/name), recording "missing" if absent. */
static int positive(ljgap__verr *e, const cJSON *obj, const char *name, const char *what, double lo,
                    double hi, double *x)
{
    char ptr[PTR_LEN];
    const cJSON *it = required(e, obj, "/material", name, what);
    snprintf(ptr, sizeof ptr, "/material/%s", name);
    return it && num_pos(e, it, ptr, x) && in_core_range(e, ptr, name, *x, lo, hi);
}

/* The material block (required when need): E* directly or from two bodies, Δγ, ε. */
static void parse_material(ljgap__verr *e, const cJSON *root, int need, ljgap__request *rq)
{
    static const char *const pair[] = {"E1", "nu1", "E2", "nu2"};
    const cJSON *m = member(root, "material"), *Es;
    double E = NAN, E1 = NAN, E2 = NAN, nu1 = NAN, nu2 = NAN, dg = NAN, eps = NAN;
    int ok = 1;
    if (!m) {
        if (need)
            ljgap__verr_add(e, "/material",
                           "missing required field \"material\" ({\"E_star\"} or {\"E1\", "
                           "\"nu1\", \"E2\", \"nu2\"}, with \"dgamma\" and \"epsilon\"; SI)");
        return;
    }
    if (!cJSON_IsObject(m)) {
        ljgap__verr_add(e, "/material", "must be an object {\"E_star\", \"dgamma\", \"epsilon\"}");
        return;
    }
    only_fields(e, m, "/material", material_fields, NULL);
    if ((Es = member(m, "E_star"))) {
        for (int i = 0; i < 4; i++) {
            char ptr[PTR_LEN];
            if (!member(m, pair[i])) continue;
            snprintf(ptr, sizeof ptr, "/material/%s", pair[i]);
            ljgap__verr_add(e, ptr, "give E_star or E1, nu1, E2, nu2, not both");
            ok = 0;
        }
        ok &= num_pos(e, Es, "/material/E_star", &E) &&
              in_core_range(e, "/material/E_star", "E_star", E, E_MIN, E_MAX);
    } else if (!member(m, "E1") && !member(m, "E2") && !member(m, "nu1") && !member(m, "nu2")) {
        ljgap__verr_add(e, "/material/E_star",
                       "missing the modulus: give E_star (Pa) or E1, nu1, E2, nu2 "
                       "(1/E* = (1-ν1²)/E1 + (1-ν2²)/E2)");
        ok = 0;
    } else {
        ok &= positive(e, m, "E1", "Young's modulus of body 1, Pa", E_MIN, E_MAX, &E1);
        ok &= poisson(e, m, "nu1", &nu1);
        ok &= positive(e, m, "E2", "Young's modulus of body 2, Pa", E_MIN, E_MAX, &E2);
        ok &= poisson(e, m, "nu2", &nu2);
        if (ok && ljgap_units_E_star(E1, nu1, E2, nu2, &E) != LJGAP_OK) {
            ljgap__verr_add(e, "/material",
                           "E* = 1/((1-ν1²)/E1 + (1-ν2²)/E2) is not a finite "
                           "positive number");
            ok = 0;
        } else if (ok) {
            ok = in_core_range(e, "/material", "E* = 1/((1-ν1²)/E1 + (1-ν2²)/E2)", E, E_MIN, E_MAX);
        }
    }
    ok &= positive(e, m, "dgamma", "work of adhesion Δγ of the flat surfaces, J/m²", DGAMMA_MIN,
                   DGAMMA_MAX, &dg);
    ok &= positive(e, m, "epsilon", "Lennard-Jones length ε, m", EPS_MIN, EPS_MAX, &eps);
    if (!ok) return;
    if (ljgap_material_set(&rq->mat, E, dg, eps) != LJGAP_OK ||
        !(isfinite(ljgap_units_chi(&rq->mat)) && ljgap_units_chi(&rq->mat) > 0 &&
          isfinite(ljgap_units_sigma0(&rq->mat)) && ljgap_units_sigma0(&rq->mat) > 0)) {
        ljgap__verr_add(e, "/material",
                       "the scales χ = 3ε²E* /(16Δγ) and σ0 = 16Δγ/(9√3ε) "
                       "are not finite positive numbers");
        return;
    }
    rq->has_material = 1;
}

/* "units": absent or "dimensionless" (0), "SI" (1, needs material), -1 after a problem. */
static int parse_units(ljgap__verr *e, const cJSON *root)
{
    static const char *const names[] = {"dimensionless", "SI", NULL};
    const cJSON *u = member(root, "units");
    int i;
    if (!u) return 0;
    i = pick(e, u, "/units", names, "units", "\"SI\" or \"dimensionless\"");
    if (i == 1 && !member(root, "material")) {
        ljgap__verr_add(e, "/units",
                       "\"units\":\"SI\" needs a \"material\" block (E*, Δγ, ε "
                       "set the scales)");
        return -1;
    }
    return i;
}

static void parse_common(ljgap__verr *e, const cJSON *root, const ljgap__limits *lim,
                         ljgap__request *rq)
{
    static const char *const names[] = {"pde", "paper", "montecarlo", NULL};
    static const ljgap_method methods[] = {LJGAP_METHOD_PDE, LJGAP_METHOD_PAPER, LJGAP_METHOD_MC};
    const cJSON *m = member(root, "method"), *it;
    double x;
    int i = m ? pick(e, m, "/method", names, "method", "\"pde\", \"paper\" or \"montecarlo\"") : -1;
    if (i >= 0) {
        rq->opts.method = methods[i];
        rq->method = names[i];
    }
    if ((it = member(root, "tol")) && num(e, it, "/tol", &x)) {
        if (x > 0 && x <= 0.1)
            rq->opts.tol = x;
        else
            ljgap__verr_add(e, "/tol", "tol = %g is outside (0, 0.1]", x);
    }
    if ((it = member(root, "vmax")) && num(e, it, "/vmax", &x)) {
        if (x > 0 && x <= 1)
            rq->opts.vmax = x;
        else
            ljgap__verr_add(e, "/vmax", "vmax = %g is outside (0, 1]", x);
        if (rq->opts.method != LJGAP_METHOD_PAPER)
            ljgap_warn(&rq->warn, "vmax is used by method \"paper\" only and was ignored");
    }
    rq->input_error = 1;
    if ((it = member(root, "input_error"))) {
        if (!cJSON_IsBool(it))
            ljgap__verr_add(e, "/input_error", "input_error must be true or false");
        else
            rq->input_error = cJSON_IsTrue(it);
    }
    if ((it = member(root, "fixed_vmax"))) {
        if (!cJSON_IsBool(it))
            ljgap__verr_add(e, "/fixed_vmax", "fixed_vmax must be true or false");
        else if ((rq->opts.fixed_vmax = cJSON_IsTrue(it)) && rq->opts.method != LJGAP_METHOD_PAPER)
            ljgap_warn(&rq->warn, "fixed_vmax is used by method \"paper\" only and was ignored");
    }
    if ((it = member(root, "samples")) &&
        num_int(e, it, "/samples", 100, (double)lim->max_samples, &x)) {
        rq->opts.samples = (long)x;
        if (rq->opts.method != LJGAP_METHOD_MC)
            ljgap_warn(&rq->warn, "samples is used by method \"montecarlo\" only and was "
                                  "ignored");
    }
    if ((it = member(root, "seed")) && num_int(e, it, "/seed", 0, LJGAP_SEED_MAX, &x)) {
        rq->opts.seed = (unsigned long)x;
        if (rq->opts.method != LJGAP_METHOD_MC)
            ljgap_warn(&rq->warn, "seed is used by method \"montecarlo\" only and was ignored");
    }
}

/* A JSON array of 1..lim->max_points entries at it into a new rq->x (values read later);
 * returns the number of entries, 0 after recording why not. */
static size_t points(ljgap__verr *e, const cJSON *it, const char *ptr, const ljgap__limits *lim,
                     const char *what, ljgap__request *rq)
{
    size_t n = array_of(e, it, ptr, 1, (size_t)lim->max_points, what);
    if (!n) return 0;
    if (!(rq->x = malloc(n * sizeof *rq->x))) {
        e->oom = 1;
        return 0;
    }
    rq->nx = n;
    return n;
}

static void parse_traction(ljgap__verr *e, const cJSON *root, const ljgap__limits *lim,
                           ljgap__request *rq)
{
    const cJSON *g = required(e, root, "", "g_ave", "{\"min\",\"max\",\"n\"} or an array");
    double r[3];
    if (!g) return;
    if (cJSON_IsObject(g)) {
        if (!parse_range(e, g, "/g_ave", (double)lim->max_points, r) ||
            !in_core_range(e, "/g_ave/min", "g_ave", r[0], LJGAP_G_MIN, LJGAP_G_MAX) ||
            !in_core_range(e, "/g_ave/max", "g_ave", r[1], LJGAP_G_MIN, LJGAP_G_MAX))
            return;
        if (!(rq->x = malloc((size_t)r[2] * sizeof *rq->x))) {
            e->oom = 1;
            return;
        }
        rq->nx = (size_t)r[2];
        for (size_t i = 0; i < rq->nx; i++)
            rq->x[i] = r[0] + (r[1] - r[0]) * (double)i / (double)(rq->nx - 1);
    } else if (cJSON_IsArray(g)) {
        const cJSON *it;
        size_t i = 0;
        char ptr[PTR_LEN];
        if (!points(e, g, "/g_ave", lim, "mean gaps", rq)) return;
        cJSON_ArrayForEach(it, g)
        {
            snprintf(ptr, sizeof ptr, "/g_ave/%zu", i);
            if (num_pos(e, it, ptr, &rq->x[i]))
                in_core_range(e, ptr, "g_ave", rq->x[i], LJGAP_G_MIN, LJGAP_G_MAX);
            i++;
        }
    } else {
        ljgap__verr_add(e, "/g_ave", "must be {\"min\",\"max\",\"n\"} or an array of mean gaps");
    }
}

static void parse_pdf(ljgap__verr *e, const cJSON *root, const ljgap__limits *lim, ljgap__request *rq)
{
    const cJSON *g = required(e, root, "", "g_ave", "the mean gap");
    const cJSON *k2 = required(e, root, "", "k2", "snapshot cut-offs, null for ∞");
    const cJSON *grid = member(root, "grid"), *it;
    size_t i = 0;
    char ptr[PTR_LEN];
    int infinite = 0, k1_known = 0;
    double k1 = 0;
    if (g && num_pos(e, g, "/g_ave", &rq->g_ave))
        in_core_range(e, "/g_ave", "g_ave", rq->g_ave, LJGAP_G_MIN, LJGAP_G_MAX);
    if (grid && !cJSON_IsObject(grid))
        ljgap__verr_add(e, "/grid", "must be an object {\"min\",\"max\",\"n\"}");
    else if (grid)
        rq->has_grid = parse_range(e, grid, "/grid", (double)lim->max_points, rq->grid);
    if (!k2 || !points(e, k2, "/k2", lim, "snapshot cut-offs", rq)) return;
    /* what the psd allows, when it was readable */
    if (rq->psd.kind == LJGAP_PSD_POWER && !isnan(rq->psd.k1) && !isnan(rq->psd.k2)) {
        k1 = rq->psd.k1, k1_known = 1;
        infinite = isinf(rq->psd.k2);
    } else if (rq->psd.kind == LJGAP_PSD_TABLE && rq->psd.k && isfinite(rq->psd.k[0])) {
        k1 = rq->psd.k[0], k1_known = 1;
        infinite = rq->psd.has_tail;
    }
    cJSON_ArrayForEach(it, k2)
    {
        snprintf(ptr, sizeof ptr, "/k2/%zu", i);
        rq->x[i] = INFINITY;
        if (cJSON_IsNull(it)) {
            if (k1_known && !infinite)
                ljgap__verr_add(e, ptr,
                               "null (∞) needs a PSD with infinite support (power law "
                               "without k2, or a table with a tail)");
        } else if (num_pos(e, it, ptr, &rq->x[i]) && k1_known && !(rq->x[i] > k1)) {
            ljgap__verr_add(e, ptr, "k2 = %g must be greater than the PSD's k1 = %g", rq->x[i], k1);
        }
        i++;
    }
}

static void parse_sweep(ljgap__verr *e, const cJSON *root, const ljgap__limits *lim,
                        ljgap__request *rq)
{
    static const char *const names[] = {"m0", "C", "D", "k1", "k2", NULL};
    static const ljgap__vary varies[] = {LJGAP_VARY_M0, LJGAP_VARY_C, LJGAP_VARY_D, LJGAP_VARY_K1,
                                        LJGAP_VARY_K2};
    const cJSON *v = required(e, root, "", "vary", "\"m0\", \"C\", \"D\", \"k1\" or \"k2\"");
    const cJSON *vals = required(e, root, "", "values", "the values of the varied field");
    const cJSON *it;
    size_t i = 0;
    char ptr[PTR_LEN];
    double chi = rq->si_psd ? ljgap_units_chi(&rq->mat) : 1, kt;
    int k =
        v ? pick(e, v, "/vary", names, "field to vary", "\"m0\", \"C\", \"D\", \"k1\" or \"k2\"")
          : -1;
    int vary_ok = k >= 0;
    if (rq->psd.kind == LJGAP_PSD_TABLE)
        ljgap__verr_add(e, "/psd/kind", "a sweep varies a power-law PSD: kind must be \"power\"");
    if (vary_ok) {
        rq->vary = varies[k];
        rq->vary_name = names[k];
    }
    if (!vals || !points(e, vals, "/values", lim, "values to sweep", rq)) return;
    cJSON_ArrayForEach(it, vals)
    {
        double *x = &rq->x[i];
        snprintf(ptr, sizeof ptr, "/values/%zu", i++);
        if (!vary_ok) {
            num(e, it, ptr, x);
        } else if (rq->vary == LJGAP_VARY_D) {
            if (num(e, it, ptr, x)) check_D(e, ptr, *x, NULL);
        } else if (rq->vary == LJGAP_VARY_K1) {
            /* x keeps the value as given; ljgap__request_sweep_spec converts it */
            if (check_k1(e, it, ptr, chi, &kt) && (*x = it->valuedouble, 1) && !isnan(rq->psd.k2) &&
                !(kt < rq->psd.k2))
                ljgap__verr_add(e, ptr, "k1 = %g must be below the PSD's k2 = %g", *x,
                               rq->psd.k2 / chi);
        } else if (rq->vary == LJGAP_VARY_K2) {
            /* the unknown short-wavelength end: k2 in the PSD's units, above k1 */
            if (num_pos(e, it, ptr, x) && isfinite(rq->psd.k1) && !(*x * chi > rq->psd.k1))
                ljgap__verr_add(e, ptr, "k2 = %g must be above the PSD's k1 = %g", *x,
                               rq->psd.k1 / chi);
            else if (*x > 0)
                in_core_range(e, ptr, "k2 (in units of 1/χ)", *x * chi, 0, LJGAP_K_MAX);
        } else {
            if (num_pos(e, it, ptr, x) && rq->vary == LJGAP_VARY_M0)
                in_core_range(e, ptr, "m0 (in units of ε²)",
                              rq->si_psd ? ljgap_units_var_to_dimless(&rq->mat, *x) : *x, 0,
                              LJGAP_M0_MAX);
        }
    }
}

int ljgap__request_parse(ljgap__endpoint ep, const cJSON *root, const ljgap__limits *lim,
                        ljgap__request *rq, ljgap__verr *e)
{
    static const char *const *const extra[] = {NULL,         traction_fields, pdf_fields,
                                               sweep_fields, contact_fields,  NULL};
    const cJSON *R;
    int si;
    memset(rq, 0, sizeof *rq);
    rq->ep = ep;
    ljgap_opts_default(&rq->opts);
    rq->method = "pde";
    rq->psd.k1 = rq->psd.k2 = NAN; /* unknown until read */
    rq->psd.kind = (ljgap_psd_kind)-1;
    if (!cJSON_IsObject(root)) {
        ljgap__verr_add(e, "", "the request body must be a JSON object");
        return e->n;
    }
    if (ep == LJGAP_EP_SIMULATION) {
        rq->method = "numerical";
        only_fields(e, root, "", sim_fields, NULL);
        ljgap__request_parse_psd_spec(e, root, NULL, &rq->psd);
        ljgap__request_parse_simulation(e, root, lim, rq);
        return e->n;
    }
    if (ep == LJGAP_EP_PSD) {
        ljgap__request_parse_psd(e, root, lim, 0, rq);
        return e->n;
    }
    if (ep == LJGAP_EP_COMBINE) {
        ljgap__combine_parse(e, root, rq);
        parse_material(e, root, 0, rq); /* optional: the theory's domain, as /v1/psd */
        return e->n;
    }
    only_fields(e, root, "", common_fields, extra[ep]);
    parse_common(e, root, lim, rq);
    parse_material(e, root, ep == LJGAP_EP_CONTACT, rq);
    si = parse_units(e, root);
    /* an SI psd cannot be checked without a valid material: its problems come first */
    if (si == 0 || (si == 1 && rq->has_material)) {
        rq->si_psd = si;
        ljgap__request_parse_psd_spec(e, root, si ? &rq->mat : NULL, &rq->psd);
    }
    switch (ep) {
    case LJGAP_EP_ADHESION:
    case LJGAP_EP_SIMULATION: /* parsed above */
    case LJGAP_EP_PSD:
    case LJGAP_EP_COMBINE:
        break;
    case LJGAP_EP_TRACTION:
        parse_traction(e, root, lim, rq);
        break;
    case LJGAP_EP_PDF:
        parse_pdf(e, root, lim, rq);
        break;
    case LJGAP_EP_SWEEP:
        parse_sweep(e, root, lim, rq);
        break;
    case LJGAP_EP_CONTACT:
        if ((R = required(e, root, "", "R", "the sphere's radius, m")) &&
            num_pos(e, R, "/R", &rq->R))
            in_core_range(e, "/R", "R (m)", rq->R, R_MIN, R_MAX);
        break;
    }
    return e->n;
}

void ljgap__request_free(ljgap__request *rq)
{
    if (!rq) return;
    free(rq->psd.k);
    free(rq->psd.P);
    free(rq->psd.P_err);
    free(rq->psd.P_corr);
    rq->psd.P_corr = NULL;
    free(rq->x);
    free(rq->topo.h);
    rq->psd.k = rq->psd.P = rq->psd.P_err = rq->x = rq->topo.h = NULL;
    ljgap__combine_spec_free(rq->combine);
    rq->combine = NULL;
    cJSON_Delete(rq->source);
    rq->source = NULL;
}

int ljgap__psd_from_spec(ljgap_psd *psd, const ljgap__psd_spec *s)
{
    if (s->kind == LJGAP_PSD_TABLE)
        return ljgap_psd_table(psd, s->k, s->P, s->n, s->has_tail, s->tail_q);
    if (s->level == LJGAP_LEVEL_C && s->c_si)
        return ljgap_psd_power(psd, s->D, s->k1, s->k2, s->level,
                               ljgap_units_C_to_dimless(&s->mat, s->level_val, s->D));
    return ljgap_psd_power(psd, s->D, s->k1, s->k2, s->level, s->level_val);
}

void ljgap__request_sweep_spec(const ljgap__request *rq, size_t i, ljgap__psd_spec *spec)
{
    const ljgap_material *mat = rq->si_psd ? &rq->mat : NULL;
    double x = rq->x[i];
    *spec = rq->psd;
    switch (rq->vary) {
    case LJGAP_VARY_M0:
        spec->level = LJGAP_LEVEL_M0, spec->c_si = 0;
        spec->level_val = mat ? ljgap_units_var_to_dimless(mat, x) : x;
        break;
    case LJGAP_VARY_C:
        spec->level = LJGAP_LEVEL_C, spec->level_val = x;
        spec->c_si = mat != NULL;
        if (mat) spec->mat = *mat;
        break;
    case LJGAP_VARY_D:
        spec->D = x;
        break;
    case LJGAP_VARY_K1:
        spec->k1 = mat ? ljgap_units_k_to_dimless(mat, x) : x;
        break;
    case LJGAP_VARY_K2:
        spec->k2 = mat ? ljgap_units_k_to_dimless(mat, x) : x;
        break;
    }
}

/* ---- the validators, for requests parsed in their own files (request.h) ---- */

void ljgap__v_only_fields(ljgap__verr *e, const cJSON *obj, const char *base,
                         const char *const *names)
{
    only_fields(e, obj, base, names, NULL);
}

const cJSON *ljgap__v_required(ljgap__verr *e, const cJSON *obj, const char *base, const char *name,
                              const char *what)
{
    return required(e, obj, base, name, what);
}

int ljgap__v_num(ljgap__verr *e, const cJSON *it, const char *ptr, double *x)
{
    return num(e, it, ptr, x);
}

size_t ljgap__v_array(ljgap__verr *e, const cJSON *it, const char *ptr, size_t min, size_t max,
                     const char *what)
{
    return array_of(e, it, ptr, min, max, what);
}

const cJSON *ljgap__v_member(const cJSON *obj, const char *name)
{
    return member(obj, name);
}

int ljgap__v_num_pos(ljgap__verr *e, const cJSON *it, const char *ptr, double *x)
{
    return num_pos(e, it, ptr, x);
}

int ljgap__v_in_core_range(ljgap__verr *e, const char *ptr, const char *what, double x, double lo,
                          double hi)
{
    return in_core_range(e, ptr, what, x, lo, hi);
}

int ljgap__v_pick(ljgap__verr *e, const cJSON *it, const char *ptr, const char *const *names,
                 const char *field, const char *what)
{
    return pick(e, it, ptr, names, field, what);
}

void ljgap__v_material(ljgap__verr *e, const cJSON *root, int need, ljgap__request *rq)
{
    parse_material(e, root, need, rq);
}

size_t ljgap__v_array_of(ljgap__verr *e, const cJSON *it, const char *ptr, size_t min, size_t max,
                        const char *what)
{
    return array_of(e, it, ptr, min, max, what);
}

int ljgap__v_k1(ljgap__verr *e, const cJSON *it, const char *ptr, double chi, double *k1)
{
    return check_k1(e, it, ptr, chi, k1);
}

const char *ljgap__v_k0_why(void)
{
    return k0_why();
}

int ljgap__v_D(ljgap__verr *e, const char *ptr, double D, const double *h)
{
    return check_D(e, ptr, D, h);
}

int ljgap__v_num_int(ljgap__verr *e, const cJSON *it, const char *ptr, double lo, double hi,
                    double *x)
{
    return num_int(e, it, ptr, lo, hi, x);
}

void ljgap__v_traction(ljgap__verr *e, const cJSON *root, const ljgap__limits *lim, ljgap__request *rq)
{
    parse_traction(e, root, lim, rq);
}
