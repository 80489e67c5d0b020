/* jobstore_sqlite.c -- the job store in SQLite: DIR/jobs.sqlite, owned by one daemon at a time.
 *
 * Files in the state directory DIR:
 *   DIR/lock          flock(2)ed for as long as the store is open, and holding the owner's pid,
 *                     so a second daemon pointed at DIR by mistake stops at start-up instead
 *                     of sharing (and requeueing) the first one's running jobs;
 *   DIR/jobs.sqlite   the database, in WAL mode (-wal and -shm beside it while open).
 *
 * Durability: what acknowledges something to a client or ends a job (create, cancel, finish,
 * release) commits with synchronous=FULL, so it is on stable storage (the WAL is fsync'ed)
 * before the call returns: a job answered 202 survives SIGKILL and power loss alike. What a
 * power cut could only make happen again (claim, renew, evict) commits with NORMAL, which a
 * killed process does not lose either, and costs no fsync (see durability()). A FULL commit
 * costs one fsync: 0.2 to 4 ms on this machine's disk, depending on its load.
 *
 * Threads: one connection, serialised by a mutex. Every operation is a single short statement
 * (a read in well under 0.1 ms, a FULL commit in one fsync); the threads that use the store are the
 * job workers, their keeper and the HTTP threads answering job routes; SQLite admits one writer at
 * a time anyway. A connection per thread would buy concurrent reads during a commit, at the
 * price of opening a connection (and parsing the schema) per HTTP connection thread and
 * repeating the prepared statements per connection. The busy timeout (5 s) covers other
 * processes that read the file meanwhile (sqlite3 on the command line).
 *
 * Reading back: every column is read with the type it should have and copied into the
 * record; an unknown state becomes LJGAP_JOB_BAD. The schema's CHECK constraints and STRICT
 * types keep rows sound, but a damaged or hand-edited file can still hold anything, so callers
 * check records before use (jobstatus.h) and never trust a text column.
 *
 * Schema versions: the table schema_version holds one number; migrations[] brings a database
 * from version v to v + 1, all of them in one transaction at open. A database newer than this
 * program is refused, as is a database of some other program (PRAGMA application_id).
 */
#include "jobstore.h"

#include <sqlite3.h>

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#define APP_ID 1279936324 /* PRAGMA application_id of a job store: 0x4c4a4744, "LJGD" */
#define STR(x) #x
#define XSTR(x) STR(x)
#define BUSY_MS 5000 /* wait this long for another process's lock */

/* migrations[v] brings the schema from version v to v + 1. */
static const char *const migrations[] = {
    /* 0 -> 1: the jobs table */
    "CREATE TABLE schema_version (version INTEGER NOT NULL) STRICT;"
    "INSERT INTO schema_version VALUES (0);"
    "CREATE TABLE jobs ("
    "  seq INTEGER PRIMARY KEY," /* submission order: the queue is FIFO */
    "  id TEXT NOT NULL UNIQUE CHECK (length(id) = 32 AND id NOT GLOB '*[^0-9a-f]*'),"
    "  kind TEXT NOT NULL CHECK (length(kind) BETWEEN 1 AND 31),"
    "  request BLOB NOT NULL," /* the body as submitted */
    "  state TEXT NOT NULL CHECK (state IN ('queued','running','done','failed','cancelled')),"
    "  progress REAL NOT NULL DEFAULT 0 CHECK (progress BETWEEN 0 AND 1),"
    "  created REAL NOT NULL,"             /* Unix seconds */
    "  started REAL,"                      /* the current (or last) run's start */
    "  finished REAL,"                     /* when it reached done, failed or cancelled */
    "  cancel INTEGER NOT NULL DEFAULT 0," /* a cancel was requested while it ran */
    "  run INTEGER NOT NULL DEFAULT 0,"    /* claims so far: the lease token */
    "  lost INTEGER NOT NULL DEFAULT 0,"   /* runs that ended without finishing */
    "  owner TEXT,"                        /* who runs it (host:pid), for the curious */
    "  lease_until REAL,"                  /* a running job's lease */
    "  answer TEXT"                        /* result (done) or problem (failed, cancelled) */
    ") STRICT;"
    "CREATE INDEX jobs_state ON jobs (state, seq);"
    "PRAGMA application_id = " XSTR(APP_ID) ";",
};
#define SCHEMA_VERSION ((int)(sizeof migrations / sizeof migrations[0]))

