/* request.h -- a compute request (docs/api.md), validated and in core terms.
 *
 * ljgap__request_parse reads a cJSON request body for one endpoint, checks every field
 * against the contract and collects ALL the problems it finds as {"pointer","detail"}
 * entries (RFC 6901 pointers into the request), so that one 422 answer tells the caller
 * everything that is wrong. A request that passes has every number the core needs, with
 * the contract's defaults filled in; the handler then only builds the PSD and calls the
 * core. Used by handler.c only.
 */
#ifndef LJGAP_REQUEST_H
#define LJGAP_REQUEST_H

#include "settings.h"
#include "ljgap.h"
#include "ljgap_sim.h"
#include "ljgap_topo.h"
#include "ljgap_units.h"

#include <cjson/cJSON.h>

#define LJGAP_SEED_MAX 9007199254740991.0 /* 2^53 - 1: the largest integer a JSON number keeps */

/* The endpoints the handler computes. */
typedef enum {
    LJGAP_EP_ADHESION,
    LJGAP_EP_TRACTION,
    LJGAP_EP_PDF,
    LJGAP_EP_SWEEP,
    LJGAP_EP_CONTACT,
    LJGAP_EP_SIMULATION, /* a numerical-model job (ljgap_sim.h), not a synchronous endpoint */
    LJGAP_EP_PSD,        /* the PSD of a height map (ljgap_topo.h); its text form too */
    LJGAP_EP_COMBINE     /* several measured PSDs as one (ljgap_combine.h, combine.c) */
} ljgap__endpoint;

/* Which PSD field a sweep varies. */
typedef enum { LJGAP_VARY_M0, LJGAP_VARY_C, LJGAP_VARY_D, LJGAP_VARY_K1, LJGAP_VARY_K2 } ljgap__vary;

/* The psd object as given (not yet built: a sweep builds one PSD per value). */
typedef struct {
    ljgap_psd_kind kind;
    double D;           /* power: fractal dimension (from D or 3 - H) */
    double k1;          /* power: lower cut-off */
    double k2;          /* power: upper cut-off, INFINITY when absent or null */
    ljgap_level level;  /* power: which field set the level */
    double level_val;   /* power: its value */
    size_t n;           /* table: number of points */
    double *k, *P;      /* table: owned, n entries each */
    int has_tail;       /* table: tail given */
    double tail_q;      /* table: tail exponent */
    double *P_err;      /* table: owned, n entries (1 σ of each P, in P's units: converted like
                         * P), or NULL when not given; input_error.c propagates them */
    double tail_q_err;  /* table: the tail exponent's 1 σ (0 when not given) */
    double *P_corr;     /* table: owned, n - 1 entries (correlation of the errors of knots i
                         * and i + 1), or NULL when not given (independent) */
    double D_err;       /* power: D's 1 σ (0 when not given) */
    double level_err;   /* power: the level's 1 σ in the level's units (C_err, m0_err, h_rms_err;
                         * converted like the level; 0 when not given) */
    int c_si;           /* power: level C is in SI (m^(2D-4)); converted with D and mat when
                         * the PSD is built (a sweep over D changes the conversion) */
    ljgap_material mat; /* the material, when c_si */
} ljgap__psd_spec;

/* A height map as given (psd: the JSON topography object, or a text upload and its query). */
typedef struct {
    double *h;    /* owned: heights in m, row-major [ny][nx] (a row of the matrix runs along x) */
    size_t nx;    /* values in a row */
    size_t ny;    /* rows */
    double dx;    /* spacing along a row, m */
    double dy;    /* spacing between rows, m (dx when not given) */
    int periodic; /* the map is one period of a periodic surface */
    int detrend;  /* ljgap_topo_detrend (LJGAP_DETREND_AUTO when not given) */
    double tip_radius; /* m, 0 when not given */
    double resolution; /* m, 0 when not given */
    double fit_kmin;   /* the fit band's ends (1/m), 0 when not given */
    double fit_kmax;
} ljgap__topo_spec;

typedef struct {
    ljgap__endpoint ep;
    ljgap_opts opts;       /* method, tol, vmax, samples, seed (limits set by the handler) */
    const char *method;    /* contract name of opts.method (static string) */
    ljgap__psd_spec psd;    /* the psd object */
    double *x;             /* owned: traction and simulation g_ave points, pdf k2 cut-offs
                            * (INFINITY for null), or sweep values (as given: SI when si_psd;
                            * see ljgap__request_sweep_spec) */
    size_t nx;             /* entries in x */
    double g_ave;          /* pdf: the mean gap */
    int has_grid;          /* pdf: grid given */
    double grid[3];        /* pdf: {min, max, n} */
    ljgap__vary vary;       /* sweep: which field */
    const char *vary_name; /* sweep: its contract name (static string) */
    int has_material;      /* a material block was given: answers add "si" */
    ljgap_material mat;    /* the material (SI), when has_material */
    int si_psd;            /* "units":"SI": the psd object was given in SI (now converted) */
    double R;              /* contact: sphere radius (m) */
    int input_error;       /* answers carry the measurement's uncertainty (input_error,
                            * extrapolated) when the PSD has one: 1 unless "input_error": false */
    ljgap_sim_opts sim;    /* simulation: n, L, realizations, seed, tol (the core's defaults
                            * for what is not given); g_ave points in x */
    ljgap__topo_spec topo;  /* psd: the height map */
    ljgap_warnings warn;   /* notes on the request itself (e.g. ignored fields) */
    struct ljgap__combine_spec *combine; /* psd/combine: the PSDs (owned, combine.c) */
    cJSON *source;         /* psd of an instrument file: the answer's "source" (owned; psd.c
                            * moves it into the answer), else NULL */
} ljgap__request;

