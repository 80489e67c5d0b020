/* answer.h -- the job and the answer builders of handler.c, for endpoints whose runner lives in
 * its own file (psd.c: POST /v1/psd; combine.c: POST /v1/psd/combine). Used by the handler's
 * files only.
 *
 * A runner gets the job with the validated request in j->rq and builds its answer in j->ans
 * through ljgap__ans_put, ljgap__ans_num and ljgap__ans_nums (handler.c's put, put_num, put_nums:
 * no NaN or Inf goes out, an allocation failure sets j->oom); run_job adds meta. It returns a
 * core status; LJGAP_EINVAL answers a 422 outside-model problem at j->bad_ptr whose detail
 * starts with j->bad_head and carries the warnings.
 */
#ifndef LJGAP_ANSWER_H
#define LJGAP_ANSWER_H

#include "reply.h"
#include "request.h"

#include <cjson/cJSON.h>

#define CT_JSON "application/json"
#define CT_PROBLEM "application/problem+json"
#define DETAIL_LEN (LJGAP_MAX_WARN * LJGAP_WARN_LEN + 400)

/* Problem types (problems.c has the status, title and page of each). */
#define P_MALFORMED "malformed-json"
#define P_NOT_FOUND "not-found"
#define P_NOT_ACCEPTABLE "not-acceptable"
#define P_VALIDATION "validation"
#define P_OUTSIDE "outside-model"
#define P_CAP "cap-exceeded"
#define P_NO_ANSWER "no-answer"
#define P_UNAVAILABLE "unavailable"
#define P_OOM "out-of-memory"

/* One computation: the validated request and the answer being built. */
typedef struct {
    ljgap__request rq;           /* what was asked; rq.warn collects every warning */
    cJSON *ans;                 /* the answer object */
    double deadline;            /* ljgap__clock_now() value when the time cap runs out */
    const volatile int *cancel; /* the call's cancel flag (or the limits' one) */
    int oom;                    /* an allocation failed while building ans */
    char fail[LJGAP_MAX_WARN * LJGAP_WARN_LEN + 400]; /* extra detail for a failed status, ""
                                                       * or starting with a space */
    const char *bad_ptr;  /* pointer of an LJGAP_EINVAL problem (NULL: "/psd") */
    const char *bad_head; /* its detail's first words (NULL: the PSD's) */
    cJSON *ie_meta;       /* meta.input_error, how the input's uncertainty was carried (owned
                           * until ljgap__ans_meta places it; server/uncert/input_error.c) */
} job;

/* item into parent (member key, or array element when key is NULL); NULL (j->oom) on failure */
cJSON *ljgap__ans_put(job *j, cJSON *parent, const char *key, cJSON *item);
/* the number v, or null with a warning naming label ([idx] when idx >= 0) when not finite */
void ljgap__ans_num(job *j, cJSON *parent, const char *key, double v, const char *label, long idx);
/* n numbers x[0], x[stride bytes], ... each through ljgap__ans_num */
cJSON *ljgap__ans_nums(job *j, cJSON *parent, const char *key, const double *x, size_t n,
                      size_t stride, const char *label);

/* The psd object of a table k, P, P_err (n knots) with the tail P ∝ k^q when q is finite
 * (exponent_err q_err) as j->ans's "psd"; its variance with the tail into *m0 (NAN: none). */
void ljgap__ans_table_psd(job *j, const double *k, const double *P, const double *P_err, size_t n,
                         double q, double q_err, double *m0);
/* With a material (j->rq.has_material): the answer's "domain" of the band [kf, kl] (named band
 * in its warning), k1 in d->k1; write the psd object from d->k1, then ljgap__ans_domain_end with
 * its variance (NAN: none) adds h_rms and m0_dimensionless. */
typedef struct {
    cJSON *obj;
    const char *band;
    double kd, kf, kl, k1, inside;
} ljgap__domain;
void ljgap__ans_domain_begin(job *j, double kf, double kl, const char *band, ljgap__domain *d);
void ljgap__ans_domain_end(job *j, const ljgap__domain *d, double m0);
/* With a material: the answer's "si" scales (chi_m, sigma0_Pa, E_star_Pa) */
void ljgap__ans_si(job *j);
/* ---- the handler's replies and checks, for simreq.c ---- */
/* The limits set at start-up (handler.h: ljgap__handler_set_limits). */
const ljgap__limits *ljgap__handler_limits(void);
/* 500 out-of-memory, from a body that needs no allocation. */
void ljgap__ans_oom(ljgap__reply *out);
/* doc as the answer, with status and ctype. */
void ljgap__ans_reply_json(ljgap__reply *out, int status, const char *ctype, const cJSON *doc);
/* A problem of type slug with detail; errors (taken; NULL: empty) is its errors[]. */
void ljgap__ans_problem(ljgap__reply *out, const char *slug, const char *detail, cJSON *errors);
/* The problem answering a failed core status st of job j. */
void ljgap__ans_status(ljgap__reply *out, int st, const job *j);
/* Parses and validates body for ep into j->rq: 1, or 0 with *out the problem. */
int ljgap__ans_validate(ljgap__endpoint ep, const char *body, size_t len, job *j, ljgap__reply *out);
/* The answer forms, JSON then CSV (accept.h picks among them). */
extern const char *const ljgap__ans_forms[2];
/* The form (0 JSON, 1 CSV when csv) accept prefers, or -1 with *out the 406 problem. */
int ljgap__ans_negotiate(const char *accept, int csv, ljgap__reply *out);
/* The answer's meta (method, elapsed_ms since t0, version, warnings, cached). */
void ljgap__ans_meta(job *j, double t0);
/* The summary s into obj, its errors into err_parent's member err_key. */
void ljgap__ans_summary(job *j, cJSON *obj, cJSON *err_parent, const char *err_key,
                       const ljgap_summary *s);
/* prefix, then the warnings of w, into buf. */

/* The 422 validation problem of ve's errors (taken) into *out. */
void ljgap__ans_invalid(ljgap__reply *out, ljgap__verr *ve);
/* Runs a validated request j with run and answers it in form (0 JSON, 1 endpoint's CSV) into
 * *out, meta timed from t0 (j->rq stays the caller's to free). */
void ljgap__ans_run_job(job *j, int (*run)(job *), const char *endpoint, int form,
                       const ljgap__call *call, double t0, ljgap__reply *out);

/* psd.c: the runner of psd */
int ljgap__run_psd(job *j);
/* combine.c: the runner of psd/combine */
int ljgap__run_combine(job *j);

#endif
