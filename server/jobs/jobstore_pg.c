/* jobstore_pg.c -- the job store in PostgreSQL: one queue shared by every ljgapd pointed at it.
 *
 * Several daemons, on several machines, open the same database (ljgapd --jobs-db URL) and so
 * share one queue: any of them answers for any job id, and their workers take jobs from it.
 * The semantics are the SQLite backend's (jobstore.h); what sharing adds:
 *
 *   - claim takes the oldest job that is queued, or running with a lapsed lease (its daemon
 *     died), with SELECT ... FOR UPDATE SKIP LOCKED: two workers never take the same job, and
 *     none waits for another's row lock;
 *   - the clock is the database's now(), one clock for every daemon, so leases and times do not
 *     depend on the machines' clocks agreeing;
 *   - create checks the queue cap and inserts under a transaction-scoped advisory lock
 *     (ljgapd.create_job), so daemons submitting at once never overfill the queue;
 *   - opening never requeues running jobs (another daemon may be running them): a dead daemon's
 *     jobs come back when their leases lapse;
 *   - the schema lives in its own PostgreSQL schema `ljgapd` (tables schema_version and jobs),
 *     created or migrated at open under an advisory lock, so daemons starting together migrate
 *     once and a shared database's other tables are left alone.
 *
 * Connections: a small pool (max_conns, opened as threads need them, kept while they work).
 * Every operation takes a connection, runs one statement (or one function call) in autocommit
 * and gives the connection back; libpq is used asynchronously with poll(), so an operation
 * never waits more than OP_S seconds for anything (a free connection, connecting, the answer),
 * whatever the network does. An idle connection is checked before use (readable while idle
 * means the server closed it, as a restart does) and replaced.
 *
 * Failures: a connection that breaks is dropped; reads, renewals, cancels, evictions and claims
 * are tried once more on a fresh connection (their repetition is harmless), creates, finishes and
 * releases are not (the first may have committed). When connecting fails or the database stops
 * answering, the store is down: for RETRY_S every operation fails at once with the reason, then
 * one operation tries to connect again (the job workers' polling makes that happen by itself).
 * So the HTTP job routes answer 503 quickly while the database is away, and work again when it
 * is back.
 *
 * Reading back: rows come in libpq's text format and are parsed by ljgap__jobstore_pg_row, which
 * trusts nothing (the fuzzer feeds it); jobstatus.h checks the record before a client sees it.
 *
 * Secrets: the URL may hold a password. Messages name the database as
 * postgresql://user@host:port/dbname and every form of the password is scrubbed from what
 * libpq says.
 */
#include "clock.h"
#include "jobstore.h"
#include "jobstore_pg_conn.h"
#include "ljgap.h"

#include <libpq-fe.h>

#include <errno.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define CONNS_DEFAULT 4
#define LOCK_KEY "1279936324" /* advisory lock class: 0x4c4a4744, "LJGD" (with 0: migrations) */

/* migrations[v] brings the schema from version v to v + 1 (the schema ljgapd and its table
 * schema_version exist already). */
