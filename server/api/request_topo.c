/* request_topo.c -- validation of a psd request: a height map and its options (request.h).
 *
 * psd takes a height map (issue 15): topography {heights: rows of heights in m, dx, dy (default
 * dx) in m, periodic, detrend, tip_radius, resolution}, an optional fit band and an optional
 * material. The matrix must be rectangular, at least LJGAP_TOPO_MIN_SIDE a side (or a single row
 * or column: a profile), its heights finite, within ±TOPO_H_MAX m and not all equal, in all at
 * most limits.max_topo_points. A text upload (topo_text.c) arrives here as its query,
 * {"topography": {dx, dy, periodic}, "material"}, with the matrix parsed beside it, and is
 * checked by the same code. The walk and its rules are request.c's (its validators, ljgap__v_*).
 */
#include "request.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PTR_LEN 96 /* room for every pointer built from known names */
/* A height map (psd): spacings and heights in m. Far beyond any instrument, but bounded, so that
 * every periodogram and moment is a finite double. */
#define TOPO_D_MIN 1e-12 /* dx, dy */
#define TOPO_D_MAX 1.0
#define TOPO_H_MAX 1e3   /* |height| */
#define TOPO_LEN_MAX 1e3 /* tip_radius, resolution (m) */
#define TOPO_K_MIN 1e-3  /* the fit band's ends (1/m) */
#define TOPO_K_MAX 1e15

static const char *const psd_fields[] = {"topography", "material", "fit", NULL};
static const char *const topo_fields[] = {"heights", "dx",         "dy",         "periodic",
                                          "detrend", "tip_radius", "resolution", NULL};
static const char *const topo_text_fields[] = {"dx",         "dy",         "periodic", "detrend",
                                               "tip_radius", "resolution", NULL}; /* the query */
static const char *const fit_fields[] = {"k_min", "k_max", NULL};

/* The JSON matrix topography.heights into t (t->h stays NULL unless every value is good). */
static void parse_heights(ljgap__verr *e, const cJSON *topo, const ljgap__limits *lim,
                          ljgap__topo_spec *t)
{
    const cJSON *H = ljgap__v_required(e, topo, "/topography", "heights",
                                      "rows of heights in m: [[h00, h01, ...], [h10, ...], ...]");
    const cJSON *row, *it;
    char ptr[PTR_LEN];
    size_t nx, ny, j = 0, bad = 0;
    if (!H) return;
    if (!cJSON_IsArray(H) || !H->child) {
        ljgap__verr_add(e, "/topography/heights",
                       "must be a non-empty array of rows, each an array of heights in m");
        return;
    }
    if (!cJSON_IsArray(H->child)) {
        ljgap__verr_add(e, "/topography/heights/0",
                       "must be an array of heights in m (one row of the map; a single profile "
                       "is [[h0, h1, ...]])");
        return;
    }
    ny = (size_t)cJSON_GetArraySize(H);
    nx = (size_t)cJSON_GetArraySize(H->child);
    if (nx == 0 || nx > ljgap__limits_topo_cap(lim) / ny) {
        ljgap__verr_add(e, "/topography/heights",
                       "%zu rows of %zu heights: give 1 to %zu heights in all", ny, nx,
                       ljgap__limits_topo_cap(lim));
        return;
    }
    if (!(t->h = malloc(nx * ny * sizeof *t->h))) {
        e->oom = 1;
        return;
    }
    cJSON_ArrayForEach(row, H)
    {
        size_t i = 0;
        snprintf(ptr, sizeof ptr, "/topography/heights/%zu", j);
        if (!cJSON_IsArray(row) || (size_t)cJSON_GetArraySize(row) != nx) {
            if (cJSON_IsArray(row))
                ljgap__verr_add(e, ptr,
                               "row %zu has %d heights, row 0 has %zu: every row needs as "
                               "many (a ragged matrix)",
                               j, cJSON_GetArraySize(row), nx);
            else
                ljgap__verr_add(e, ptr, "row %zu must be an array of heights in m", j);
            bad++;
            j++;
            continue;
        }
        cJSON_ArrayForEach(it, row)
        {
            double x = NAN;
            snprintf(ptr, sizeof ptr, "/topography/heights/%zu/%zu", j, i);
            if (ljgap__v_num(e, it, ptr, &x) && !(fabs(x) <= TOPO_H_MAX)) {
                ljgap__verr_add(e, ptr, "height %g m is outside [-%g, %g] m (heights are in metres)",
                               x, TOPO_H_MAX, TOPO_H_MAX);
                x = NAN;
            }
            bad += isnan(x);
            t->h[j * nx + i++] = x;
        }
        j++;
    }
    if (bad) {
        free(t->h);
        t->h = NULL;
        return;
    }
    t->nx = nx;
    t->ny = ny;
}