/* The columns of a record, in the order read_record expects them. */
#define RECORD_COLS                                                                                \
    "id, kind, state, progress, created, started, finished, cancel, run, lost, answer"

enum {
    S_CREATE,
    S_CLAIM,
    S_RENEW,
    S_FINISH,
    S_RELEASE,
    S_GET,
    S_CANCEL,
    S_COUNTS,
    S_EVICT,
    S_SYNC_NORMAL,
    S_SYNC_FULL,
    S_N
};

static const char *const sql[S_N] = {
    [S_CREATE] = "INSERT INTO jobs (id, kind, request, state, created) "
                 "SELECT ?1, ?2, ?3, 'queued', ?4 "
                 "WHERE ?5 = 0 OR (SELECT count(*) FROM jobs WHERE state = 'queued') < ?5",
    [S_CLAIM] = "UPDATE jobs SET state = 'running', run = run + 1, lost = lost + (state = "
                "'running'), started = ?1, progress = 0, lease_until = ?1 + ?2, owner = ?3 "
                "WHERE seq = (SELECT seq FROM jobs WHERE state = 'queued' "
                "OR (state = 'running' AND lease_until < ?1) ORDER BY seq LIMIT 1) "
                "RETURNING " RECORD_COLS ", request",
    [S_RENEW] = "UPDATE jobs SET progress = max(progress, ?3), lease_until = ?4 + ?5 "
                "WHERE id = ?1 AND run = ?2 AND state = 'running' RETURNING cancel",
    [S_FINISH] = "UPDATE jobs SET state = ?3, answer = ?4, finished = ?5, lease_until = NULL, "
                 "owner = NULL, progress = CASE WHEN ?3 = 'done' THEN 1 ELSE progress END "
                 "WHERE id = ?1 AND run = ?2 AND state = 'running'",
    [S_RELEASE] = "UPDATE jobs SET state = 'queued', started = NULL, progress = 0, "
                  "lease_until = NULL, owner = NULL "
                  "WHERE id = ?1 AND run = ?2 AND state = 'running'",
    [S_GET] = "SELECT " RECORD_COLS " FROM jobs WHERE id = ?1",
    [S_CANCEL] = "UPDATE jobs SET state = CASE state WHEN 'queued' THEN 'cancelled' ELSE state "
                 "END, finished = CASE state WHEN 'queued' THEN ?2 ELSE finished END, "
                 "cancel = CASE state WHEN 'running' THEN 1 ELSE cancel END "
                 "WHERE id = ?1 AND state IN ('queued', 'running') RETURNING " RECORD_COLS,
    [S_COUNTS] = "SELECT coalesce(sum(state = 'queued'), 0), coalesce(sum(state = 'running'), 0) "
                 "FROM jobs WHERE state IN ('queued', 'running')",
    [S_EVICT] = "DELETE FROM jobs WHERE state NOT IN ('queued', 'running') AND "
                "(coalesce(finished, 0) < ?1 OR seq NOT IN (SELECT seq FROM jobs "
                "WHERE state NOT IN ('queued', 'running') ORDER BY finished DESC, seq DESC "
                "LIMIT ?2))",
    [S_SYNC_NORMAL] = "PRAGMA synchronous = NORMAL",
    [S_SYNC_FULL] = "PRAGMA synchronous = FULL",
};

typedef struct {
    ljgap__jobstore base;     /* the operations; first, so a ljgap__jobstore * points here */
    pthread_mutex_t lock;    /* serialises every use of db and of the statements */
    sqlite3 *db;             /* the one connection */
    sqlite3_stmt *stmt[S_N]; /* prepared once at open */
    int lock_fd;             /* DIR/lock, flock'ed while open; -1 when not */
    int sync_normal;         /* synchronous is NORMAL now (else FULL) */
    char *path;              /* DIR/jobs.sqlite, for messages */
} sqlite_store;

/* ---- errors ---- */

/* Records the connection's last error for the calling thread; returns LJGAP_JOBSTORE_ERROR
 * (NOMEM for SQLITE_NOMEM). */