static const char *const migrations[] = {
    /* 0 -> 1: the jobs table, and the two functions that need a lock */
    "CREATE TABLE ljgapd.jobs ("
    "  seq bigserial PRIMARY KEY," /* submission order: the queue is FIFO */
    "  id text NOT NULL UNIQUE CHECK (id ~ '^[0-9a-f]{32}$'),"
    "  kind text NOT NULL CHECK (kind ~ '^[a-z0-9_]{1,31}$'),"
    "  request bytea NOT NULL," /* the body as submitted */
    "  state text NOT NULL CHECK (state IN ('queued','running','done','failed','cancelled')),"
    "  progress float8 NOT NULL DEFAULT 0 CHECK (progress BETWEEN 0 AND 1),"
    "  created timestamptz NOT NULL DEFAULT now(),"
    "  started timestamptz,"                   /* the current (or last) run's start */
    "  finished timestamptz,"                  /* when it reached done, failed or cancelled */
    "  cancel boolean NOT NULL DEFAULT false," /* a cancel was requested while it ran */
    "  run bigint NOT NULL DEFAULT 0,"         /* claims so far: the lease token */
    "  lost bigint NOT NULL DEFAULT 0,"        /* runs that ended without finishing */
    "  owner text,"                            /* who runs it (host:pid), for the curious */
    "  lease_until timestamptz,"               /* a running job's lease */
    "  answer text"                            /* result (done) or problem (failed, cancelled) */
    ");"
    "CREATE INDEX jobs_live ON ljgapd.jobs (seq) WHERE state IN ('queued', 'running');"
    "CREATE INDEX jobs_finished ON ljgapd.jobs (finished) WHERE state NOT IN ('queued', "
    "'running');"
    /* the queue cap and the insert under one lock: concurrent creates never overfill it (in
     * read committed, the count after the lock sees every insert committed before it) */
    "CREATE FUNCTION ljgapd.create_job(p_id text, p_kind text, p_request bytea, p_cap bigint) "
    "RETURNS boolean LANGUAGE plpgsql AS $$ BEGIN "
    "  PERFORM pg_advisory_xact_lock(" LOCK_KEY ", 1);"
    "  IF p_cap > 0 AND (SELECT count(*) FROM ljgapd.jobs WHERE state = 'queued') >= p_cap THEN"
    "    RETURN false;"
    "  END IF;"
    "  INSERT INTO ljgapd.jobs (id, kind, request, state) VALUES (p_id, p_kind, p_request, "
    "  'queued');"
    "  RETURN true;"
    "END $$;"
    /* one eviction at a time across daemons; the others skip theirs */
    "CREATE FUNCTION ljgapd.evict(p_keep_seconds float8, p_keep bigint) "
    "RETURNS bigint LANGUAGE plpgsql AS $$ DECLARE n bigint; BEGIN "
    "  IF NOT pg_try_advisory_xact_lock(" LOCK_KEY ", 2) THEN RETURN 0; END IF;"
    "  DELETE FROM ljgapd.jobs WHERE state NOT IN ('queued', 'running') AND "
    "    (coalesce(finished, 'epoch') < now() - p_keep_seconds * interval '1 second' OR "
    "     seq NOT IN (SELECT seq FROM ljgapd.jobs WHERE state NOT IN ('queued', 'running') "
    "                 ORDER BY finished DESC NULLS LAST, seq DESC LIMIT p_keep));"
    "  GET DIAGNOSTICS n = ROW_COUNT;"
    "  RETURN n;"
    "END $$;",
};
#define SCHEMA_VERSION ((int)(sizeof migrations / sizeof migrations[0]))

/* The columns of a record (table alias j), in LJGAP_PG_* order. */
#define RECORD_COLS                                                                                \
    "j.id, j.kind, j.state, j.progress, extract(epoch FROM j.created)::float8, "                   \
    "extract(epoch FROM j.started)::float8, extract(epoch FROM j.finished)::float8, j.cancel, "    \
    "j.run, j.lost, j.answer, extract(epoch FROM now())::float8"

static const char sql_create[] = "SELECT ljgapd.create_job($1, $2, $3::bytea, $4::int8)";
static const char sql_claim[] =
    "UPDATE ljgapd.jobs j SET state = 'running', run = j.run + 1, "
    "lost = j.lost + CASE WHEN j.state = 'running' THEN 1 ELSE 0 END, started = now(), "
    "progress = 0, lease_until = now() + $2::float8 * interval '1 second', owner = $1 "
    "FROM (SELECT seq FROM ljgapd.jobs WHERE state = 'queued' OR (state = 'running' AND "
    "lease_until < now()) ORDER BY seq LIMIT 1 FOR UPDATE SKIP LOCKED) c WHERE j.seq = c.seq "
    "RETURNING " RECORD_COLS ", j.request";
