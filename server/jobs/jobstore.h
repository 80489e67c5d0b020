/* jobstore.h -- where background jobs live: a small interface with one backend per database.
 *
 * The job store keeps every job's row: its id, its kind, the request body as submitted, its
 * state, progress, timestamps and its answer. It knows nothing of HTTP or physics: a request
 * and an answer are opaque bytes to it (the answer is JSON text by convention), a kind is a
 * short name the job runner (jobs.h) maps to a function. Backends implement the table of
 * operations below: SQLite (jobstore_sqlite.c: one process owns a state directory) and
 * PostgreSQL (jobstore_pg.c: several daemons, on several machines, share one queue), with the
 * same semantics:
 *
 *   - a worker claims a job with a lease (claim) and renews it while it runs (renew); a
 *     running job whose lease lapsed can be claimed again (its worker died), and the claim
 *     counter `run` is the lease's token: renew, finish and release name it, and answer
 *     LJGAP_JOBSTORE_LOST once the job was claimed again by someone else;
 *   - renew writes progress, extends the lease and reads back a cancel request in one call,
 *     so a cancel asked anywhere reaches the worker at its next renewal;
 *   - every time is the store's clock (Unix seconds, a double), and every record carries the
 *     store's clock when it was read (`now`), so a caller never mixes clocks.
 *
 * States: queued -> running -> done | failed | cancelled, and queued -> cancelled (cancel
 * before a worker claims it), running -> queued (release: the worker stopped without an
 * answer, e.g. at shutdown; the job runs again from the start). Finished jobs are removed by
 * evict, never by anything else.
 *
 *   ljgap__jobstore *st;  char err[300];
 *   if (ljgap__jobstore_open_sqlite("/var/lib/ljgapd", &st, err, sizeof err)) fail(err);
 *   ljgap__jobstore_create(st, id, "simulation", body, len, 8);     HTTP thread: queue it
 *   ljgap__jobstore_claim(st, "host:pid", 30, &rec);                worker: take the oldest
 *   ljgap__jobstore_renew(st, rec.id, rec.run, 0.4, 30, &cancel);   worker, now and then
 *   ljgap__jobstore_finish(st, rec.id, rec.run, LJGAP_JOB_DONE, answer, n);
 *   ljgap__jobstore_get(st, id, &rec);  ...  ljgap__job_record_clear(&rec);
 *   ljgap__jobstore_close(st);
 *
 * Every operation is thread-safe and returns one of the LJGAP_JOBSTORE_* codes; when it is
 * LJGAP_JOBSTORE_ERROR, ljgap__jobstore_errmsg() gives the calling thread the reason (like
 * errno). Records read back are input like any other: a backend maps what it reads onto the
 * record's types (an unknown state becomes LJGAP_JOB_BAD) and never trusts a text column to
 * be valid JSON or UTF-8; jobstatus.h checks records before they reach a client.
 */
#ifndef LJGAP_JOBSTORE_H
#define LJGAP_JOBSTORE_H

#include <stddef.h>

#define LJGAP_JOB_ID_LEN 32   /* hex digits of a job id: 128 random bits */
#define LJGAP_JOB_KIND_MAX 31 /* longest kind name: lower-case letters, digits, '_' */

typedef enum {
    LJGAP_JOB_QUEUED,
    LJGAP_JOB_RUNNING,
    LJGAP_JOB_DONE,
    LJGAP_JOB_FAILED,
    LJGAP_JOB_CANCELLED,
    LJGAP_JOB_BAD, /* read back: the stored state is none of the above (a damaged row) */
} ljgap__job_state;

/* One job as read back from the store. Strings are what the row holds: checked for length,
 * not for content. */
typedef struct {
    char id[LJGAP_JOB_ID_LEN + 1];     /* as stored (claim) or as asked for (get, cancel) */
    char kind[LJGAP_JOB_KIND_MAX + 1]; /* as stored; "" if it did not fit */
    ljgap__job_state state;             /* LJGAP_JOB_BAD if the row's state is unknown */
    double progress;                   /* as stored (0..1 when the row is sound) */
    double created, started, finished; /* store clock, Unix seconds; 0 = not (yet) */
    double now;                        /* the store's clock when this was read */
    int cancel;                        /* a cancel was requested while it ran */
    long run;                          /* claims so far: the current claim's lease token */
    long lost;                         /* runs that ended without finishing (crash, lease) */
    char *request;                     /* claim only: the body as submitted, NUL-terminated */
    size_t request_len;                /* its length in bytes (it may hold NULs) */
    char *answer;                      /* result (done) or problem (failed, cancelled) text, */
    size_t answer_len;                 /* NUL-terminated, or NULL; its length in bytes */
} ljgap__job_record;

