/* topo_text.c -- the plain-text form of POST /v1/psd: a height matrix and its query.
 *
 * A lab's AFM or profilometer export is a matrix of numbers, tens of MiB of it: too large for
 * JSON (1 MiB, and cJSON would spend some 60 bytes a number), so psd also takes the matrix as
 * text/plain or text/csv, with the rest of the request in the query string. The two parts go
 * through the JSON request's own validation (request.c): the query becomes the root
 * {"topography": {dx, dy, periodic}, "material": {...}} and the matrix the topography's
 * heights, so a problem has the pointer the same field has in a JSON request, and the answer
 * is the JSON request's.
 *
 * The matrix: one row of the map a line (heights in metres along x, spacing dx; successive
 * lines are dy apart), values separated by white space or by one comma (with any white space
 * around it), '#' starts a comment that runs to the end of the line, blank and comment-only
 * lines are skipped, CR LF and CR line ends and a leading UTF-8 byte-order mark are accepted. A
 * value is a decimal number (digits, sign, point, exponent: no hex, inf or nan). Every problem is
 * recorded with its pointer (/topography/heights/ROW/COL, ROW counting the data rows from 0) and
 * a detail that names the line and column (1-based, in bytes) where the value starts, so that
 * the user can find it in an editor; the parse stops after LJGAP_MAX_ERRORS of them.
 *
 * Speed: one pass over the bytes; a value with at most 19 significant digits and a power of
 * ten within ±22 is converted exactly by Clinger's fast path, anything else by strtod (both
 * give the correctly rounded double, as cJSON's strtod does for the same digits, so text and
 * JSON agree bit for bit); the matrix grows by doubling (bench/topo.sh times a 2048² map).
 */
#include "topo_text.h"
#include "textbuf.h" /* ljgap__utf8_span */

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TOKEN_MAX 64    /* longest value read (a double needs at most 24 characters) */
#define QUOTE_MAX 24    /* characters of a bad value quoted in a problem */
#define HEIGHT_MAX 1e3  /* |height| in m, as request.c's TOPO_H_MAX */
#define TEXT_PTR_LEN 96 /* /topography/heights/ROW/COL */

/* The values read so far. */
typedef struct {
    double *h;     /* values, row after row */
    size_t n, cap; /* used, allocated */
} values;

static int push(values *v, double x)
{
    if (v->n == v->cap) {
        size_t cap = v->cap ? 2 * v->cap : 4096;
        double *h = realloc(v->h, cap * sizeof *h);
        if (!h) return -1;
        v->h = h;
        v->cap = cap;
    }
    v->h[v->n++] = x;
    return 0;
}

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/* The token s[0..n) quoted for a message: printable ASCII only (the rest becomes '?'), at most
 * QUOTE_MAX characters and "..." when longer. */
static void quote(char *out, const char *s, size_t n)
{
    size_t k = 0;
    for (; k < n && k < QUOTE_MAX; k++)
        out[k] = s[k] >= 0x20 && s[k] < 0x7f ? s[k] : '?';
    if (n > QUOTE_MAX) memcpy(out + k, "...", 3), k += 3;
    out[k] = '\0';
}

/* A decimal number s[0..n) into *x: [+-] digits [. digits] [(e|E) [+-] digits], at least one
 * mantissa digit; 0 when it is one, -1 when not. Clinger's fast path: a mantissa of at most 19
 * digits below 2^53 and a power of ten |e| <= 22 are both exact doubles, so m·10^e or m/10^-e is
 * the correctly rounded value, as strtod gives it; anything else goes to strtod. */
static int decimal(const char *s, size_t n, double *x)
{
    static const double p10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                 1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    size_t i = 0, digits = 0, sig = 0;
    uint64_t m = 0;
    long e = 0, ex = 0;
    int neg = 0, eneg = 0, slow = 0;
    if (i < n && (s[i] == '+' || s[i] == '-')) neg = s[i++] == '-';
    for (int frac = 0; i < n; i++) {
        if (s[i] == '.' && !frac) {
            frac = 1;
            continue;
        }
        if (s[i] < '0' || s[i] > '9') break;
        digits++;
        if (m == 0 && s[i] == '0') { /* leading zeros are not significant */
            e -= frac;
            continue;
        }
        if (sig < 19)
            m = 10 * m + (uint64_t)(s[i] - '0'), sig++, e -= frac;
        else
            slow = 1, e += !frac;
    }
    if (!digits) return -1;
    if (i < n && (s[i] == 'e' || s[i] == 'E')) {
        size_t d = ++i;
        if (i < n && (s[i] == '+' || s[i] == '-')) eneg = s[i++] == '-', d = i;
        for (; i < n && s[i] >= '0' && s[i] <= '9'; i++)
            if (ex < 100000) ex = 10 * ex + (s[i] - '0');
        if (i == d) return -1;
    }
    if (i != n) return -1;
    e += eneg ? -ex : ex;
    if (!slow && m < ((uint64_t)1 << 53) && e >= -22 && e <= 22) {
        double v = (double)m;
        v = e < 0 ? v / p10[-e] : v * p10[e];
        *x = neg ? -v : v;
        return 0;
    }
    char buf[TOKEN_MAX + 1], *end;
    memcpy(buf, s, n);
    buf[n] = '\0';
    *x = strtod(buf, &end);
    return end == buf + n ? 0 : -1;
}