static const char sql_renew[] =
    "UPDATE ljgapd.jobs SET progress = greatest(progress, $3::float8), "
    "lease_until = now() + $4::float8 * interval '1 second' "
    "WHERE id = $1 AND run = $2::int8 AND state = 'running' RETURNING cancel";
static const char sql_finish[] =
    "UPDATE ljgapd.jobs SET state = $3::text, answer = $4, finished = now(), lease_until = NULL, "
    "owner = NULL, progress = CASE WHEN $3::text = 'done' THEN 1 ELSE progress END "
    "WHERE id = $1 AND run = $2::int8 AND state = 'running'";
static const char sql_release[] =
    "UPDATE ljgapd.jobs SET state = 'queued', started = NULL, progress = 0, lease_until = NULL, "
    "owner = NULL WHERE id = $1 AND run = $2::int8 AND state = 'running'";
static const char sql_get[] = "SELECT " RECORD_COLS " FROM ljgapd.jobs j WHERE j.id = $1";
static const char sql_cancel[] =
    "UPDATE ljgapd.jobs j SET state = CASE j.state WHEN 'queued' THEN 'cancelled' ELSE j.state "
    "END, finished = CASE j.state WHEN 'queued' THEN now() ELSE j.finished END, "
    "cancel = CASE j.state WHEN 'running' THEN true ELSE j.cancel END "
    "WHERE j.id = $1 AND j.state IN ('queued', 'running') RETURNING " RECORD_COLS;
static const char sql_counts[] =
    "SELECT count(*) FILTER (WHERE state = 'queued'), count(*) FILTER (WHERE state = 'running') "
    "FROM ljgapd.jobs WHERE state IN ('queued', 'running')";
static const char sql_evict[] = "SELECT ljgapd.evict($1::float8, $2::int8)";

/* ---- reading rows ---- */

/* Copies the text val (len bytes) into dst (cap bytes) when it fits without a NUL; else "". */
static void text_short(const char *val, int len, char *dst, size_t cap)
{
    dst[0] = '\0';
    if (val && len >= 0 && (size_t)len < cap && !memchr(val, '\0', (size_t)len)) {
        memcpy(dst, val, (size_t)len);
        dst[len] = '\0';
    }
}

/* A float8's text ("NaN" and "Infinity" included); 0 for NULL or anything else. */
static double number(const char *val, int len)
{
    char buf[64], *end;
    double v;
    if (!val || len <= 0 || (size_t)len >= sizeof buf) return 0;
    memcpy(buf, val, (size_t)len);
    buf[len] = '\0';
    v = strtod(buf, &end);
    return end != buf && *end == '\0' ? v : 0;
}

static long integer(const char *val, int len)
{
    char buf[32], *end;
    long v;
    if (!val || len <= 0 || (size_t)len >= sizeof buf) return 0;
    memcpy(buf, val, (size_t)len);
    buf[len] = '\0';
    errno = 0;
    v = strtol(buf, &end, 10);
    return end != buf && *end == '\0' && errno == 0 ? v : 0;
}

