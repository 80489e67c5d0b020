/* jobs.h -- background jobs for the HTTP daemon: worker threads running jobs from a job store.
 *
 * A job is a request body of some kind (the daemon has one, "simulation") kept in a job store
 * (jobstore.h: SQLite, or PostgreSQL shared by several daemons). Submitting writes it there;
 * worker threads claim jobs from the store, run the kind's function on the stored body and
 * write progress and the answer back; clients poll by id. Since a job is its stored body, a
 * daemon that restarts (or crashes) runs the jobs that were queued or running again from the
 * start, under the same ids, and keeps serving the finished ones until they expire; with a
 * shared store another daemon does, once the lost job's lease lapses. The runner knows nothing of
 * physics or HTTP: kinds are functions given at start.
 *
 *   ljgap__jobs *js = ljgap__jobs_alloc(&cfg, store, kinds, nkinds);   workers start here
 *   ljgap__jobs_submit(js, "simulation", body, len, id);   durable, or LJGAP_JOBS_FULL
 *   ljgap__jobs_status(js, id, &json);                     {"id","status","progress",...}
 *   ljgap__jobs_cancel(js, id, wait_s, &json, &final);     cancel, then the same status object
 *   ljgap__jobs_shutdown(js);                              at SIGTERM: stop the running ones
 *   ljgap__jobs_free(js);                                  join the workers
 *
 * States (jobstore.h): queued -> running -> done | failed | cancelled. A run whose reply is
 * 2xx is done; a run that returns a problem is failed, or cancelled when a cancel was asked.
 * At shutdown the running jobs are stopped and put back in the queue (they run again at the
 * next start); queued jobs stay queued. A job whose runs were lost max_lost times (the daemon
 * died each time) fails with a job-abandoned problem instead of running again, so one job
 * that crashes the daemon cannot keep it in a restart loop. Finished jobs are kept for
 * keep_seconds, and at most keep_done of them. Every function is thread-safe.
 *
 * Threads: `workers` workers, and one keeper that every fraction of a second writes the running
 * jobs' progress, renews their leases and reads back cancel requests made elsewhere (so a
 * progress callback costs no I/O and a job whose computation reports nothing keeps its lease),
 * and evicts expired jobs now and then.
 */
#ifndef LJGAP_JOBS_H
#define LJGAP_JOBS_H

#include "reply.h"
#include "jobstore.h"

#include <stddef.h>

/* What a running job may look at: its cancel flag and where to report progress. */
typedef struct {
    const volatile int *cancel;                   /* nonzero: stop early (ljgap_sim_opts.cancel) */
    void (*progress)(void *ctx, double fraction); /* fraction done, 0..1; cheap, no I/O */
    void *ctx;                                    /* first argument of progress */
} ljgap__job_ctl;

/* A kind of job: its name and the function that runs a stored request body of that kind,
 * filling *out (a 2xx JSON answer, or a problem; a body that does not parse is a problem). */
typedef struct {
    const char *name; /* jobstore.h kind name, e.g. "simulation" */
    void (*run)(void *ctx, const char *body, size_t len, const ljgap__job_ctl *ctl,
                ljgap__reply *out);
    void *ctx; /* first argument of run */
} ljgap__job_kind;

typedef struct {
    unsigned workers;        /* worker threads, jobs running at once (default 1) */
    unsigned queue_cap;      /* jobs waiting; more get LJGAP_JOBS_FULL (default 8) */
    unsigned keep_done;      /* finished jobs kept (default 64) */
    double keep_seconds;     /* how long a finished job is kept (default 3600 s) */
    double lease_seconds;    /* a running job's lease, renewed every third of it (default 30) */
    double progress_seconds; /* progress is written at most this often (default 0.5 s) */
    double poll_seconds;     /* idle workers look at the store this often (default 1 s) */
    unsigned max_lost;       /* a job whose runs were lost this often fails (default 3) */
} ljgap__jobs_config;

void ljgap__jobs_config_default(ljgap__jobs_config *c);

typedef struct ljgap__jobs ljgap__jobs;

/* Status codes of submit, status and cancel. */
enum {
    LJGAP_JOBS_OK = 0,
    LJGAP_JOBS_FULL = 1,     /* submit: the queue is full */
    LJGAP_JOBS_STOPPING = 2, /* submit: shutting down, no new jobs */
    LJGAP_JOBS_UNKNOWN = 3,  /* status/cancel: no job with that id (never was, or evicted) */
    LJGAP_JOBS_NOMEM = 4,    /* an allocation failed */
    LJGAP_JOBS_STORE = 5,    /* the job store failed: ljgap__jobstore_errmsg() says why */
};

/* Starts the workers on store (which stays the caller's, to close after ljgap__jobs_free).
 * kinds[0..nkinds) are copied. NULL if the configuration is bad or memory or threads run
 * out (nothing is left behind). */
ljgap__jobs *ljgap__jobs_alloc(const ljgap__jobs_config *c, ljgap__jobstore *store,
                             const ljgap__job_kind *kinds, size_t nkinds);

/* Stores a job of the given kind (one of the kinds given at alloc) with the request body,
 * queued. LJGAP_JOBS_OK means it is committed to the store: it survives a crash from here on.
 * id receives its id (LJGAP_JOB_ID_LEN hex digits and a NUL; "" on failure). */
int ljgap__jobs_submit(ljgap__jobs *js, const char *kind, const char *body, size_t len,
                      char id[LJGAP_JOB_ID_LEN + 1]);

/* The status object of job id as a malloc'd JSON string (jobstatus.h). */
int ljgap__jobs_status(ljgap__jobs *js, const char *id, char **json);

/* Cancels job id: a queued job is cancelled at once; a running one is told to stop (at once
 * when it runs here, at its next lease renewal elsewhere) and waited for up to wait_s seconds;
 * a finished one is left as it is. *json receives the status afterwards (as
 * ljgap__jobs_status); *final is 1 when the job has finished (in any state), 0 when it is still
 * running. */
int ljgap__jobs_cancel(ljgap__jobs *js, const char *id, double wait_s, char **json, int *final);

/* Number of jobs queued and running now (in the whole store); 0 or LJGAP_JOBS_STORE. */
int ljgap__jobs_counts(ljgap__jobs *js, unsigned *queued, unsigned *running);

/* Refuses new jobs, stops claiming and raises the cancel flag of the jobs running here, which
 * go back to the queue when they return. Returns at once. */
void ljgap__jobs_shutdown(ljgap__jobs *js);

/* Waits up to wait_s seconds for the jobs running here to return; 1 when none is running. */
int ljgap__jobs_wait_idle(ljgap__jobs *js, double wait_s);

/* Shuts down (if not yet), joins the threads and frees everything but the store. NULL is
 * fine. */
void ljgap__jobs_free(ljgap__jobs *js);

#endif