static int db_error(sqlite_store *s, const char *what)
{
    int code = sqlite3_errcode(s->db);
    ljgap__jobstore_set_errmsg("%s: %s: %s", s->path, what, sqlite3_errmsg(s->db));
    return code == SQLITE_NOMEM ? LJGAP_JOBSTORE_NOMEM : LJGAP_JOBSTORE_ERROR;
}

/* ---- durability ---- */

/* Commits that acknowledge something (create, finish, release, cancel) are synchronous=FULL;
 * those whose loss a power cut would only repeat (a claim or a lease renewal: the job runs
 * again; an eviction) are NORMAL, durable against a killed process but not a power cut, and
 * cost no fsync. Either way the WAL keeps the file consistent, and a FULL commit syncs the
 * NORMAL ones before it too. Lock held. */
static void durability(sqlite_store *s, int full)
{
    sqlite3_stmt *q = s->stmt[full ? S_SYNC_FULL : S_SYNC_NORMAL];
    if (s->sync_normal == !full) return;
    while (sqlite3_step(q) == SQLITE_ROW)
        ;
    sqlite3_reset(q);
    s->sync_normal = !full;
}

/* ---- reading rows ---- */

/* A malloc'd NUL-terminated copy of column col (text or blob, whatever it holds) and its
 * length; *out NULL for SQL NULL. 0, or -1 when memory ran out. */
static int column_copy(sqlite3_stmt *q, int col, char **out, size_t *len)
{
    const void *p;
    int n;
    *out = NULL;
    *len = 0;
    if (sqlite3_column_type(q, col) == SQLITE_NULL) return 0;
    p = sqlite3_column_blob(q, col);
    n = sqlite3_column_bytes(q, col);
    if (!p && n > 0) return -1;
    if (!(*out = malloc((size_t)n + 1))) return -1;
    if (n) memcpy(*out, p, (size_t)n);
    (*out)[n] = '\0';
    *len = (size_t)n;
    return 0;
}

/* Copies column col, a short text, into dst (size cap) when it fits; "" otherwise. */
static void column_short(sqlite3_stmt *q, int col, char *dst, size_t cap)
{
    const unsigned char *t = sqlite3_column_text(q, col);
    int n = sqlite3_column_bytes(q, col);
    dst[0] = '\0';
    if (t && n >= 0 && (size_t)n < cap && memchr(t, '\0', (size_t)n) == NULL) {
        memcpy(dst, t, (size_t)n);
        dst[n] = '\0';
    }
}

/* The row at q (RECORD_COLS, then request when with_request) into rec. */
static int read_record(sqlite_store *s, sqlite3_stmt *q, ljgap__job_record *rec, int with_request)
{
    char state[16];
    column_short(q, 0, rec->id, sizeof rec->id);
    column_short(q, 1, rec->kind, sizeof rec->kind);
    column_short(q, 2, state, sizeof state);
    rec->state = ljgap__job_state_parse(state);
    rec->progress = sqlite3_column_double(q, 3);
    rec->created = sqlite3_column_double(q, 4);
    rec->started = sqlite3_column_double(q, 5);
    rec->finished = sqlite3_column_double(q, 6);
    rec->cancel = sqlite3_column_int64(q, 7) != 0;
    rec->run = (long)sqlite3_column_int64(q, 8);
    rec->lost = (long)sqlite3_column_int64(q, 9);
    if (column_copy(q, 10, &rec->answer, &rec->answer_len) != 0 ||
        (with_request && column_copy(q, 11, &rec->request, &rec->request_len) != 0)) {
        ljgap__job_record_clear(rec);
        ljgap__jobstore_set_errmsg("%s: out of memory reading a job", s->path);
        return LJGAP_JOBSTORE_NOMEM;
    }
    if (with_request && !rec->request && !(rec->request = calloc(1, 1))) {
        ljgap__job_record_clear(rec);
        return LJGAP_JOBSTORE_NOMEM;
    }
    return LJGAP_JOBSTORE_OK;
}

/* ---- running statements (lock held) ---- */

/* Steps q to its end. With rec, the first row (if any) is read into it and *got set; the
 * other columns' values are dropped. Resets q either way. */