/* The value s[0..n) into *x: 0, or a reason it is not a height. */
static const char *read_value(const char *s, size_t n, double *x)
{
    if (n > TOKEN_MAX) return "is too long to be a number";
    if (decimal(s, n, x)) return "is not a number";
    if (!isfinite(*x)) return "overflows a double";
    if (!(fabs(*x) <= HEIGHT_MAX)) return "is outside [-1e3, 1e3] m (heights are in metres)";
    return NULL;
}

void ljgap__topo_text_parse(const char *body, size_t len, size_t max_points, ljgap__topo_spec *t,
                           ljgap__verr *e)
{
    const char *p = body, *end = body + len;
    values v = {0};
    size_t line = 0, rows = 0, nx = 0, first_line = 0, bad = 0;
    char ptr[TEXT_PTR_LEN], q[QUOTE_MAX + 4];
    t->h = NULL;
    t->nx = t->ny = 0;
    if (len >= 3 && memcmp(body, "\xEF\xBB\xBF", 3) == 0) p += 3;
    while (p < end && e->n <= LJGAP_MAX_ERRORS) {
        const char *ls = p, *le = memchr(p, '\n', (size_t)(end - p));
        size_t cols = 0;
        int last = 0; /* 0: line start, 1: after a value, 2: after a comma */
        if (!le) le = end;
        /* a CR not followed by LF ends the line too (classic Mac OS line ends): without this
         * such a file would be one long line, a map read as a single profile */
        const char *cr = memchr(p, '\r', (size_t)(le - p));
        if (cr && cr + 1 < le) le = cr;
        line++;
        while (p < le) {
            if (is_space(*p)) {
                p++;
                continue;
            }
            if (*p == '#') break;
            if (*p == ',') {
                if (last != 1) {
                    snprintf(ptr, sizeof ptr, "/topography/heights/%zu/%zu", rows, cols);
                    ljgap__verr_add(e, ptr,
                                   "line %zu, column %zu: an empty value before this comma "
                                   "(values are separated by white space or one comma)",
                                   line, (size_t)(p - ls) + 1);
                    bad++;
                }
                last = 2;
                p++;
                continue;
            }
            const char *s = p;
            while (p < le && !is_space(*p) && *p != ',' && *p != '#')
                p++;
            double x = 0;
            const char *why = read_value(s, (size_t)(p - s), &x);
            if (why) {
                quote(q, s, (size_t)(p - s));
                snprintf(ptr, sizeof ptr, "/topography/heights/%zu/%zu", rows, cols);
                ljgap__verr_add(e, ptr, "line %zu, column %zu: \"%s\" %s", line,
                               (size_t)(s - ls) + 1, q, why);
                bad++;
            }
            if (v.n >= max_points) {
                ljgap__verr_add(e, "/topography/heights",
                               "more than %zu heights (line %zu): the cap of this server",
                               max_points, line);
                bad++;
                goto done;
            }
            if (push(&v, x)) {
                e->oom = 1;
                goto done;
            }
            cols++;
            last = 1;
        }
        if (last == 2) {
            snprintf(ptr, sizeof ptr, "/topography/heights/%zu/%zu", rows, cols);
            ljgap__verr_add(e, ptr,
                           "line %zu, column %zu: the line ends with a comma: a value is "
                           "missing",
                           line, (size_t)(p - ls));
            bad++;
        }
        if (cols) {
            if (!rows) {
                nx = cols;
                first_line = line;
            } else if (cols != nx) {
                snprintf(ptr, sizeof ptr, "/topography/heights/%zu", rows);
                ljgap__verr_add(e, ptr,
                               "line %zu has %zu values, the first row (line %zu) has %zu: every "
                               "row needs as many (a ragged matrix)",
                               line, cols, first_line, nx);
                bad++;
            }
            rows++;
        }
        p = le + 1;
    }
done:
    if (!bad && !e->oom && !v.n)
        ljgap__verr_add(e, "/topography/heights",
                       "no heights: the body holds no numbers (one row of the map a line, "
                       "values in m separated by spaces or commas)");
    if (bad || e->oom || !v.n) {
        free(v.h);
        return;
    }
    t->h = v.h;
    t->nx = nx;
    t->ny = rows;
}

