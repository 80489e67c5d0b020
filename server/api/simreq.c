/* simreq.c -- simulations (ljgap_sim.h) through the handler: parse, run, answer, poll.
 *
 * Not an endpoint of ljgap__handle: a run takes minutes. ljgap__sim_request_parse validates like
 * every endpoint (the same problems, request.c) and builds the PSD; ljgap__sim_request_run runs it
 * under the caller's cancel flag, progress callback and time cap, its realizations on
 * limits.sim_threads threads, and serialises the result with the handler's builders (answer.h).
 * The daemon runs them as background jobs (jobs/jobs.c), the CLI in the foreground;
 * ljgap__sim_status_answer answers a poll of a job, with a finished job's result as CSV when
 * Accept asks for it.
 */
#include "answer.h"
#include "clock.h" /* ljgap__clock_now */
#include "csv.h"
#include "handler.h"
#include "accept.h"
#include "ljgap_sim.h"
#include "problems.h" /* ljgap__ans_join_warnings */

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

struct ljgap__sim_request {
    job j;         /* the validated request (j.rq) and, while it runs, the answer */
    ljgap_psd psd; /* built from j.rq.psd at parse time */
};

ljgap__sim_request *ljgap__sim_request_parse(const char *body, size_t len, ljgap__reply *out)
{
    ljgap__sim_request *sr = calloc(1, sizeof *sr);
    ljgap__verr ve = {0};
    int st;
    memset(out, 0, sizeof *out);
    if (!sr) {
        ljgap__ans_oom(out);
        return NULL;
    }
    if (!ljgap__ans_validate(LJGAP_EP_SIMULATION, body, len, &sr->j, out)) goto fail;
    st = ljgap__psd_from_spec(&sr->psd, &sr->j.rq.psd);
    if (st == LJGAP_OK && sr->psd.m0 > 0 && sr->psd.m0 <= LJGAP_M0_MAX) return sr;
    if (st == LJGAP_ENOMEM || !(ve.errors = cJSON_CreateArray())) {
        ljgap__ans_oom(out);
        goto fail;
    }
    ljgap__verr_add(&ve, "/psd", "the PSD's variance m0 = %g is outside (0, %g]",
                   st == LJGAP_OK ? sr->psd.m0 : NAN, LJGAP_M0_MAX);
    if (ve.oom)
        ljgap__ans_oom(out);
    else
        ljgap__ans_problem(out, P_VALIDATION, "1 problem in the request: see errors", ve.errors);
    ve.errors = NULL;
fail:
    cJSON_Delete(ve.errors);
    ljgap__sim_request_free(sr);
    return NULL;
}

/* The result object of a run (api.md "simulations"). */
static void put_sim_result(job *j, const ljgap_sim_result *r, double t0)
{
    cJSON *jump, *err;
    size_t n = r->n_gap;
    ljgap__ans_nums(j, j->ans, "g_ave", r->g_ave, n, sizeof *r->g_ave, "g_ave");
    ljgap__ans_nums(j, j->ans, "sigma", r->sigma, n, sizeof *r->sigma, "sigma");
    ljgap__ans_nums(j, j->ans, "sigma_std", r->sigma_std, n, sizeof *r->sigma_std, "sigma_std");
    ljgap__ans_nums(j, j->ans, "sigma_out", r->sigma_out, n, sizeof *r->sigma_out, "sigma_out");
    ljgap__ans_nums(j, j->ans, "residual", r->residual, n, sizeof *r->residual, "residual");
    jump = ljgap__ans_put(j, j->ans, "jump", cJSON_CreateArray());
    for (size_t i = 0; jump && i < n; i++)
        ljgap__ans_put(j, jump, NULL, cJSON_CreateBool(r->jump[i]));
    ljgap__ans_nums(j, j->ans, "m0_realized", r->m0_realized, (size_t)r->realizations,
                   sizeof *r->m0_realized, "m0_realized");
    ljgap__ans_num(j, j->ans, "m0", r->m0_target, "m0", -1);
    ljgap__ans_num(j, j->ans, "m0_grid", r->m0_grid, "m0_grid", -1);
    ljgap__ans_num(j, j->ans, "L", r->L, "L", -1);
    ljgap__ans_put(j, j->ans, "n", cJSON_CreateNumber(r->n));
    ljgap__ans_put(j, j->ans, "realizations", cJSON_CreateNumber(r->realizations));
    ljgap__ans_put(j, j->ans, "seed", cJSON_CreateNumber((double)j->rq.sim.seed));
    ljgap__ans_put(j, j->ans, "tol", cJSON_CreateNumber(j->rq.sim.tol));
    ljgap__ans_put(j, j->ans, "elapsed_ms", cJSON_CreateNumber((ljgap__clock_now() - t0) * 1e3));
    err = ljgap__ans_put(j, j->ans, "error", cJSON_CreateObject());
    ljgap__ans_nums(j, err, "sigma", r->sigma_err, n, sizeof *r->sigma_err, "error.sigma");
    if (r->k_split > 0) { /* the hybrid: the fine band and its modified law */
        cJSON *fine;
        ljgap__ans_num(j, j->ans, "k_split", r->k_split, "k_split", -1);
        fine = ljgap__ans_put(j, j->ans, "fine", cJSON_CreateObject());
        ljgap__ans_summary(j, fine, fine, "error", &r->fine);
        ljgap__ans_num(j, fine, "law_error", r->law_err, "fine.law_error", -1);
    }
}