static int run_stmt(sqlite_store *s, int which, ljgap__job_record *rec, int with_request, int *got)
{
    sqlite3_stmt *q = s->stmt[which];
    int rc, st = LJGAP_JOBSTORE_OK;
    if (got) *got = 0;
    while ((rc = sqlite3_step(q)) == SQLITE_ROW)
        if (rec && got && !*got && st == LJGAP_JOBSTORE_OK) {
            st = read_record(s, q, rec, with_request);
            *got = st == LJGAP_JOBSTORE_OK;
        }
    if (rc != SQLITE_DONE) {
        if (rec) ljgap__job_record_clear(rec);
        st = db_error(s, "statement failed");
        if (got) *got = 0;
    }
    sqlite3_reset(q);
    sqlite3_clear_bindings(q);
    return st;
}

static int bind_text(sqlite3_stmt *q, int i, const char *t)
{
    return sqlite3_bind_text(q, i, t, -1, SQLITE_STATIC);
}

/* ---- the operations ---- */

static int op_create(ljgap__jobstore *base, const char *id, const char *kind, const char *request,
                     size_t len, unsigned max_queued)
{
    sqlite_store *s = (sqlite_store *)base;
    sqlite3_stmt *q;
    int st = LJGAP_JOBSTORE_OK, rc;
    if (len > INT_MAX) return LJGAP_JOBSTORE_INVALID;
    pthread_mutex_lock(&s->lock);
    durability(s, 1);
    q = s->stmt[S_CREATE];
    bind_text(q, 1, id);
    bind_text(q, 2, kind);
    sqlite3_bind_blob(q, 3, request, (int)len, SQLITE_STATIC);
    sqlite3_bind_double(q, 4, ljgap__jobstore_wallclock());
    sqlite3_bind_int64(q, 5, max_queued);
    rc = sqlite3_step(q);
    if (rc == SQLITE_DONE)
        st = sqlite3_changes(s->db) == 1 ? LJGAP_JOBSTORE_OK : LJGAP_JOBSTORE_FULL;
    else if (sqlite3_extended_errcode(s->db) == SQLITE_CONSTRAINT_UNIQUE)
        st = LJGAP_JOBSTORE_EXISTS;
    else
        st = db_error(s, "cannot add a job");
    sqlite3_reset(q);
    sqlite3_clear_bindings(q);
    pthread_mutex_unlock(&s->lock);
    return st;
}

static int op_claim(ljgap__jobstore *base, const char *owner, double lease_s, ljgap__job_record *rec)
{
    sqlite_store *s = (sqlite_store *)base;
    double now = ljgap__jobstore_wallclock();
    int st, got = 0;
    pthread_mutex_lock(&s->lock);
    durability(s, 0);
    sqlite3_bind_double(s->stmt[S_CLAIM], 1, now);
    sqlite3_bind_double(s->stmt[S_CLAIM], 2, lease_s);
    bind_text(s->stmt[S_CLAIM], 3, owner);
    st = run_stmt(s, S_CLAIM, rec, 1, &got);
    pthread_mutex_unlock(&s->lock);
    rec->now = now;
    return st == LJGAP_JOBSTORE_OK && !got ? LJGAP_JOBSTORE_EMPTY : st;
}

static int op_renew(ljgap__jobstore *base, const char *id, long run, double progress, double lease_s,
                    int *cancel)
{
    sqlite_store *s = (sqlite_store *)base;
    sqlite3_stmt *q;
    int rc, st = LJGAP_JOBSTORE_LOST;
    pthread_mutex_lock(&s->lock);
    durability(s, 0);
    q = s->stmt[S_RENEW];
    bind_text(q, 1, id);
    sqlite3_bind_int64(q, 2, run);
    sqlite3_bind_double(q, 3, progress);
    sqlite3_bind_double(q, 4, ljgap__jobstore_wallclock());
    sqlite3_bind_double(q, 5, lease_s);
    while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
        *cancel = sqlite3_column_int64(q, 0) != 0;
        st = LJGAP_JOBSTORE_OK;
    }
    if (rc != SQLITE_DONE) st = db_error(s, "cannot renew a job's lease");
    sqlite3_reset(q);
    sqlite3_clear_bindings(q);
    pthread_mutex_unlock(&s->lock);
    return st;
}

