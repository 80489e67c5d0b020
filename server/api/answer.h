/* answer.h -- the job and the answer builders of handler.c, for endpoints whose runner lives in
 * its own file (combine.c: POST /v1/psd/combine). Used by the handler's files only.
 *
 * A runner gets the job with the validated request in j->rq and builds its answer in j->ans
 * through ljgap_ans_put, ljgap_ans_num and ljgap_ans_nums (handler.c's put, put_num, put_nums:
 * no NaN or Inf goes out, an allocation failure sets j->oom); run_job adds meta. It returns a
 * core status; LJGAP_EINVAL answers a 422 outside-model problem at j->bad_ptr whose detail
 * starts with j->bad_head and carries the warnings.
 */
#ifndef LJGAP_ANSWER_H
#define LJGAP_ANSWER_H

#include "request.h"

#include <cjson/cJSON.h>

/* One computation: the validated request and the answer being built. */
typedef struct {
    ljgap_request rq;           /* what was asked; rq.warn collects every warning */
    cJSON *ans;                 /* the answer object */
    double deadline;            /* ljgap_now() value when the time cap runs out */
    const volatile int *cancel; /* the call's cancel flag (or the limits' one) */
    int oom;                    /* an allocation failed while building ans */
    char fail[LJGAP_MAX_WARN * LJGAP_WARN_LEN + 400]; /* extra detail for a failed status, ""
                                                       * or starting with a space */
    const char *bad_ptr;  /* pointer of an LJGAP_EINVAL problem (NULL: "/psd") */
    const char *bad_head; /* its detail's first words (NULL: the PSD's) */
} job;

/* item into parent (member key, or array element when key is NULL); NULL (j->oom) on failure */
cJSON *ljgap_ans_put(job *j, cJSON *parent, const char *key, cJSON *item);
/* the number v, or null with a warning naming label ([idx] when idx >= 0) when not finite */
void ljgap_ans_num(job *j, cJSON *parent, const char *key, double v, const char *label, long idx);
/* n numbers x[0], x[stride bytes], ... each through ljgap_ans_num */
cJSON *ljgap_ans_nums(job *j, cJSON *parent, const char *key, const double *x, size_t n,
                      size_t stride, const char *label);

/* The psd object of a table k, P, P_err (n knots) with the tail P ∝ k^q when q is finite
 * (exponent_err q_err) as j->ans's "psd"; its variance with the tail into *m0 (NAN: none). */
void ljgap_ans_table_psd(job *j, const double *k, const double *P, const double *P_err, size_t n,
                         double q, double q_err, double *m0);
/* With a material (j->rq.has_material): the answer's "domain" of the band [kf, kl] (named band
 * in its warning), k1 in d->k1; write the psd object from d->k1, then ljgap_ans_domain_end with
 * its variance (NAN: none) adds h_rms and m0_dimensionless. */
typedef struct {
    cJSON *obj;
    const char *band;
    double kd, kf, kl, k1, inside;
} ljgap_domain;
void ljgap_ans_domain_begin(job *j, double kf, double kl, const char *band, ljgap_domain *d);
void ljgap_ans_domain_end(job *j, const ljgap_domain *d, double m0);
/* With a material: the answer's "si" scales (chi_m, sigma0_Pa, E_star_Pa) */
void ljgap_ans_si(job *j);
/* combine.c: the runner of psd/combine */
int ljgap_run_combine(job *j);

#endif