/* The pointer of a query parameter: its field in the JSON request, or /NAME. */
static void param_pointer(char *ptr, size_t size, const char *name, int where)
{
    static const char *const base[] = {"", "/topography", "/material", "/fit"};
    size_t k = (size_t)snprintf(ptr, size, "%s/", base[where]);
    /* RFC 6901 escapes; the name cut at whole UTF-8 characters (the pointer goes out as JSON) */
    size_t n = ljgap__utf8_span(name, strnlen(name, 60));
    for (size_t i = 0; i < n && k + 3 < size; i++) {
        if (name[i] == '~' || name[i] == '/')
            ptr[k++] = '~', ptr[k++] = name[i] == '~' ? '0' : '1';
        else
            ptr[k++] = name[i];
    }
    ptr[k] = '\0';
}

cJSON *ljgap__topo_params_json(const ljgap__param *p, size_t np, ljgap__verr *e)
{
    static const char *const topo_names[] = {"dx",         "dy",         "periodic", "detrend",
                                             "tip_radius", "resolution", NULL};
    static const char *const fit_names[] = {"fit_k_min", "fit_k_max", NULL};
    static const char *const mat_names[] = {"E_star", "E1",     "nu1",     "E2",
                                            "nu2",    "dgamma", "epsilon", NULL};
    cJSON *root = cJSON_CreateObject(), *topo = NULL, *mat = NULL, *fit = NULL;
    char ptr[TEXT_PTR_LEN + 80], q[QUOTE_MAX + 4];
    if (!root || !(topo = cJSON_AddObjectToObject(root, "topography"))) goto oom;
    for (size_t i = 0; i < np; i++) {
        const char *name = p[i].name ? p[i].name : "", *val = p[i].value ? p[i].value : "";
        int where = 0, dup = 0;
        for (int k = 0; topo_names[k]; k++)
            if (strcmp(name, topo_names[k]) == 0) where = 1;
        for (int k = 0; mat_names[k]; k++)
            if (strcmp(name, mat_names[k]) == 0) where = 2;
        for (int k = 0; fit_names[k]; k++)
            if (strcmp(name, fit_names[k]) == 0) where = 3;
        /* fit_k_min is the JSON request's /fit/k_min */
        const char *field = where == 3 ? name + 4 : name;
        for (size_t k = 0; k < i; k++)
            dup = dup || strcmp(name, p[k].name ? p[k].name : "") == 0;
        param_pointer(ptr, sizeof ptr, field, where);
        quote(q, name, strlen(name));
        if (dup) {
            ljgap__verr_add(e, ptr, "the query parameter \"%s\" is given more than once", q);
            continue;
        }
        if (!where) {
            ljgap__verr_add(e, ptr,
                           "unknown query parameter \"%s\": psd takes dx, dy, periodic, detrend, "
                           "tip_radius, resolution, fit_k_min, fit_k_max and the material's E_star "
                           "(or E1, nu1, E2, nu2), dgamma, epsilon",
                           q);
            continue;
        }
        cJSON *obj = where == 1 ? topo : where == 2 ? mat : fit;
        if (where == 2 && !mat && !(obj = mat = cJSON_AddObjectToObject(root, "material")))
            goto oom;
        if (where == 3 && !fit && !(obj = fit = cJSON_AddObjectToObject(root, "fit"))) goto oom;
        /* a value that is not what the field takes goes in as a string, for request.c to
         * refuse at the field's pointer like the same string in a JSON request */
        cJSON *item = NULL;
        if (strcmp(name, "periodic") == 0) {
            int yes = !*val || strcmp(val, "true") == 0 || strcmp(val, "1") == 0;
            int no = strcmp(val, "false") == 0 || strcmp(val, "0") == 0;
            item = yes || no ? cJSON_CreateBool(yes) : NULL;
        } else if (strcmp(name, "detrend") == 0) {
            item = NULL; /* a string: request.c checks the name */
        } else {
            double x = NAN;
            char *end = NULL;
            size_t n = strlen(val);
            if (n && n <= TOKEN_MAX && strspn(val, "0123456789+-.eE") == n) x = strtod(val, &end);
            item = end && !*end && isfinite(x) ? cJSON_CreateNumber(x) : NULL;
        }
        if (!item) {
            quote(q, val, strlen(val));
            item = cJSON_CreateString(q);
        }
        if (!item || !cJSON_AddItemToObject(obj, field, item)) {
            cJSON_Delete(item);
            goto oom;
        }
    }
    return root;
oom:
    cJSON_Delete(root);
    return NULL;
}