static int op_finish(ljgap__jobstore *base, const char *id, long run, ljgap__job_state state,
                     const char *answer, size_t answer_len)
{
    sqlite_store *s = (sqlite_store *)base;
    sqlite3_stmt *q;
    int st;
    if (answer_len > INT_MAX) return LJGAP_JOBSTORE_INVALID;
    pthread_mutex_lock(&s->lock);
    durability(s, 1);
    q = s->stmt[S_FINISH];
    bind_text(q, 1, id);
    sqlite3_bind_int64(q, 2, run);
    bind_text(q, 3, ljgap__job_state_name(state));
    if (answer)
        sqlite3_bind_text(q, 4, answer, (int)answer_len, SQLITE_STATIC);
    else
        sqlite3_bind_null(q, 4);
    sqlite3_bind_double(q, 5, ljgap__jobstore_wallclock());
    st = run_stmt(s, S_FINISH, NULL, 0, NULL);
    if (st == LJGAP_JOBSTORE_OK && sqlite3_changes(s->db) != 1) st = LJGAP_JOBSTORE_LOST;
    pthread_mutex_unlock(&s->lock);
    return st;
}

static int op_release(ljgap__jobstore *base, const char *id, long run)
{
    sqlite_store *s = (sqlite_store *)base;
    int st;
    pthread_mutex_lock(&s->lock);
    durability(s, 1);
    bind_text(s->stmt[S_RELEASE], 1, id);
    sqlite3_bind_int64(s->stmt[S_RELEASE], 2, run);
    st = run_stmt(s, S_RELEASE, NULL, 0, NULL);
    if (st == LJGAP_JOBSTORE_OK && sqlite3_changes(s->db) != 1) st = LJGAP_JOBSTORE_LOST;
    pthread_mutex_unlock(&s->lock);
    return st;
}

/* get, lock held */
static int get_locked(sqlite_store *s, const char *id, ljgap__job_record *rec)
{
    int st, got = 0;
    bind_text(s->stmt[S_GET], 1, id);
    st = run_stmt(s, S_GET, rec, 0, &got);
    rec->now = ljgap__jobstore_wallclock();
    return st == LJGAP_JOBSTORE_OK && !got ? LJGAP_JOBSTORE_UNKNOWN : st;
}

static int op_get(ljgap__jobstore *base, const char *id, ljgap__job_record *rec)
{
    sqlite_store *s = (sqlite_store *)base;
    int st;
    pthread_mutex_lock(&s->lock);
    st = get_locked(s, id, rec);
    pthread_mutex_unlock(&s->lock);
    return st;
}

static int op_cancel(ljgap__jobstore *base, const char *id, ljgap__job_record *rec)
{
    sqlite_store *s = (sqlite_store *)base;
    double now = ljgap__jobstore_wallclock();
    int st, got = 0;
    pthread_mutex_lock(&s->lock);
    durability(s, 1);
    bind_text(s->stmt[S_CANCEL], 1, id);
    sqlite3_bind_double(s->stmt[S_CANCEL], 2, now);
    st = run_stmt(s, S_CANCEL, rec, 0, &got);
    rec->now = now;
    /* not queued or running: finished (left as it is), unknown, or a damaged row */
    if (st == LJGAP_JOBSTORE_OK && !got) st = get_locked(s, id, rec);
    pthread_mutex_unlock(&s->lock);
    return st;
}

static int op_counts(ljgap__jobstore *base, unsigned *queued, unsigned *running)
{
    sqlite_store *s = (sqlite_store *)base;
    sqlite3_stmt *q;
    int rc, st = LJGAP_JOBSTORE_OK;
    pthread_mutex_lock(&s->lock);
    q = s->stmt[S_COUNTS];
    while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
        *queued = (unsigned)sqlite3_column_int64(q, 0);
        *running = (unsigned)sqlite3_column_int64(q, 1);
    }
    if (rc != SQLITE_DONE) st = db_error(s, "cannot count jobs");
    sqlite3_reset(q);
    pthread_mutex_unlock(&s->lock);
    return st;
}

static int op_evict(ljgap__jobstore *base, unsigned keep_done, double keep_seconds,
                    unsigned *evicted)
{
    sqlite_store *s = (sqlite_store *)base;
    int st;
    pthread_mutex_lock(&s->lock);
    durability(s, 0);
    sqlite3_bind_double(s->stmt[S_EVICT], 1, ljgap__jobstore_wallclock() - keep_seconds);
    sqlite3_bind_int64(s->stmt[S_EVICT], 2, keep_done);
    st = run_stmt(s, S_EVICT, NULL, 0, NULL);
    if (st == LJGAP_JOBSTORE_OK) *evicted = (unsigned)sqlite3_changes(s->db);
    pthread_mutex_unlock(&s->lock);
    return st;
}