int ljgap__jobstore_pg_row(ljgap__job_record *rec, const char *const *val, const int *len, int ncols)
{
    char state[16];
    text_short(val[LJGAP_PG_ID], len[LJGAP_PG_ID], rec->id, sizeof rec->id);
    text_short(val[LJGAP_PG_KIND], len[LJGAP_PG_KIND], rec->kind, sizeof rec->kind);
    text_short(val[LJGAP_PG_STATE], len[LJGAP_PG_STATE], state, sizeof state);
    rec->state = ljgap__job_state_parse(state);
    rec->progress = number(val[LJGAP_PG_PROGRESS], len[LJGAP_PG_PROGRESS]);
    rec->created = number(val[LJGAP_PG_CREATED], len[LJGAP_PG_CREATED]);
    rec->started = number(val[LJGAP_PG_STARTED], len[LJGAP_PG_STARTED]);
    rec->finished = number(val[LJGAP_PG_FINISHED], len[LJGAP_PG_FINISHED]);
    rec->now = number(val[LJGAP_PG_NOW], len[LJGAP_PG_NOW]);
    rec->cancel =
        val[LJGAP_PG_CANCEL] && len[LJGAP_PG_CANCEL] == 1 && val[LJGAP_PG_CANCEL][0] == 't';
    rec->run = integer(val[LJGAP_PG_RUN], len[LJGAP_PG_RUN]);
    rec->lost = integer(val[LJGAP_PG_LOST], len[LJGAP_PG_LOST]);
    if (val[LJGAP_PG_ANSWER] && len[LJGAP_PG_ANSWER] >= 0) {
        size_t n = (size_t)len[LJGAP_PG_ANSWER];
        if (!(rec->answer = malloc(n + 1))) goto nomem;
        memcpy(rec->answer, val[LJGAP_PG_ANSWER], n);
        rec->answer[n] = '\0';
        rec->answer_len = n;
    }
    if (ncols > LJGAP_PG_REQUEST) { /* "\x" and pairs of hex digits; anything else is empty */
        const char *h = val[LJGAP_PG_REQUEST];
        int n = len[LJGAP_PG_REQUEST];
        int ok = h && n >= 2 && h[0] == '\\' && h[1] == 'x' && n % 2 == 0;
        size_t bytes = ok ? (size_t)(n - 2) / 2 : 0;
        if (!(rec->request = malloc(bytes + 1))) goto nomem;
        for (size_t i = 0; i < bytes && ok; i++) {
            int hi = pgs_hexval(h[2 + 2 * i]), lo = pgs_hexval(h[3 + 2 * i]);
            ok = hi >= 0 && lo >= 0;
            rec->request[i] = (char)(hi * 16 + lo);
        }
        rec->request_len = ok ? bytes : 0;
        rec->request[rec->request_len] = '\0';
    }
    return LJGAP_JOBSTORE_OK;
nomem:
    ljgap__job_record_clear(rec);
    ljgap__jobstore_set_errmsg("out of memory reading a job");
    return LJGAP_JOBSTORE_NOMEM;
}

/* Row 0 of res into rec (ncols: LJGAP_PG_REQUEST, or LJGAP_PG_COLS with the request). */
static int read_row(PGresult *res, ljgap__job_record *rec, int ncols)
{
    const char *val[LJGAP_PG_COLS] = {0};
    int len[LJGAP_PG_COLS] = {0};
    if (PQnfields(res) != ncols) {
        ljgap__jobstore_set_errmsg("the server answered %d columns, not %d", PQnfields(res), ncols);
        return LJGAP_JOBSTORE_ERROR;
    }
    for (int i = 0; i < ncols; i++)
        if (!PQgetisnull(res, 0, i)) {
            val[i] = PQgetvalue(res, 0, i);
            len[i] = PQgetlength(res, 0, i);
        }
    return ljgap__jobstore_pg_row(rec, val, len, ncols);
}

/* ---- the operations ---- */

static int op_create(ljgap__jobstore *base, const char *id, const char *kind, const char *request,
                     size_t len, unsigned max_queued)
{
    pg_store *s = (pg_store *)base;
    char cap[16];
    const char *v[4] = {id, kind, NULL, cap};
    PGresult *res;
    int st;
    if (len > (size_t)1 << 30) return LJGAP_JOBSTORE_INVALID;
    snprintf(cap, sizeof cap, "%u", max_queued);
    res = pgs_run(s, "cannot add a job", sql_create, 4, v, request, len, PGRES_TUPLES_OK, 0, &st);
    if (!res) return st;
    st = PQntuples(res) == 1 && PQgetvalue(res, 0, 0)[0] == 't' ? LJGAP_JOBSTORE_OK
                                                                : LJGAP_JOBSTORE_FULL;
    PQclear(res);
    return st;
}