/* Collected validation problems. */
typedef struct {
    cJSON *errors; /* array of {"pointer","detail"}, at most LJGAP_MAX_ERRORS kept */
    int n;         /* problems found (may exceed the number kept) */
    int oom;       /* an allocation failed while recording */
} ljgap__verr;

#define LJGAP_MAX_ERRORS 100

/* Validates root (any JSON value) as a request to ep. Returns 0 when it is valid; else the
 * number of problems, each recorded in e (whose errors array must exist). rq is always left
 * in a state ljgap__request_free accepts. */
int ljgap__request_parse(ljgap__endpoint ep, const cJSON *root, const ljgap__limits *lim,
                        ljgap__request *rq, ljgap__verr *e);
void ljgap__request_free(ljgap__request *rq);
/* The same for a text upload to psd: root holds the query as {"topography": {dx, dy,
 * periodic}, "material": {...}} (ljgap__topo_params_json) and heights the parsed matrix, which
 * rq takes over (heights is left empty). Problems already in e (the text's) stay first. */
int ljgap__request_parse_text(const cJSON *root, ljgap__topo_spec *heights, const ljgap__limits *lim,
                             ljgap__request *rq, ljgap__verr *e);

/* Builds the PSD a spec describes (ljgap_psd_power / ljgap_psd_table status). */
int ljgap__psd_from_spec(ljgap_psd *psd, const ljgap__psd_spec *s);
/* The PSD spec of sweep value i (rq->x[i] placed in the varied field, in core units). */
void ljgap__request_sweep_spec(const ljgap__request *rq, size_t i, ljgap__psd_spec *spec);

/* Records one problem at pointer ptr (printf-style detail). */
void ljgap__verr_add(ljgap__verr *e, const char *ptr, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* ---- the validators above, for requests parsed in their own files (combine.c) ----
 * Each records its problems in e as the request's own parsers do. */
/* Every member of obj (pointer base) must be named in names (NULL-terminated), once. */
void ljgap__v_only_fields(ljgap__verr *e, const cJSON *obj, const char *base,
                         const char *const *names);
/* obj[name], recording "missing" at base/name (what: what the field is) when absent. */
const cJSON *ljgap__v_required(ljgap__verr *e, const cJSON *obj, const char *base, const char *name,
                              const char *what);
/* A finite JSON number at it (pointer ptr) into *x; 0 after recording why not. */
int ljgap__v_num(ljgap__verr *e, const cJSON *it, const char *ptr, double *x);
/* A JSON array of min..max entries; its size, or 0 after recording why not. */
size_t ljgap__v_array(ljgap__verr *e, const cJSON *it, const char *ptr, size_t min, size_t max,
                     const char *what);
/* obj[name], or NULL. */
const cJSON *ljgap__v_member(const cJSON *obj, const char *name);
/* A finite positive JSON number at it into *x; 0 after recording why not. */
int ljgap__v_num_pos(ljgap__verr *e, const cJSON *it, const char *ptr, double *x);
/* Is x (what, at ptr) within [lo, hi], the range the core handles? 0 after recording why not. */
int ljgap__v_in_core_range(ljgap__verr *e, const char *ptr, const char *what, double x, double lo,
                          double hi);
/* The index in names (NULL-terminated) of the string at it, or -1 after recording why not. */
int ljgap__v_pick(ljgap__verr *e, const cJSON *it, const char *ptr, const char *const *names,
                 const char *field, const char *what);
/* The request's material block into rq (need: it must be there). */
void ljgap__v_material(ljgap__verr *e, const cJSON *root, int need, ljgap__request *rq);
/* A JSON array of min..max entries at it (what it should hold); its size, or 0. */
size_t ljgap__v_array_of(ljgap__verr *e, const cJSON *it, const char *ptr, size_t min, size_t max,
                        const char *what);
/* k1 at it, k0 < chi k1 checked (chi 1: dimensionless); 0 after recording why not. */
int ljgap__v_k1(ljgap__verr *e, const cJSON *it, const char *ptr, double chi, double *k1);
/* 2 < D < 3 (h: the Hurst exponent it came from, or NULL); 0 after recording why not. */
int ljgap__v_D(ljgap__verr *e, const char *ptr, double D, const double *h);
/* Why k1 must be above k0, for the details. */
const char *ljgap__v_k0_why(void);
/* An integer JSON number in [lo, hi] at it into *x; 0 after recording why not. */
int ljgap__v_num_int(ljgap__verr *e, const cJSON *it, const char *ptr, double lo, double hi,
                    double *x);
/* traction's g_ave (a list or a range) into rq. */
void ljgap__v_traction(ljgap__verr *e, const cJSON *root, const ljgap__limits *lim, ljgap__request *rq);
/* request_sim.c: a simulation request's own fields into rq (its psd already read). */
void ljgap__request_parse_simulation(ljgap__verr *e, const cJSON *root, const ljgap__limits *lim,
                                    ljgap__request *rq);
/* request_psd.c: root's psd object into s (SI with mat, else dimensionless). */
void ljgap__request_parse_psd_spec(ljgap__verr *e, const cJSON *root, const ljgap_material *mat,
                                  ljgap__psd_spec *s);
/* request_topo.c: a psd request (text: the matrix came as text, already in rq->topo). */
void ljgap__request_parse_psd(ljgap__verr *e, const cJSON *root, const ljgap__limits *lim, int text,
                             ljgap__request *rq);

/* ---- combine.c: POST /v1/psd/combine ---- */
/* Validates root's {"psds": [...], "points_per_decade"} into rq->combine. */
void ljgap__combine_parse(ljgap__verr *e, const cJSON *root, ljgap__request *rq);
void ljgap__combine_spec_free(struct ljgap__combine_spec *s); /* NULL is fine */

#endif
