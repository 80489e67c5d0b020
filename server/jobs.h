/* jobs.h -- background jobs for the HTTP daemon: a bounded queue, worker threads, a store.
 *
 * A job is a function that writes one reply (handler.h): the daemon submits numerical-model
 * runs (ljgap_sim_request_run) and clients poll them by id. The store knows nothing of
 * physics or HTTP; it only runs functions, keeps their answers and counts progress.
 *
 *   ljgap_jobs *js = ljgap_jobs_alloc(&cfg);        workers start here
 *   ljgap_jobs_submit(js, run, arg, free_arg, id);  queued, or LJGAP_JOBS_FULL
 *   ljgap_jobs_status(js, id, &json);               {"id","status","progress",...}
 *   ljgap_jobs_cancel(js, id, wait_s, &json);       cancel, then the same status object
 *   ljgap_jobs_shutdown(js);                        at SIGTERM: cancel everything
 *   ljgap_jobs_free(js);                            join the workers, free everything
 *
 * States: queued -> running -> done | failed | cancelled (queued -> cancelled directly when
 * cancelled before a worker takes it). A run whose reply is 2xx is done; a run that returns
 * a problem is failed, or cancelled when its cancel flag was raised. Finished jobs are kept
 * for keep_seconds, and at most keep_done of them (the oldest finished goes first); queued
 * and running jobs are never evicted. Every function is thread-safe.
 */
#ifndef LJGAP_JOBS_H
#define LJGAP_JOBS_H

#include "handler.h"

#include <stddef.h>

#define LJGAP_JOB_ID_LEN 32 /* hex digits of a job id: 128 random bits */

/* What a running job may look at: its cancel flag and where to report progress. */
typedef struct {
    const volatile int *cancel;                   /* nonzero: stop early (ljgap_sim_opts.cancel) */
    void (*progress)(void *ctx, double fraction); /* fraction done, 0..1; cheap */
    void *ctx;                                    /* first argument of progress */
} ljgap_job_ctl;

/* The work of a job: fills *out (a 2xx JSON answer, or a problem). */
typedef void (*ljgap_job_fn)(void *arg, const ljgap_job_ctl *ctl, ljgap_reply *out);

typedef struct {
    unsigned workers;    /* worker threads, jobs running at once (default 1) */
    unsigned queue_cap;  /* jobs waiting for a worker; more get LJGAP_JOBS_FULL (default 8) */
    unsigned keep_done;  /* finished jobs kept (default 64) */
    double keep_seconds; /* how long a finished job is kept (default 3600 s) */
} ljgap_jobs_config;

void ljgap_jobs_config_default(ljgap_jobs_config *c);

typedef struct ljgap_jobs ljgap_jobs;

/* Status codes of submit, status and cancel. */
enum {
    LJGAP_JOBS_OK = 0,
    LJGAP_JOBS_FULL = 1,     /* submit: the queue is full */
    LJGAP_JOBS_STOPPING = 2, /* submit: shutting down, no new jobs */
    LJGAP_JOBS_UNKNOWN = 3,  /* status/cancel: no job with that id (never was, or evicted) */
    LJGAP_JOBS_NOMEM = 4,    /* an allocation failed */
};

/* Starts the workers; NULL if memory or threads run out (nothing is left behind). */
ljgap_jobs *ljgap_jobs_alloc(const ljgap_jobs_config *c);

/* Queues run(arg). The store owns arg from here on, whatever the result, and releases it
 * with free_arg (may be NULL) once the job has run or was cancelled. id receives the new id
 * (LJGAP_JOB_ID_LEN hex digits and a NUL). */
int ljgap_jobs_submit(ljgap_jobs *js, ljgap_job_fn run, void *arg, void (*free_arg)(void *),
                      char id[LJGAP_JOB_ID_LEN + 1]);

/* The status object of job id as a malloc'd JSON string (one line):
 *   {"id","status","progress","elapsed_ms"[,"result"][,"problem"]}
 * progress is 0..1, elapsed_ms the running time so far (0 while queued), result the run's
 * answer when done, problem its problem when failed (or cancelled while running). */
int ljgap_jobs_status(ljgap_jobs *js, const char *id, char **json);

/* Cancels job id: a queued job is cancelled at once; a running one has its cancel flag
 * raised and is waited for up to wait_s seconds; a finished one is left as it is. *json
 * receives the status afterwards (as ljgap_jobs_status); *final is 1 when the job has
 * finished (in any state), 0 when it is still running. */
int ljgap_jobs_cancel(ljgap_jobs *js, const char *id, double wait_s, char **json, int *final);

/* Number of jobs queued and running now. */
void ljgap_jobs_counts(ljgap_jobs *js, unsigned *queued, unsigned *running);

/* Refuses new jobs, cancels the queued ones and raises the cancel flag of the running ones.
 * Returns at once. */
void ljgap_jobs_shutdown(ljgap_jobs *js);

/* Waits up to wait_s seconds for the running jobs to return; 1 when none is running. */
int ljgap_jobs_wait_idle(ljgap_jobs *js, double wait_s);

/* Shuts down (if not yet), joins the workers and frees everything. NULL is fine. */
void ljgap_jobs_free(ljgap_jobs *js);

#endif