void ljgap__sim_request_run(ljgap__sim_request *sr, const ljgap__sim_control *ctl, ljgap__reply *out)
{
    double t0 = ljgap__clock_now();
    job *j = &sr->j;
    ljgap_sim_opts o = j->rq.sim;
    ljgap_sim_result res;
    char head[DETAIL_LEN + 200], detail[DETAIL_LEN];
    int st;
    memset(out, 0, sizeof *out);
    memset(&res, 0, sizeof res);
    long th = ljgap__handler_limits()->sim_threads > 0 ? ljgap__handler_limits()->sim_threads
                                                      : sysconf(_SC_NPROCESSORS_ONLN);
    o.threads = th < 1 ? 1 : th > LJGAP_SIM_THREADS_MAX ? LJGAP_SIM_THREADS_MAX : (int)th;
    if (ctl) {
        if (ctl->max_seconds > 0) o.max_seconds = ctl->max_seconds;
        o.cancel = ctl->cancel;
        o.progress = ctl->progress;
        o.progress_ctx = ctl->progress_ctx;
    }
    st = ljgap_sim_run(&sr->psd, &o, j->rq.x, j->rq.nx, &res, &j->rq.warn);
    if (!st && !(j->ans = cJSON_CreateObject())) st = LJGAP_ENOMEM;
    if (!st) {
        put_sim_result(j, &res, t0);
        ljgap__ans_meta(j, t0);
        if (j->oom) st = LJGAP_ENOMEM;
    }
    if (!st) {
        ljgap__ans_reply_json(out, 200, CT_JSON, j->ans);
    } else if (st == LJGAP_ECAP) {
        snprintf(head, sizeof head,
                 "the simulation needs more than the cap of %g s of wall time for one run; "
                 "ask for a smaller n, fewer realizations or fewer mean gaps",
                 o.max_seconds);
        ljgap__ans_join_warnings(detail, sizeof detail, head, &j->rq.warn);
        ljgap__ans_problem(out, P_CAP, detail, NULL);
    } else if (st == LJGAP_ECANCEL) {
        ljgap__ans_problem(out, P_UNAVAILABLE,
                          "the simulation was cancelled before it finished (DELETE, Ctrl-C, or the "
                          "server shutting down)",
                          NULL);
    } else {
        ljgap__ans_status(out, st, j);
    }
    cJSON_Delete(j->ans);
    j->ans = NULL;
    ljgap_sim_result_free(&res);
}

void ljgap__sim_request_free(ljgap__sim_request *sr)
{
    if (!sr) return;
    ljgap_psd_free(&sr->psd);
    ljgap__request_free(&sr->j.rq);
    free(sr);
}

void ljgap__sim_status_answer(const char *status_json, int http_status, const char *accept,
                             ljgap__reply *out)
{
    cJSON *doc = NULL;
    const char *state;
    char detail[200];
    int form;
    memset(out, 0, sizeof *out);
    if ((form = ljgap__ans_negotiate(accept, 1, out)) < 0) return;
    if (form == 1) {
        doc = cJSON_Parse(status_json);
        if (!doc) {
            ljgap__ans_oom(out);
            return;
        }
        state = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(doc, "status"));
        if (state && strcmp(state, "done") == 0) {
            if (ljgap__csv_render("simulations", cJSON_GetObjectItemCaseSensitive(doc, "result"), 0,
                                 out) != 0)
                ljgap__ans_oom(out);
            goto end;
        }
        if (ljgap__accept_pick(accept, ljgap__ans_forms, 1) < 0) { /* only CSV will do */
            snprintf(detail, sizeof detail,
                     "the job is %.20s: its result is there as text/csv once it is done; until "
                     "then ask for application/json too (Accept: text/csv, "
                     "application/json;q=0.5)",
                     state ? state : "not done");
            ljgap__ans_problem(out, P_NOT_ACCEPTABLE, detail, NULL);
            goto end;
        }
    }
    if (!(out->body = strdup(status_json))) {
        ljgap__ans_oom(out);
        goto end;
    }
    out->status = http_status;
    out->len = strlen(out->body);
    out->content_type = CT_JSON;
end:
    cJSON_Delete(doc);
}