static void op_close(ljgap__jobstore *base)
{
    sqlite_store *s = (sqlite_store *)base;
    for (int i = 0; i < S_N; i++)
        sqlite3_finalize(s->stmt[i]);
    if (s->db) sqlite3_close(s->db);        /* the last connection: checkpoints and drops the WAL */
    if (s->lock_fd >= 0) close(s->lock_fd); /* releases the flock */
    pthread_mutex_destroy(&s->lock);
    free(s->path);
    free(s);
}

static const ljgap__jobstore_ops sqlite_ops = {
    .name = "sqlite",
    .create = op_create,
    .claim = op_claim,
    .renew = op_renew,
    .finish = op_finish,
    .release = op_release,
    .get = op_get,
    .cancel = op_cancel,
    .counts = op_counts,
    .evict = op_evict,
    .close = op_close,
};

/* ---- opening ---- */

/* mkdir -p dir (new directories 0700: jobs hold users' requests). 0, or -1 with errno and
 * the path that failed in failed (size cap). */
static int make_dirs(const char *dir, char *failed, size_t cap)
{
    char *p = strdup(dir);
    int rc = 0;
    if (!p) return -1;
    for (char *c = p + 1;; c++) {
        if (*c == '/' || *c == '\0') {
            char keep = *c;
            *c = '\0';
            if (mkdir(p, 0700) != 0 && errno != EEXIST) {
                snprintf(failed, cap, "%s", p);
                rc = -1;
                break;
            }
            *c = keep;
            if (!keep) break;
        }
    }
    free(p);
    return rc;
}

/* Takes DIR/lock: creates it, flocks it (never waiting) and writes our pid into it. */
static int take_lock(sqlite_store *s, const char *dir, char *err, size_t errlen)
{
    char path[PATH_MAX], pid[32];
    ssize_t n;
    snprintf(path, sizeof path, "%s/lock", dir);
    s->lock_fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0600);
    if (s->lock_fd < 0) {
        snprintf(err, errlen, "state directory %s is not writable: cannot create %s: %s", dir, path,
                 strerror(errno));
        return -1;
    }
    if (flock(s->lock_fd, LOCK_EX | LOCK_NB) != 0) {
        int e = errno;
        n = pread(s->lock_fd, pid, sizeof pid - 1, 0);
        pid[n > 0 ? n : 0] = '\0';
        pid[strcspn(pid, "\n")] = '\0';
        if (e == EWOULDBLOCK)
            snprintf(err, errlen,
                     "state directory %s is in use by another process (pid %s, see %s); give "
                     "each ljgapd its own --state-dir",
                     dir, pid[0] ? pid : "unknown", path);
        else
            snprintf(err, errlen, "cannot lock %s: %s", path, strerror(e));
        return -1;
    }
    n = snprintf(pid, sizeof pid, "%ld\n", (long)getpid());
    if (ftruncate(s->lock_fd, 0) != 0 || pwrite(s->lock_fd, pid, (size_t)n, 0) != n) {
        snprintf(err, errlen, "state directory %s is not writable: cannot write %s: %s", dir, path,
                 strerror(errno));
        return -1;
    }
    return 0;
}

/* One integer from a query (the first column of its first row); 0 or -1. */
static int query_int(sqlite3 *db, const char *q, long long *out)
{
    sqlite3_stmt *stmt = NULL;
    int rc = sqlite3_prepare_v2(db, q, -1, &stmt, NULL);
    if (rc == SQLITE_OK && (rc = sqlite3_step(stmt)) == SQLITE_ROW) {
        *out = sqlite3_column_int64(stmt, 0);
        rc = SQLITE_OK;
    }
    sqlite3_finalize(stmt);
    return rc == SQLITE_OK ? 0 : -1;
}