static int op_claim(ljgap__jobstore *base, const char *owner, double lease_s, ljgap__job_record *rec)
{
    pg_store *s = (pg_store *)base;
    char lease[32];
    const char *v[2] = {owner, lease};
    PGresult *res;
    int st;
    snprintf(lease, sizeof lease, "%.17g", lease_s);
    res = pgs_run(s, "cannot claim a job", sql_claim, 2, v, NULL, 0, PGRES_TUPLES_OK, 1, &st);
    if (!res) return st;
    st = PQntuples(res) ? read_row(res, rec, LJGAP_PG_COLS) : LJGAP_JOBSTORE_EMPTY;
    PQclear(res);
    return st;
}

static int op_renew(ljgap__jobstore *base, const char *id, long run_, double progress,
                    double lease_s, int *cancel)
{
    pg_store *s = (pg_store *)base;
    char r[24], p[32], lease[32];
    const char *v[4] = {id, r, p, lease};
    PGresult *res;
    int st;
    snprintf(r, sizeof r, "%ld", run_);
    snprintf(p, sizeof p, "%.17g", progress);
    snprintf(lease, sizeof lease, "%.17g", lease_s);
    res =
        pgs_run(s, "cannot renew a job's lease", sql_renew, 4, v, NULL, 0, PGRES_TUPLES_OK, 1, &st);
    if (!res) return st;
    st = PQntuples(res) ? LJGAP_JOBSTORE_OK : LJGAP_JOBSTORE_LOST;
    if (st == LJGAP_JOBSTORE_OK) *cancel = PQgetvalue(res, 0, 0)[0] == 't';
    PQclear(res);
    return st;
}

static int op_finish(ljgap__jobstore *base, const char *id, long run_, ljgap__job_state state,
                     const char *answer, size_t answer_len)
{
    pg_store *s = (pg_store *)base;
    char r[24];
    const char *v[4] = {id, r, ljgap__job_state_name(state), answer};
    PGresult *res;
    int st;
    (void)answer_len; /* answer is NUL-terminated text */
    snprintf(r, sizeof r, "%ld", run_);
    res = pgs_run(s, "cannot write the end of a job", sql_finish, 4, v, NULL, 0, PGRES_COMMAND_OK,
                  0, &st);
    if (!res) return st;
    st = pgs_changed(res) == 1 ? LJGAP_JOBSTORE_OK : LJGAP_JOBSTORE_LOST;
    PQclear(res);
    return st;
}

static int op_release(ljgap__jobstore *base, const char *id, long run_)
{
    pg_store *s = (pg_store *)base;
    char r[24];
    const char *v[2] = {id, r};
    PGresult *res;
    int st;
    snprintf(r, sizeof r, "%ld", run_);
    res = pgs_run(s, "cannot put back a job", sql_release, 2, v, NULL, 0, PGRES_COMMAND_OK, 0, &st);
    if (!res) return st;
    st = pgs_changed(res) == 1 ? LJGAP_JOBSTORE_OK : LJGAP_JOBSTORE_LOST;
    PQclear(res);
    return st;
}

/* Runs sql with the id as its parameter and reads the one record it returns into rec;
 * LJGAP_JOBSTORE_UNKNOWN when it returns none. */
static int record_by_id(pg_store *s, const char *what, const char *sql, const char *id,
                        ljgap__job_record *rec)
{
    const char *v[1] = {id};
    PGresult *res;
    int st;
    res = pgs_run(s, what, sql, 1, v, NULL, 0, PGRES_TUPLES_OK, 1, &st);
    if (!res) return st;
    st = PQntuples(res) ? read_row(res, rec, LJGAP_PG_REQUEST) : LJGAP_JOBSTORE_UNKNOWN;
    PQclear(res);
    return st;
}