/* Status codes of every operation. */
enum {
    LJGAP_JOBSTORE_OK = 0,
    LJGAP_JOBSTORE_EMPTY = 1,   /* claim: nothing to claim */
    LJGAP_JOBSTORE_FULL = 2,    /* create: max_queued jobs are queued already */
    LJGAP_JOBSTORE_EXISTS = 3,  /* create: a job with this id exists */
    LJGAP_JOBSTORE_UNKNOWN = 4, /* get, cancel: no job with this id (never was, or evicted) */
    LJGAP_JOBSTORE_LOST = 5,    /* renew, finish, release: this claim is no longer current (the
                                 * lease lapsed and the job was claimed again, or it ended) */
    LJGAP_JOBSTORE_NOMEM = 6,   /* an allocation failed */
    LJGAP_JOBSTORE_ERROR = 7,   /* the database failed or refused: see ljgap__jobstore_errmsg */
    LJGAP_JOBSTORE_INVALID = 8, /* a bad argument (an id that is not 32 hex digits, ...) */
};

typedef struct ljgap__jobstore ljgap__jobstore;

/* The operations a backend implements. The public functions below check their arguments and
 * call these; a backend may rely on: ids are 32 lower-case hex digits, kinds are 1 to
 * LJGAP_JOB_KIND_MAX of [a-z0-9_], rec points at a zeroed record, lease_s > 0, progress in
 * [0, 1], answers are NUL-terminated with answer_len = strlen. */
typedef struct {
    const char *name; /* "sqlite" */
    int (*create)(ljgap__jobstore *st, const char *id, const char *kind, const char *request,
                  size_t len, unsigned max_queued);
    int (*claim)(ljgap__jobstore *st, const char *owner, double lease_s, ljgap__job_record *rec);
    int (*renew)(ljgap__jobstore *st, const char *id, long run, double progress, double lease_s,
                 int *cancel);
    int (*finish)(ljgap__jobstore *st, const char *id, long run, ljgap__job_state state,
                  const char *answer, size_t answer_len);
    int (*release)(ljgap__jobstore *st, const char *id, long run);
    int (*get)(ljgap__jobstore *st, const char *id, ljgap__job_record *rec);
    int (*cancel)(ljgap__jobstore *st, const char *id, ljgap__job_record *rec);
    int (*counts)(ljgap__jobstore *st, unsigned *queued, unsigned *running);
    int (*evict)(ljgap__jobstore *st, unsigned keep_done, double keep_seconds, unsigned *evicted);
    void (*close)(ljgap__jobstore *st);
} ljgap__jobstore_ops;

/* The head of every backend's handle (a backend's struct starts with it). */
struct ljgap__jobstore {
    const ljgap__jobstore_ops *ops;
    const char *where; /* for messages: the database file, or the URL without its password */
};

/* ---- opening: one function per backend ---- */

/* Opens (creating it if needed, parents too) the state directory dir: locks dir/lock against a
 * second daemon, opens dir/jobs.sqlite in WAL mode, checks it, creates or migrates its schema,
 * and puts the jobs that were running when the last owner stopped back in the queue (lost + 1;
 * a running job whose cancel was requested is cancelled instead). On failure returns
 * LJGAP_JOBSTORE_ERROR (or NOMEM) with one line in err naming the path and the reason: missing
 * and uncreatable, not a directory, not writable, in use by another process, not a database,
 * corrupt, a schema newer than this program knows. */
int ljgap__jobstore_open_sqlite(const char *dir, ljgap__jobstore **out, char *err, size_t errlen);

/* Opens the PostgreSQL job store at url (postgresql://[user[:password]@]host[:port]/dbname[?...],
 * or postgres://; anything libpq takes in a URI), shared by every daemon pointed at it: connects
 * (within 5 s), checks the server (9.5 or newer, UTF8 encoding), and creates or migrates its
 * schema `ljgapd` (tables schema_version and jobs) under an advisory lock, so daemons starting
 * together migrate once. Running jobs are left alone: other daemons may be running them, and a
 * job whose daemon died is claimed again once its lease lapses. Afterwards the store keeps at most
 * max_conns connections (0: 4), opened as threads need them; an operation never waits more than
 * 5 s for the database, and while the database is known to be unreachable operations fail at
 * once (LJGAP_JOBSTORE_ERROR) and one of them tries to reconnect every second. On failure
 * returns LJGAP_JOBSTORE_ERROR, NOMEM or INVALID (not such a URL) with one line in err naming
 * the database (never the password) and the reason. */
int ljgap__jobstore_open_pg(const char *url, unsigned max_conns, ljgap__jobstore **out, char *err,
                           size_t errlen);

/* The columns of one job row as the PostgreSQL backend reads them, in text format: */
enum {
    LJGAP_PG_ID,       /* text */
    LJGAP_PG_KIND,     /* text */
    LJGAP_PG_STATE,    /* text */
    LJGAP_PG_PROGRESS, /* float8 ("NaN", "Infinity" too) */
    LJGAP_PG_CREATED,  /* Unix seconds as float8, or NULL */
    LJGAP_PG_STARTED,
    LJGAP_PG_FINISHED,
    LJGAP_PG_CANCEL,  /* bool: "t" or "f" */
    LJGAP_PG_RUN,     /* int8 */
    LJGAP_PG_LOST,    /* int8 */
    LJGAP_PG_ANSWER,  /* text, or NULL */
    LJGAP_PG_NOW,     /* the database's clock, Unix seconds */
    LJGAP_PG_REQUEST, /* bytea in hex ("\x7b7d"): claim only */
    LJGAP_PG_COLS
};
/* Fills the zeroed *rec from a row's values (val[i] NULL for SQL NULL, len[i] its bytes; ncols
 * is LJGAP_PG_REQUEST or LJGAP_PG_COLS), trusting none of them: a text that does not fit is "",
 * an unknown state LJGAP_JOB_BAD, a number that does not parse 0, a request that is not hex
 * empty. 0, or LJGAP_JOBSTORE_NOMEM (rec cleared). The backend's reading, and the fuzzer's. */