/* One text from a query, copied into out (size cap); 0 or -1. */
static int query_text(sqlite3 *db, const char *q, char *out, size_t cap)
{
    sqlite3_stmt *stmt = NULL;
    int rc = sqlite3_prepare_v2(db, q, -1, &stmt, NULL);
    if (rc == SQLITE_OK && (rc = sqlite3_step(stmt)) == SQLITE_ROW) {
        const unsigned char *t = sqlite3_column_text(stmt, 0);
        snprintf(out, cap, "%s", t ? (const char *)t : "");
        for (char *c = out; *c; c++) /* quick_check's report has lines: one line for a message */
            if (*c == '\n') *c = ' ';
        rc = SQLITE_OK;
    }
    sqlite3_finalize(stmt);
    return rc == SQLITE_OK ? 0 : -1;
}

/* The schema: this file's, at its latest version (migrating), or an error. */
static int check_schema(sqlite_store *s, char *err, size_t errlen)
{
    long long app = 0, tables = 0, version = 0;
    char *msg = NULL;
    if (query_int(s->db, "PRAGMA application_id", &app) != 0 ||
        query_int(s->db, "SELECT count(*) FROM sqlite_schema", &tables) != 0)
        goto db_fail;
    if (app != APP_ID && (app != 0 || tables > 0)) {
        snprintf(err, errlen,
                 "%s is not an ljgapd job store (another program's database: application_id "
                 "%lld, %lld tables); move it away or choose another --state-dir",
                 s->path, app, tables);
        return -1;
    }
    if (app == APP_ID &&
        query_int(s->db, "SELECT max(version) FROM schema_version", &version) != 0) {
        snprintf(err, errlen, "%s is damaged: no schema version (%s)", s->path,
                 sqlite3_errmsg(s->db));
        return -1;
    }
    if (version > SCHEMA_VERSION || version < 0) {
        snprintf(err, errlen,
                 "%s has schema version %lld, and this ljgapd knows versions up to %d: it was "
                 "written by a newer ljgapd; run that one, or choose another --state-dir",
                 s->path, version, SCHEMA_VERSION);
        return -1;
    }
    if (version == SCHEMA_VERSION) return 0;
    if (sqlite3_exec(s->db, "BEGIN IMMEDIATE", NULL, NULL, &msg) != SQLITE_OK) goto exec_fail;
    for (long long v = version; v < SCHEMA_VERSION; v++) {
        char set[80];
        snprintf(set, sizeof set, "UPDATE schema_version SET version = %lld", v + 1);
        if (sqlite3_exec(s->db, migrations[v], NULL, NULL, &msg) != SQLITE_OK ||
            sqlite3_exec(s->db, set, NULL, NULL, &msg) != SQLITE_OK) {
            sqlite3_exec(s->db, "ROLLBACK", NULL, NULL, NULL);
            goto exec_fail;
        }
    }
    if (sqlite3_exec(s->db, "COMMIT", NULL, NULL, &msg) == SQLITE_OK) return 0;
    sqlite3_exec(s->db, "ROLLBACK", NULL, NULL, NULL);
exec_fail:
    snprintf(err, errlen, "%s: cannot create or migrate the schema to version %d: %s", s->path,
             SCHEMA_VERSION, msg ? msg : sqlite3_errmsg(s->db));
    sqlite3_free(msg);
    return -1;
db_fail:
    snprintf(err, errlen, "%s cannot be read: %s", s->path, sqlite3_errmsg(s->db));
    return -1;
}

/* The jobs that were running when the last owner stopped run again (or end cancelled, when
 * their cancel had been asked): one process owns the directory, so nobody runs them now. */
static int requeue(sqlite_store *s, char *err, size_t errlen)
{
    sqlite3_stmt *q = NULL;
    int rc = sqlite3_prepare_v2(
        s->db,
        "UPDATE jobs SET state = CASE WHEN cancel THEN 'cancelled' ELSE 'queued' END, "
        "finished = CASE WHEN cancel THEN ?1 ELSE NULL END, "
        "started = CASE WHEN cancel THEN started ELSE NULL END, "
        "progress = CASE WHEN cancel THEN progress ELSE 0 END, "
        "lost = lost + 1, lease_until = NULL, owner = NULL WHERE state = 'running'",
        -1, &q, NULL);
    if (rc == SQLITE_OK) {
        sqlite3_bind_double(q, 1, ljgap__jobstore_wallclock());
        rc = sqlite3_step(q);
    }
    sqlite3_finalize(q);
    if (rc == SQLITE_OK || rc == SQLITE_DONE) return 0;
    snprintf(err, errlen, "%s cannot be written: %s", s->path, sqlite3_errmsg(s->db));
    return -1;
}