static int op_get(ljgap__jobstore *base, const char *id, ljgap__job_record *rec)
{
    return record_by_id((pg_store *)base, "cannot read a job", sql_get, id, rec);
}

static int op_cancel(ljgap__jobstore *base, const char *id, ljgap__job_record *rec)
{
    int st = record_by_id((pg_store *)base, "cannot cancel a job", sql_cancel, id, rec);
    /* not queued or running: finished (left as it is), unknown, or a damaged row */
    return st == LJGAP_JOBSTORE_UNKNOWN ? op_get(base, id, rec) : st;
}

static int op_counts(ljgap__jobstore *base, unsigned *queued, unsigned *running)
{
    pg_store *s = (pg_store *)base;
    PGresult *res;
    int st;
    res = pgs_run(s, "cannot count jobs", sql_counts, 0, NULL, NULL, 0, PGRES_TUPLES_OK, 1, &st);
    if (!res) return st;
    if (PQntuples(res) == 1 && PQnfields(res) == 2) {
        *queued = (unsigned)strtoul(PQgetvalue(res, 0, 0), NULL, 10);
        *running = (unsigned)strtoul(PQgetvalue(res, 0, 1), NULL, 10);
    }
    PQclear(res);
    return LJGAP_JOBSTORE_OK;
}

static int op_evict(ljgap__jobstore *base, unsigned keep_done, double keep_seconds,
                    unsigned *evicted)
{
    pg_store *s = (pg_store *)base;
    char secs[32], keep[16];
    const char *v[2] = {secs, keep};
    PGresult *res;
    int st;
    snprintf(secs, sizeof secs, "%.17g", keep_seconds);
    snprintf(keep, sizeof keep, "%u", keep_done);
    res =
        pgs_run(s, "cannot evict finished jobs", sql_evict, 2, v, NULL, 0, PGRES_TUPLES_OK, 1, &st);
    if (!res) return st;
    if (PQntuples(res) == 1) *evicted = (unsigned)strtoul(PQgetvalue(res, 0, 0), NULL, 10);
    PQclear(res);
    return LJGAP_JOBSTORE_OK;
}

static void op_close(ljgap__jobstore *base)
{
    pg_store *s = (pg_store *)base;
    for (unsigned i = 0; i < s->n_idle; i++)
        PQfinish(s->idle[i]);
    for (int i = 0; i < SECRETS; i++)
        free(s->secret[i]);
    free(s->idle);
    free(s->url);
    free(s->safe);
    pthread_cond_destroy(&s->freed);
    pthread_mutex_destroy(&s->lock);
    free(s);
}