int ljgap__jobstore_pg_row(ljgap__job_record *rec, const char *const *val, const int *len, int ncols);

/* Closes the store (NULL is fine). Running jobs stay as they are in the database. */
void ljgap__jobstore_close(ljgap__jobstore *st);

/* ---- operations ---- */

/* Adds job id (fresh: ljgap__job_id_new) of the given kind with the request bytes, queued,
 * created now, unless max_queued or more jobs are queued (LJGAP_JOBSTORE_FULL; 0 = no cap) or
 * the id exists (LJGAP_JOBSTORE_EXISTS). LJGAP_JOBSTORE_OK means the row is durable: it is
 * committed to stable storage before this returns. */
int ljgap__jobstore_create(ljgap__jobstore *st, const char *id, const char *kind, const char *request,
                          size_t len, unsigned max_queued);

/* Claims the oldest job that is queued, or running with a lapsed lease (then lost + 1), for
 * owner (a name for diagnostics): it becomes running with run + 1, started now, progress 0 and
 * a lease of lease_s seconds. *rec receives it, with its request; the caller runs it unless
 * rec->cancel is set (cancel requested during a lost run: finish it cancelled). */
int ljgap__jobstore_claim(ljgap__jobstore *st, const char *owner, double lease_s,
                         ljgap__job_record *rec);

/* While running claim `run` of job id: raises its progress to `progress` (never lowers it),
 * extends its lease to now + lease_s and sets *cancel to 1 if a cancel was requested. */
int ljgap__jobstore_renew(ljgap__jobstore *st, const char *id, long run, double progress,
                         double lease_s, int *cancel);

/* Ends claim `run` of job id in state done, failed or cancelled, finished now, with answer
 * (answer_len bytes; NULL for none). Done sets progress to 1. */
int ljgap__jobstore_finish(ljgap__jobstore *st, const char *id, long run, ljgap__job_state state,
                          const char *answer, size_t answer_len);

/* Gives claim `run` of job id back: queued again, progress 0, in its old place in the queue. */
int ljgap__jobstore_release(ljgap__jobstore *st, const char *id, long run);

/* The record of job id (without its request). */
int ljgap__jobstore_get(ljgap__jobstore *st, const char *id, ljgap__job_record *rec);

/* Requests the cancel of job id: a queued job is cancelled now (finished, no answer); a
 * running one is flagged (its worker sees the flag at its next renew, or at once through the
 * runner when it runs in this process); a finished one is left as it is. *rec receives the
 * record afterwards. */
int ljgap__jobstore_cancel(ljgap__jobstore *st, const char *id, ljgap__job_record *rec);

/* Jobs queued and running now (running includes lapsed leases not yet claimed again). */
int ljgap__jobstore_counts(ljgap__jobstore *st, unsigned *queued, unsigned *running);

/* Removes finished jobs (done, failed, cancelled) that finished more than keep_seconds ago,
 * then the oldest finished beyond the keep_done most recent. *evicted (may be NULL) receives
 * the number removed. */
int ljgap__jobstore_evict(ljgap__jobstore *st, unsigned keep_done, double keep_seconds,
                         unsigned *evicted);

/* ---- helpers shared by backends and callers ---- */

/* The calling thread's reason for its last LJGAP_JOBSTORE_ERROR ("" if none). */
const char *ljgap__jobstore_errmsg(void);
/* Sets it (printf-style): for backends. */
void ljgap__jobstore_set_errmsg(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* A fresh random id (128 bits from getrandom, in hex); 0, or -1 if no randomness. */
int ljgap__job_id_new(char id[LJGAP_JOB_ID_LEN + 1]);
/* Is s exactly LJGAP_JOB_ID_LEN lower-case hex digits? */
int ljgap__job_id_valid(const char *s);
/* Is s a kind name (1 to LJGAP_JOB_KIND_MAX of [a-z0-9_])? */
int ljgap__job_kind_valid(const char *s);

/* "queued", "running", "done", "failed", "cancelled" (NULL for LJGAP_JOB_BAD), and back
 * (LJGAP_JOB_BAD for anything else, NULL included). */
const char *ljgap__job_state_name(ljgap__job_state s);
ljgap__job_state ljgap__job_state_parse(const char *s);

/* Frees a record's request and answer and zeroes it (NULL is fine). */
void ljgap__job_record_clear(ljgap__job_record *rec);

/* The store's clock for backends that have none of their own: CLOCK_REALTIME in seconds. */
double ljgap__jobstore_wallclock(void);

#endif