int ljgap__jobstore_open_sqlite(const char *dir, ljgap__jobstore **out, char *err, size_t errlen)
{
    sqlite_store *s = NULL;
    struct stat sb;
    char failed[PATH_MAX], text[160];
    int rc;
    *out = NULL;
    if (!dir || !dir[0]) {
        snprintf(err, errlen, "no state directory given");
        return LJGAP_JOBSTORE_INVALID;
    }
    if (strlen(dir) > PATH_MAX - 32) {
        snprintf(err, errlen, "state directory path too long: %.80s...", dir);
        return LJGAP_JOBSTORE_INVALID;
    }
    if (!sqlite3_threadsafe()) {
        snprintf(err, errlen, "this SQLite library was built without thread support");
        return LJGAP_JOBSTORE_ERROR;
    }
    if (!(s = calloc(1, sizeof *s)) || !(s->path = malloc(strlen(dir) + 16))) {
        free(s);
        snprintf(err, errlen, "out of memory");
        return LJGAP_JOBSTORE_NOMEM;
    }
    s->base.ops = &sqlite_ops;
    s->lock_fd = -1;
    pthread_mutex_init(&s->lock, NULL);
    s->base.where = s->path;
    sprintf(s->path, "%s/jobs.sqlite", dir);

    if (make_dirs(dir, failed, sizeof failed) != 0) {
        snprintf(err, errlen, "cannot create state directory %s: %s (at %s)", dir, strerror(errno),
                 failed);
        goto fail;
    }
    if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode)) {
        snprintf(err, errlen, "state directory %s is not a directory", dir);
        goto fail;
    }
    if (take_lock(s, dir, err, errlen) != 0) goto fail;

    rc = sqlite3_open_v2(s->path, &s->db,
                         SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, NULL);
    if (rc != SQLITE_OK) {
        snprintf(err, errlen, "cannot open %s: %s", s->path,
                 s->db ? sqlite3_errmsg(s->db) : sqlite3_errstr(rc));
        goto fail;
    }
    if (sqlite3_db_readonly(s->db, "main") == 1) {
        snprintf(err, errlen, "%s is read-only (check its permissions)", s->path);
        goto fail;
    }
    sqlite3_busy_timeout(s->db, BUSY_MS);
    /* WAL first: the first statement that reads the file says whether it is a database */
    if (query_text(s->db, "PRAGMA journal_mode = WAL", text, sizeof text) != 0) {
        snprintf(err, errlen, "%s is not a usable database: %s", s->path, sqlite3_errmsg(s->db));
        goto fail;
    }
    if (strcmp(text, "wal") != 0) {
        snprintf(err, errlen, "%s cannot use WAL mode (journal mode stays %s)", s->path, text);
        goto fail;
    }
    if (sqlite3_exec(s->db,
                     "PRAGMA synchronous = FULL; PRAGMA trusted_schema = OFF; "
                     "PRAGMA cell_size_check = ON",
                     NULL, NULL, NULL) != SQLITE_OK ||
        query_text(s->db, "PRAGMA quick_check", text, sizeof text) != 0) {
        snprintf(err, errlen, "%s cannot be checked: %s", s->path, sqlite3_errmsg(s->db));
        goto fail;
    }
    if (strcmp(text, "ok") != 0) {
        snprintf(err, errlen, "%s is corrupt (quick_check: %s); move it away to start afresh",
                 s->path, text);
        goto fail;
    }
    if (check_schema(s, err, errlen) != 0 || requeue(s, err, errlen) != 0) goto fail;
    for (int i = 0; i < S_N; i++)
        if (sqlite3_prepare_v3(s->db, sql[i], -1, SQLITE_PREPARE_PERSISTENT, &s->stmt[i], NULL) !=
            SQLITE_OK) {
            snprintf(err, errlen, "%s: cannot prepare a statement: %s", s->path,
                     sqlite3_errmsg(s->db));
            goto fail;
        }
    *out = &s->base;
    return LJGAP_JOBSTORE_OK;
fail:
    op_close(&s->base);
    return LJGAP_JOBSTORE_ERROR;
}