/* The map's shape (LJGAP_TOPO_MIN_SIDE a side, or one row or column: a profile) and its
 * heights not all equal; t->h is the parsed matrix (NULL: already reported). */
static void check_map(ljgap__verr *e, const ljgap__topo_spec *t)
{
    size_t N = t->nx * t->ny, same = 1;
    int profile = t->nx == 1 || t->ny == 1;
    if (!t->h) return;
    if (profile && N < LJGAP_TOPO_MIN_SIDE) {
        ljgap__verr_add(e, "/topography/heights", "a profile of %zu heights: at least %d are needed",
                       N, LJGAP_TOPO_MIN_SIDE);
        return;
    }
    if (!profile && t->ny < LJGAP_TOPO_MIN_SIDE)
        ljgap__verr_add(e, "/topography/heights",
                       "%zu rows: a map needs at least %d rows of at least %d heights (or one "
                       "row: a profile)",
                       t->ny, LJGAP_TOPO_MIN_SIDE, LJGAP_TOPO_MIN_SIDE);
    if (!profile && t->nx < LJGAP_TOPO_MIN_SIDE)
        ljgap__verr_add(e, "/topography/heights/0",
                       "rows of %zu heights: a map needs at least %d a row (or one column: a "
                       "profile)",
                       t->nx, LJGAP_TOPO_MIN_SIDE);
    for (size_t i = 1; i < N; i++)
        same += t->h[i] == t->h[0];
    if (same == N)
        ljgap__verr_add(e, "/topography/heights",
                       "all %zu heights are equal (%g m): a flat map has no spectrum", N, t->h[0]);
}

/* A spacing at topo[name] (default: *dflt when absent and dflt is not NULL). */
static void parse_spacing(ljgap__verr *e, const cJSON *topo, const char *name, const double *dflt,
                          double *x)
{
    char ptr[PTR_LEN];
    const cJSON *it =
        dflt ? ljgap__v_member(topo, name)
             : ljgap__v_required(e, topo, "/topography", name,
                                "the spacing of the heights along a row, m (for a text "
                                "upload the query parameter dx)");
    snprintf(ptr, sizeof ptr, "/topography/%s", name);
    *x = NAN;
    if (!it) {
        if (dflt) *x = *dflt;
        return;
    }
    if (ljgap__v_num_pos(e, it, ptr, x) &&
        !ljgap__v_in_core_range(e, ptr, name, *x, TOPO_D_MIN, TOPO_D_MAX))
        *x = NAN;
}

/* An optional length in m at topo[name] (0 when absent), within [TOPO_D_MIN, TOPO_LEN_MAX]. */
static void parse_length(ljgap__verr *e, const cJSON *obj, const char *base, const char *name,
                         double *x)
{
    char ptr[PTR_LEN];
    const cJSON *it = ljgap__v_member(obj, name);
    *x = 0;
    if (!it) return;
    snprintf(ptr, sizeof ptr, "%s/%s", base, name);
    if (!ljgap__v_num_pos(e, it, ptr, x) ||
        !ljgap__v_in_core_range(e, ptr, name, *x, TOPO_D_MIN, TOPO_LEN_MAX))
        *x = 0;
}

/* detrend, tip_radius and resolution of the topography object. */
static void parse_topo_options(ljgap__verr *e, const cJSON *topo, ljgap__topo_spec *t)
{
    static const char *const modes[] = {"mean", "plane", "lines", "curvature", NULL};
    const cJSON *d = ljgap__v_member(topo, "detrend");
    t->detrend = LJGAP_DETREND_AUTO;
    if (d) {
        int m = ljgap__v_pick(e, d, "/topography/detrend", modes, "detrend",
                             "\"mean\", \"plane\", \"lines\" or \"curvature\"");
        if (m >= 0) t->detrend = ljgap_topo_detrend_parse(modes[m]);
    }
    parse_length(e, topo, "/topography", "tip_radius", &t->tip_radius);
    parse_length(e, topo, "/topography", "resolution", &t->resolution);
}