static const ljgap__jobstore_ops pg_ops = {
    .name = "postgresql",
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

/* Runs sql on c (in the open's transaction); the result when it is want, else NULL with the
 * reason in err. */
static PGresult *open_exec(pg_store *s, PGconn *c, const char *sql, ExecStatusType want,
                           double deadline, char *err, size_t errlen)
{
    exec_fail fail;
    PGresult *res = pgs_exec(c, sql, -1, NULL, NULL, NULL, deadline, &fail);
    char why[MSG_MAX];
    if (res && PQresultStatus(res) == want) return res;
    pgs_clean_msg(s,
                  res                 ? PQresultErrorMessage(res)
                  : fail == X_TIMEOUT ? "no answer in time"
                                      : PQerrorMessage(c),
                  why, sizeof why);
    snprintf(err, errlen, "%s: cannot create or check the schema: %s", s->safe, why);
    PQclear(res);
    return NULL;
}

/* The schema: ours, at its latest version (migrating under the lock), or an error in err. */
static int check_schema(pg_store *s, PGconn *c, char *err, size_t errlen)
{
    double deadline = ljgap__clock_now() + 4 * OP_S;
    PGresult *res = NULL;
    long version = 0, tables = 0;
    int has_schema, has_version, ok = -1;
    char sql[96];

    if (!(res = open_exec(s, c,
                          "BEGIN; SELECT pg_advisory_xact_lock(" LOCK_KEY ", 0); "
                          "SELECT to_regnamespace('ljgapd') IS NOT NULL, "
                          "to_regclass('ljgapd.schema_version') IS NOT NULL, "
                          "(SELECT count(*) FROM pg_class c JOIN pg_namespace n "
                          "ON n.oid = c.relnamespace WHERE n.nspname = 'ljgapd')",
                          PGRES_TUPLES_OK, deadline, err, errlen)))
        goto end;
    has_schema = PQgetvalue(res, 0, 0)[0] == 't';
    has_version = PQgetvalue(res, 0, 1)[0] == 't';
    tables = strtol(PQgetvalue(res, 0, 2), NULL, 10);
    PQclear(res);
    res = NULL;
    if (has_schema && !has_version && tables > 0) {
        snprintf(err, errlen,
                 "%s: the schema ljgapd holds %ld tables or indexes but no schema_version: it is "
                 "not an ljgapd job store (another program's?); drop it or use another database",
                 s->safe, tables);
        goto end;
    }
    if (has_version) {
        if (!(res = open_exec(s, c, "SELECT max(version) FROM ljgapd.schema_version",
                              PGRES_TUPLES_OK, deadline, err, errlen)))
            goto end;
        if (PQgetisnull(res, 0, 0)) {
            snprintf(err, errlen, "%s: the job store is damaged: ljgapd.schema_version is empty",
                     s->safe);
            goto end;
        }
        version = strtol(PQgetvalue(res, 0, 0), NULL, 10);
        PQclear(res);
        res = NULL;
    }
    if (version > SCHEMA_VERSION || version < 0) {
        snprintf(err, errlen,
                 "%s: the job store has schema version %ld, and this ljgapd knows versions up "
                 "to %d: it was written by a newer ljgapd; run that one, or use another database",
                 s->safe, version, SCHEMA_VERSION);
        goto end;
    }
    if (!has_version &&
        !(res = open_exec(s, c,
                          "CREATE SCHEMA IF NOT EXISTS ljgapd; "
                          "CREATE TABLE ljgapd.schema_version (version integer NOT NULL); "
                          "INSERT INTO ljgapd.schema_version VALUES (0)",
                          PGRES_COMMAND_OK, deadline, err, errlen)))
        goto end;
    for (long v = version; v < SCHEMA_VERSION; v++) {
        PQclear(res);
        snprintf(sql, sizeof sql, "UPDATE ljgapd.schema_version SET version = %ld", v + 1);
        if (!(res = open_exec(s, c, migrations[v], PGRES_COMMAND_OK, deadline, err, errlen)))
            goto end;
        PQclear(res);
        if (!(res = open_exec(s, c, sql, PGRES_COMMAND_OK, deadline, err, errlen))) goto end;
    }
    PQclear(res);
    if ((res = open_exec(s, c, "COMMIT", PGRES_COMMAND_OK, deadline, err, errlen))) ok = 0;
end:
    PQclear(res);
    if (ok != 0 && PQstatus(c) == CONNECTION_OK) { /* leave the connection clean (or drop it) */
        exec_fail fail;
        PQclear(pgs_exec(c, "ROLLBACK", -1, NULL, NULL, NULL, ljgap__clock_now() + OP_S, &fail));
    }
    return ok;
}

int ljgap__jobstore_open_pg(const char *url, unsigned max_conns, ljgap__jobstore **out, char *err,
                           size_t errlen)
{
    pg_store *s = NULL;
    PQconninfoOption *info = NULL;
    PGconn *c = NULL;
    char *perr = NULL, why[MSG_MAX];
    const char *host, *port, *user, *db;
    size_t safe_len;
    int k = 0;

    *out = NULL;
    if (!url || (strncmp(url, "postgresql://", 13) != 0 && strncmp(url, "postgres://", 11) != 0)) {
        snprintf(err, errlen, "the job database must be a postgresql:// URL");
        return LJGAP_JOBSTORE_INVALID;
    }
    if (!(s = calloc(1, sizeof *s)) || !(s->url = strdup(url))) {
        free(s);
        snprintf(err, errlen, "out of memory");
        return LJGAP_JOBSTORE_NOMEM;
    }
    s->base.ops = &pg_ops;
    pthread_mutex_init(&s->lock, NULL);
    ljgap__cond_init_monotonic(&s->freed);
    s->max = max_conns ? max_conns : CONNS_DEFAULT;
    pgs_find_secrets(s, url);
    s->safe = strdup("postgresql://");
    if (!s->safe || !(s->idle = calloc(s->max, sizeof *s->idle))) {
        snprintf(err, errlen, "out of memory");
        op_close(&s->base);
        return LJGAP_JOBSTORE_NOMEM;
    }
    s->base.where = s->safe;
    if (!(info = PQconninfoParse(url, &perr))) {
        pgs_clean_msg(s, perr ? perr : "out of memory", why, sizeof why);
        snprintf(err, errlen, "the job database URL does not parse: %s", why);
        PQfreemem(perr);
        op_close(&s->base);
        return LJGAP_JOBSTORE_INVALID;
    }
    host = pgs_opt(info, "host") ? pgs_opt(info, "host") : pgs_opt(info, "hostaddr");
    port = pgs_opt(info, "port");
    user = pgs_opt(info, "user");
    db = pgs_opt(info, "dbname");
    safe_len = 32 + (host ? strlen(host) : 0) + (port ? strlen(port) : 0) +
               (user ? strlen(user) : 0) + (db ? strlen(db) : 0);
    free(s->safe);
    if (!(s->safe = malloc(safe_len))) {
        PQconninfoFree(info);
        snprintf(err, errlen, "out of memory");
        s->base.where = NULL;
        op_close(&s->base);
        return LJGAP_JOBSTORE_NOMEM;
    }
    snprintf(s->safe, safe_len, "postgresql://%s%s%s%s%s/%s", user ? user : "", user ? "@" : "",
             host ? host : "", port ? ":" : "", port ? port : "", db ? db : "");
    s->base.where = s->safe;
    PQconninfoFree(info);

    /* our defaults first: the URL's own settings win (expand_dbname: later keys override) */
    s->keys[k] = "connect_timeout", s->vals[k++] = "5";
    s->keys[k] = "application_name", s->vals[k++] = "ljgapd";
    s->keys[k] = "keepalives", s->vals[k++] = "1";
    s->keys[k] = "keepalives_idle", s->vals[k++] = "10";
    s->keys[k] = "keepalives_interval", s->vals[k++] = "5";
    s->keys[k] = "keepalives_count", s->vals[k++] = "3";
    s->keys[k] = "tcp_user_timeout", s->vals[k++] = "10000";
    s->keys[k] = "dbname", s->vals[k++] = s->url;
    s->keys[k] = "client_encoding", s->vals[k++] = "UTF8"; /* after the URL: always */
    s->keys[k] = NULL, s->vals[k] = NULL;

    if (!(c = pgs_connect(s, ljgap__clock_now() + OP_S, why, sizeof why))) {
        char clean[MSG_MAX];
        pgs_clean_msg(s, why, clean, sizeof clean);
        snprintf(err, errlen, "cannot connect to the job database %s: %s", s->safe, clean);
        op_close(&s->base);
        return LJGAP_JOBSTORE_ERROR;
    }
    if (check_schema(s, c, err, errlen) != 0) {
        PQfinish(c);
        op_close(&s->base);
        return LJGAP_JOBSTORE_ERROR;
    }
    s->open = 1;
    pgs_give(s, c, X_OK);
    *out = &s->base;
    return LJGAP_JOBSTORE_OK;
}