/* The optional fit band {"k_min", "k_max"} (1/m; either or both). */
static void parse_fit_band(ljgap__verr *e, const cJSON *root, ljgap__topo_spec *t)
{
    const cJSON *f = ljgap__v_member(root, "fit"), *it;
    t->fit_kmin = t->fit_kmax = 0;
    if (!f) return;
    if (!cJSON_IsObject(f)) {
        ljgap__verr_add(e, "/fit", "must be an object {\"k_min\": 1/m, \"k_max\": 1/m}");
        return;
    }
    ljgap__v_only_fields(e, f, "/fit", fit_fields);
    if ((it = ljgap__v_member(f, "k_min")) &&
        (!ljgap__v_num_pos(e, it, "/fit/k_min", &t->fit_kmin) ||
         !ljgap__v_in_core_range(e, "/fit/k_min", "k_min (1/m)", t->fit_kmin, TOPO_K_MIN,
                                TOPO_K_MAX)))
        t->fit_kmin = 0;
    if ((it = ljgap__v_member(f, "k_max")) &&
        (!ljgap__v_num_pos(e, it, "/fit/k_max", &t->fit_kmax) ||
         !ljgap__v_in_core_range(e, "/fit/k_max", "k_max (1/m)", t->fit_kmax, TOPO_K_MIN,
                                TOPO_K_MAX)))
        t->fit_kmax = 0;
    if (t->fit_kmin > 0 && t->fit_kmax > 0 && !(t->fit_kmax > t->fit_kmin)) {
        ljgap__verr_add(e, "/fit/k_max", "k_max = %g must exceed k_min = %g", t->fit_kmax,
                       t->fit_kmin);
        t->fit_kmax = 0;
    }
}

/* The topography object: heights (unless text: they came as the body), dx, dy, periodic. */
static void parse_topography(ljgap__verr *e, const cJSON *root, const ljgap__limits *lim, int text,
                             ljgap__topo_spec *t)
{
    const cJSON *topo = ljgap__v_required(e, root, "", "topography",
                                         "{\"heights\": [[...], ...], \"dx\": m, \"dy\": m, "
                                         "\"periodic\": false}"),
                *per;
    if (!topo) return;
    if (!cJSON_IsObject(topo)) {
        ljgap__verr_add(e, "/topography",
                       "must be an object {\"heights\": [[...], ...], \"dx\": m, ...}");
        return;
    }
    ljgap__v_only_fields(e, topo, "/topography", text ? topo_text_fields : topo_fields);
    parse_spacing(e, topo, "dx", NULL, &t->dx);
    parse_spacing(e, topo, "dy", &t->dx, &t->dy);
    if ((per = ljgap__v_member(topo, "periodic"))) {
        if (cJSON_IsBool(per))
            t->periodic = cJSON_IsTrue(per);
        else
            ljgap__verr_add(e, "/topography/periodic",
                           "must be true (the map is one period of the surface: no plane, no "
                           "window) or false");
    }
    parse_topo_options(e, topo, t);
    if (!text) parse_heights(e, topo, lim, t);
    check_map(e, t);
}

void ljgap__request_parse_psd(ljgap__verr *e, const cJSON *root, const ljgap__limits *lim, int text,
                             ljgap__request *rq)
{
    rq->method = "periodogram";
    ljgap__v_only_fields(e, root, "", psd_fields);
    ljgap__v_material(e, root, 0, rq);
    parse_topography(e, root, lim, text, &rq->topo);
    parse_fit_band(e, root, &rq->topo);
}

int ljgap__request_parse_text(const cJSON *root, ljgap__topo_spec *heights, const ljgap__limits *lim,
                             ljgap__request *rq, ljgap__verr *e)
{
    memset(rq, 0, sizeof *rq);
    rq->ep = LJGAP_EP_PSD;
    ljgap_opts_default(&rq->opts);
    rq->psd.kind = (ljgap_psd_kind)-1;
    rq->topo.h = heights->h;
    rq->topo.nx = heights->nx;
    rq->topo.ny = heights->ny;
    heights->h = NULL;
    if (!cJSON_IsObject(root)) {
        ljgap__verr_add(e, "", "the query must be an object");
        return e->n;
    }
    ljgap__request_parse_psd(e, root, lim, 1, rq);
    return e->n;
}
