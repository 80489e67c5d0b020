/* test_jobstore_pg.c -- the PostgreSQL job store (server/jobs/jobstore_pg.c) against a private
 * cluster: tests/scaleout/run.sh starts one and runs this with LJGAP_TEST_PG_URL set to a
 * database of it (without it this program fails: it is not one of make test's plain unit
 * tests). Each case starts from a database without the schema ljgapd, and drops it again.
 *
 * The contract every backend keeps (jobstore_contract.h), with rows damaged through SQL as an
 * operator could (checks dropped first), and what sharing adds: the schema created and
 * versioned, two stores on one database as two daemons (one queue, cancels and lapsed leases
 * crossing over), running jobs left alone by a reopen, concurrent claims that never take a job
 * twice, concurrent creates that never overfill the queue, connections killed by the server and
 * replaced, and every way opening fails, with the reason and never the password. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <libpq-fe.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "jobstatus.h"
#include "jobstore.h"

typedef struct {
    const char *url; /* $LJGAP_TEST_PG_URL */
} fixture;

static void quiet(void *arg, const char *message)
{
    (void)arg, (void)message;
}

/* Runs sql on a connection of its own; fails the test when PostgreSQL refuses. */
static PGresult *raw(const char *url, const char *sql)
{
    PGconn *c = PQconnectdb(url);
    PGresult *r = NULL;
    ExecStatusType st;
    if (PQstatus(c) != CONNECTION_OK) {
        print_error("%s: %s", url, PQerrorMessage(c));
        PQfinish(c);
        fail();
    }
    PQsetNoticeProcessor(c, quiet, NULL);
    r = PQexec(c, sql);
    st = PQresultStatus(r);
    if (st != PGRES_COMMAND_OK && st != PGRES_TUPLES_OK) {
        print_error("%s: %s", sql, PQresultErrorMessage(r));
        PQclear(r);
        PQfinish(c);
        fail();
    }
    PQfinish(c);
    return r;
}

static void raw_ok(const char *url, const char *sql)
{
    PQclear(raw(url, sql));
}

/* The first value of sql's first row, as a number. */
static long raw_long(const char *url, const char *sql)
{
    PGresult *r = raw(url, sql);
    long v;
    assert_true(PQntuples(r) >= 1);
    v = strtol(PQgetvalue(r, 0, 0), NULL, 10);
    PQclear(r);
    return v;
}

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    assert_non_null(f);
    f->url = getenv("LJGAP_TEST_PG_URL");
    assert_non_null(f->url);
    raw_ok(f->url, "DROP SCHEMA IF EXISTS ljgapd CASCADE");
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    raw_ok(f->url, "DROP SCHEMA IF EXISTS ljgapd CASCADE"); /* leave the database as found */
    free(f);
    return 0;
}

static ljgap__jobstore *open_pg(const char *url, unsigned conns)
{
    ljgap__jobstore *st = NULL;
    char err[600] = "";
    int rc = ljgap__jobstore_open_pg(url, conns, &st, err, sizeof err);
    if (rc != LJGAP_JOBSTORE_OK) print_error("open: %s\n", err);
    assert_int_equal(rc, LJGAP_JOBSTORE_OK);
    assert_non_null(st);
    return st;
}

/* Opening url fails with status rc, the message says `why` and does not hold `hidden`. */
static void open_fails(const char *url, int rc, const char *why, const char *hidden)
{
    ljgap__jobstore *st = (ljgap__jobstore *)1;
    char err[600] = "";
    assert_int_equal(ljgap__jobstore_open_pg(url, 0, &st, err, sizeof err), rc);
    assert_null(st);
    if (!strstr(err, why) || (hidden && strstr(err, hidden)))
        print_error("message \"%s\" should say \"%s\"%s%s\n", err, why,
                    hidden ? " and not show " : "", hidden ? hidden : "");
    assert_non_null(strstr(err, why));
    if (hidden) assert_null(strstr(err, hidden));
}

/* ---- the contract, on PostgreSQL ---- */

static ljgap__jobstore *contract_open(void **state)
{
    return open_pg(((fixture *)*state)->url, 0);
}

/* Drops the table's checks (so the rows it refuses can be written, as by hand), then sql. */
static void contract_sql(void **state, const char *sql)
{
    const char *url = ((fixture *)*state)->url;
    raw_ok(url, "DO $$ DECLARE c record; BEGIN FOR c IN SELECT conname FROM pg_constraint "
                "WHERE conrelid = 'ljgapd.jobs'::regclass AND contype = 'c' LOOP "
                "EXECUTE format('ALTER TABLE ljgapd.jobs DROP CONSTRAINT %I', c.conname); "
                "END LOOP; END $$");
    raw_ok(url, sql);
}

#define CONTRACT_TABLE "ljgapd.jobs"
static const char *const contract_damages[] = {
    /* 1: an unknown state */ "state = 'weird'",
    /* 2: a result that is not JSON */ "state = 'done', answer = '{broken'",
    /* 3: a number that is not finite */ "state = 'done', answer = '{\"a\":1e999}'",
    /* 4: not an object */ "state = 'done', answer = '\"text\"'",
    /* 5: a lone surrogate */ "state = 'done', answer = '{\"a\":\"\\ud800\"}'",
    /* 6: done without a result */ "state = 'done', answer = NULL",
    /* 7: failed without a problem */ "state = 'failed', answer = NULL",
    /* 8: trailing garbage */ "state = 'done', answer = '{} {}'",
    /* 9: a problem that is not one */ "state = 'failed', answer = '{\"x\":1}'",
    /* 10: errors that are not {pointer, detail} */
    "state = 'cancelled', answer = '{\"type\":\"" LJGAP_PROBLEM_BASE "x\",\"title\":\"t\","
    "\"status\":1,\"detail\":\"d\",\"errors\":[1]}'",
    /* 11: someone else's problem type */
    "state = 'failed', answer = '{\"type\":\"about:blank\",\"title\":\"t\","
    "\"status\":1,\"detail\":\"d\",\"errors\":[]}'",
    /* 12: an empty result */ "state = 'done', answer = ''",
    /* 13: nesting deeper than the parser takes */ "state = 'done', answer = repeat('[', 100000)",
    /* 14: an empty state */ "state = ''",
};
#define CONTRACT_ODD_NUMBERS                                                                       \
    "progress = 'Infinity', created = 'epoch'::timestamptz - interval '5 seconds', "               \
    "started = 'infinity', finished = 'epoch'::timestamptz + interval '2 seconds'"
#define CONTRACT_RUNNING_JUNK "progress = 'NaN', answer = 'junk'"

#include "jobstore_contract.h"

/* ---- PostgreSQL's own ---- */

/* The schema ljgapd at version 1 with its functions; the store names the database without a
 * password; it opens again without migrating. */
static void test_pg_schema(void **state)
{
    fixture *f = *state;
    ljgap__jobstore *st = open_pg(f->url, 0);
    char want[300];
    assert_int_equal(raw_long(f->url, "SELECT version FROM ljgapd.schema_version"), 1);
    assert_int_equal(raw_long(f->url, "SELECT count(*) FROM ljgapd.schema_version"), 1);
    assert_int_equal(raw_long(f->url, "SELECT count(*) FROM pg_proc p JOIN pg_namespace n ON "
                                      "n.oid = p.pronamespace WHERE n.nspname = 'ljgapd'"),
                     2);
    snprintf(want, sizeof want, "%s", f->url); /* postgresql://user@host:port/db, no password */
    assert_string_equal(st->where, want);
    ljgap__jobstore_close(st);
    st = open_pg(f->url, 0);
    assert_int_equal(raw_long(f->url, "SELECT count(*) FROM ljgapd.schema_version"), 1);
    ljgap__jobstore_close(st);
}

static void *opener(void *p)
{
    char err[600];
    ljgap__jobstore *st = NULL;
    if (ljgap__jobstore_open_pg(getenv("LJGAP_TEST_PG_URL"), 1, &st, err, sizeof err) != 0)
        return NULL;
    return st;
}

/* Four daemons starting at once on an empty database: the schema is made once, all open. */
static void test_pg_concurrent_open(void **state)
{
    fixture *f = *state;
    pthread_t t[4];
    void *st[4];
    for (int i = 0; i < 4; i++)
        assert_int_equal(pthread_create(&t[i], NULL, opener, NULL), 0);
    for (int i = 0; i < 4; i++)
        pthread_join(t[i], &st[i]);
    for (int i = 0; i < 4; i++) {
        assert_non_null(st[i]);
        ljgap__jobstore_close(st[i]);
    }
    assert_int_equal(raw_long(f->url, "SELECT count(*) FROM ljgapd.schema_version"), 1);
    assert_int_equal(raw_long(f->url, "SELECT max(version) FROM ljgapd.schema_version"), 1);
}

/* Two stores on one database are two daemons sharing one queue. */
static void test_pg_two_daemons(void **state)
{
    fixture *f = *state;
    ljgap__jobstore *a = open_pg(f->url, 0), *b = open_pg(f->url, 0);
    ljgap__job_record rec;
    unsigned q, r;
    int cancel = 0;
    long run;
    create_ok(a, ID_A, "{\"from\":\"a\"}");
    create_ok(b, ID_B, "{}");
    assert_int_equal(state_of(b, ID_A), LJGAP_JOB_QUEUED); /* any daemon answers for any job */
    assert_int_equal(ljgap__jobstore_counts(b, &q, &r), LJGAP_JOBSTORE_OK);
    assert_true(q == 2 && r == 0);
    assert_int_equal(ljgap__jobstore_claim(b, "b:1", 30, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, ID_A); /* one FIFO queue */
    assert_string_equal(rec.request, "{\"from\":\"a\"}");
    run = rec.run;
    ljgap__job_record_clear(&rec);
    /* a cancel asked of a reaches b's worker at its next renewal */
    assert_int_equal(ljgap__jobstore_cancel(a, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_true(rec.state == LJGAP_JOB_RUNNING && rec.cancel == 1);
    ljgap__job_record_clear(&rec);
    assert_int_equal(ljgap__jobstore_renew(b, ID_A, run, 0.3, 30, &cancel), LJGAP_JOBSTORE_OK);
    assert_int_equal(cancel, 1);
    assert_int_equal(ljgap__jobstore_finish(b, ID_A, run, LJGAP_JOB_CANCELLED, NULL, 0), 0);
    assert_int_equal(state_of(a, ID_A), LJGAP_JOB_CANCELLED);
    /* a daemon dies holding a job: another claims it once the lease lapses, from the start */
    run = claim_ok(a, ID_B, 0.2);
    ljgap__jobstore_close(a); /* the job stays running, as after a crash */
    assert_int_equal(ljgap__jobstore_claim(b, "b:1", 30, &rec), LJGAP_JOBSTORE_EMPTY);
    sleep_ms(300);
    assert_int_equal(ljgap__jobstore_claim(b, "b:1", 30, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, ID_B);
    assert_true(rec.run == run + 1 && rec.lost == 1 && rec.progress == 0);
    assert_true(rec.now >= rec.started && rec.started > rec.created);
    ljgap__job_record_clear(&rec);
    assert_int_equal(ljgap__jobstore_finish(b, ID_B, run, LJGAP_JOB_DONE, "{}", 2),
                     LJGAP_JOBSTORE_LOST); /* the dead daemon's claim */
    assert_int_equal(ljgap__jobstore_finish(b, ID_B, run + 1, LJGAP_JOB_DONE, "{}", 2), 0);
    ljgap__jobstore_close(b);
}

/* Opening never requeues: running jobs may belong to another daemon. */
static void test_pg_reopen(void **state)
{
    fixture *f = *state;
    ljgap__jobstore *st = open_pg(f->url, 0);
    ljgap__job_record rec;
    long run;
    create_ok(st, ID_A, "{}");
    create_ok(st, ID_B, "{}");
    run = claim_ok(st, ID_A, 30);
    ljgap__jobstore_close(st);
    st = open_pg(f->url, 0);
    assert_int_equal(ljgap__jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_true(rec.state == LJGAP_JOB_RUNNING && rec.run == run && rec.lost == 0);
    ljgap__job_record_clear(&rec);
    claim_ok(st, ID_B, 30); /* not A: its lease holds */
    ljgap__jobstore_close(st);
}

/* ---- concurrency ---- */

#define JOBS 40
typedef struct {
    ljgap__jobstore *st;
    int n; /* jobs this thread claimed */
    char ids[JOBS][LJGAP_JOB_ID_LEN + 1];
    int errors;        /* store calls that failed */
    int created, full; /* create: OK and FULL answers */
} worker_arg;

static void *claimer(void *p)
{
    worker_arg *w = p;
    ljgap__job_record rec;
    int st;
    while ((st = ljgap__jobstore_claim(w->st, "t", 30, &rec)) == LJGAP_JOBSTORE_OK) {
        if (w->n < JOBS) memcpy(w->ids[w->n++], rec.id, sizeof rec.id);
        if (ljgap__jobstore_finish(w->st, rec.id, rec.run, LJGAP_JOB_DONE, "{}", 2) != 0)
            w->errors++;
        ljgap__job_record_clear(&rec);
    }
    if (st != LJGAP_JOBSTORE_EMPTY) w->errors++;
    return NULL;
}

/* Four workers of two daemons claim 40 jobs at once: each job exactly once. */
static void test_pg_concurrent_claims(void **state)
{
    fixture *f = *state;
    ljgap__jobstore *a = open_pg(f->url, 2), *b = open_pg(f->url, 2);
    worker_arg w[4];
    pthread_t t[4];
    int seen[JOBS] = {0}, total = 0;
    char id[LJGAP_JOB_ID_LEN + 1];
    for (int i = 0; i < JOBS; i++) {
        snprintf(id, sizeof id, "%032x", i);
        create_ok(i % 2 ? a : b, id, "{}");
    }
    memset(w, 0, sizeof w);
    for (int i = 0; i < 4; i++) {
        w[i].st = i % 2 ? a : b;
        assert_int_equal(pthread_create(&t[i], NULL, claimer, &w[i]), 0);
    }
    for (int i = 0; i < 4; i++) {
        pthread_join(t[i], NULL);
        assert_int_equal(w[i].errors, 0);
        for (int k = 0; k < w[i].n; k++)
            seen[strtol(w[i].ids[k], NULL, 16)]++;
        total += w[i].n;
    }
    assert_int_equal(total, JOBS);
    for (int i = 0; i < JOBS; i++)
        assert_int_equal(seen[i], 1);
    ljgap__jobstore_close(a);
    ljgap__jobstore_close(b);
}

static void *creator(void *p)
{
    worker_arg *w = p;
    char id[LJGAP_JOB_ID_LEN + 1];
    for (int i = 0; i < 10; i++) {
        int st;
        ljgap__job_id_new(id);
        st = ljgap__jobstore_create(w->st, id, "simulation", "{}", 2, 15);
        if (st == LJGAP_JOBSTORE_OK)
            w->created++;
        else if (st == LJGAP_JOBSTORE_FULL)
            w->full++;
        else
            w->errors++;
    }
    return NULL;
}

/* Four threads of two daemons create 40 jobs at once with a cap of 15: exactly 15 are queued. */
static void test_pg_concurrent_cap(void **state)
{
    fixture *f = *state;
    ljgap__jobstore *a = open_pg(f->url, 2), *b = open_pg(f->url, 2);
    worker_arg w[4];
    pthread_t t[4];
    int created = 0, full = 0;
    unsigned q, r;
    memset(w, 0, sizeof w);
    for (int i = 0; i < 4; i++) {
        w[i].st = i % 2 ? a : b;
        assert_int_equal(pthread_create(&t[i], NULL, creator, &w[i]), 0);
    }
    for (int i = 0; i < 4; i++) {
        pthread_join(t[i], NULL);
        assert_int_equal(w[i].errors, 0);
        created += w[i].created;
        full += w[i].full;
    }
    assert_int_equal(created, 15);
    assert_int_equal(full, 25);
    assert_int_equal(ljgap__jobstore_counts(a, &q, &r), 0);
    assert_int_equal(q, 15);
    ljgap__jobstore_close(a);
    ljgap__jobstore_close(b);
}

/* The server kills the store's connections (an administrator, a restart): the next calls get
 * fresh ones and succeed; the store never holds more than it may. */
static void test_pg_reconnect(void **state)
{
    fixture *f = *state;
    ljgap__jobstore *st = open_pg(f->url, 2);
    /* (waiting up to 5 s for each to be gone: then its socket is closed) */
    static const char kill_all[] = "SELECT count(pg_terminate_backend(pid, 5000)) FROM "
                                   "pg_stat_activity WHERE application_name = 'ljgapd' AND pid "
                                   "<> pg_backend_pid()";
    unsigned q, r;
    long run;
    int cancel;
    create_ok(st, ID_A, "{}");
    create_ok(st, ID_B, "{}");
    assert_true(raw_long(f->url, kill_all) >= 1);
    assert_int_equal(state_of(st, ID_A), LJGAP_JOB_QUEUED);
    run = claim_ok(st, ID_A, 30);
    raw_ok(f->url, kill_all);
    assert_int_equal(ljgap__jobstore_renew(st, ID_A, run, 0.5, 30, &cancel), LJGAP_JOBSTORE_OK);
    raw_ok(f->url, kill_all);
    assert_int_equal(ljgap__jobstore_finish(st, ID_A, run, LJGAP_JOB_DONE, "{}", 2), 0);
    raw_ok(f->url, kill_all);
    create_ok(st, ID_C, "{}");
    assert_int_equal(ljgap__jobstore_counts(st, &q, &r), 0);
    assert_true(q == 2 && r == 0);
    assert_true(raw_long(f->url, "SELECT count(*) FROM pg_stat_activity WHERE application_name "
                                 "= 'ljgapd'") <= 2);
    ljgap__jobstore_close(st);
    assert_int_equal(raw_long(f->url, "SELECT count(*) FROM pg_stat_activity WHERE "
                                      "application_name = 'ljgapd'"),
                     0); /* close closes them all */
}

/* ---- opening fails, with the reason and without the password ---- */

/* f->url with its host:port and database replaced; password inserted as user:PASSWORD@ */
static void url_with(const fixture *f, const char *password, const char *hostport, const char *db,
                     char *out, size_t n)
{
    const char *auth = strstr(f->url, "://") + 3, *at = strchr(auth, '@');
    const char *rest = at + 1, *slash = strchr(rest, '/');
    snprintf(out, n, "postgresql://%.*s%s%s@%.*s/%s", (int)(at - auth), auth, password ? ":" : "",
             password ? password : "", hostport ? (int)strlen(hostport) : (int)(slash - rest),
             hostport ? hostport : rest, db ? db : slash + 1);
}

static void test_pg_open_errors(void **state)
{
    fixture *f = *state;
    char url[400];
    ljgap__jobstore *st;
    double t0;

    /* nobody listens there: refused at once, the password never shown */
    url_with(f, "s3cretpw", "127.0.0.1:1", NULL, url, sizeof url);
    t0 = ljgap__jobstore_wallclock();
    open_fails(url, LJGAP_JOBSTORE_ERROR, "refused", "s3cretpw");
    open_fails(url, LJGAP_JOBSTORE_ERROR, "postgresql://ljgap@127.0.0.1:1/", NULL);
    assert_true(ljgap__jobstore_wallclock() - t0 < 5);
    /* the password as a query parameter, and percent-encoded */
    snprintf(url, sizeof url, "postgresql://ljgap@127.0.0.1:1/x?password=qwerty%%2112");
    open_fails(url, LJGAP_JOBSTORE_ERROR, "refused", "qwerty");
    /* a URL libpq cannot parse quotes the bad part: scrubbed when it is the password */
    url_with(f, "pa%zzss", "127.0.0.1:1", NULL, url, sizeof url);
    open_fails(url, LJGAP_JOBSTORE_INVALID, "does not parse", "pa%zz");
    open_fails("mysql://x@y/z", LJGAP_JOBSTORE_INVALID, "postgresql:// URL", NULL);
    open_fails(NULL, LJGAP_JOBSTORE_INVALID, "postgresql:// URL", NULL);
    /* no such database */
    url_with(f, NULL, NULL, "no_such_db", url, sizeof url);
    open_fails(url, LJGAP_JOBSTORE_ERROR, "does not exist", NULL);
    /* a database that is not UTF8 */
    if (raw_long(f->url, "SELECT count(*) FROM pg_database WHERE datname = 'latin'") == 0)
        raw_ok(f->url, "CREATE DATABASE latin ENCODING 'LATIN1' TEMPLATE template0 "
                       "LC_COLLATE 'C' LC_CTYPE 'C'");
    url_with(f, NULL, NULL, "latin", url, sizeof url);
    open_fails(url, LJGAP_JOBSTORE_ERROR, "needs a UTF8 database", NULL);
    /* and the good one still opens */
    st = open_pg(f->url, 0);
    ljgap__jobstore_close(st);
}

static void test_pg_foreign_schema(void **state)
{
    fixture *f = *state;
    raw_ok(f->url, "CREATE SCHEMA ljgapd; CREATE TABLE ljgapd.notes (t text)");
    open_fails(f->url, LJGAP_JOBSTORE_ERROR, "not an ljgapd job store", NULL);
    /* an empty schema ljgapd (made by an administrator, with its grants) is taken */
    raw_ok(f->url, "DROP TABLE ljgapd.notes");
    ljgap__jobstore_close(open_pg(f->url, 0));
}

static void test_pg_schema_too_new(void **state)
{
    fixture *f = *state;
    ljgap__jobstore_close(open_pg(f->url, 0));
    raw_ok(f->url, "UPDATE ljgapd.schema_version SET version = 99");
    open_fails(f->url, LJGAP_JOBSTORE_ERROR, "schema version 99", NULL);
    raw_ok(f->url, "DELETE FROM ljgapd.schema_version");
    open_fails(f->url, LJGAP_JOBSTORE_ERROR, "schema_version is empty", NULL);
}

/* ---- reading rows: whatever the text, a record ---- */

static void test_pg_row(void **state)
{
    ljgap__job_record rec;
    const char *val[LJGAP_PG_COLS] = {0};
    int len[LJGAP_PG_COLS] = {0};
    char *json;
    static const char *const good[LJGAP_PG_COLS] = {"0123456789abcdef0123456789abcdef",
                                                    "simulation",
                                                    "running",
                                                    "0.25",
                                                    "1700000000.5",
                                                    "1700000001",
                                                    NULL,
                                                    "t",
                                                    "3",
                                                    "1",
                                                    NULL,
                                                    "1700000002.25",
                                                    "\\x7b7d00ff"};
    (void)state;
    for (int i = 0; i < LJGAP_PG_COLS; i++) {
        val[i] = good[i];
        len[i] = good[i] ? (int)strlen(good[i]) : 0;
    }
    memset(&rec, 0, sizeof rec);
    assert_int_equal(ljgap__jobstore_pg_row(&rec, val, len, LJGAP_PG_COLS), 0);
    assert_string_equal(rec.id, good[0]);
    assert_true(rec.state == LJGAP_JOB_RUNNING && rec.progress == 0.25 && rec.cancel == 1);
    assert_true(rec.created == 1700000000.5 && rec.finished == 0 && rec.now == 1700000002.25);
    assert_true(rec.run == 3 && rec.lost == 1 && rec.answer == NULL);
    assert_int_equal(rec.request_len, 4);
    assert_memory_equal(rec.request, "{}\0\xff", 4);
    ljgap__job_record_clear(&rec);

    /* junk everywhere */
    val[LJGAP_PG_ID] = "0123456789abcdef0123456789abcdef0"; /* too long */
    val[LJGAP_PG_STATE] = "RUNNING";
    val[LJGAP_PG_PROGRESS] = "0.5x";
    val[LJGAP_PG_CREATED] = "Infinity";
    val[LJGAP_PG_STARTED] = "NaN";
    val[LJGAP_PG_CANCEL] = "true";
    val[LJGAP_PG_RUN] = "99999999999999999999999";
    val[LJGAP_PG_LOST] = "-";
    val[LJGAP_PG_REQUEST] = "\\x7b7"; /* odd */
    for (int i = 0; i < LJGAP_PG_COLS; i++)
        len[i] = val[i] ? (int)strlen(val[i]) : 0;
    val[LJGAP_PG_ANSWER] = "{\"a\":1}\0junk"; /* a length past a NUL */
    len[LJGAP_PG_ANSWER] = 12;
    memset(&rec, 0, sizeof rec);
    assert_int_equal(ljgap__jobstore_pg_row(&rec, val, len, LJGAP_PG_COLS), 0);
    assert_string_equal(rec.id, "");
    assert_int_equal(rec.state, LJGAP_JOB_BAD);
    assert_true(rec.progress == 0 && isinf(rec.created) && isnan(rec.started));
    assert_true(rec.cancel == 0 && rec.run == 0 && rec.lost == 0);
    assert_int_equal(rec.request_len, 0);
    assert_string_equal(rec.request, "");
    assert_int_equal(rec.answer_len, 12); /* kept as read: the status check refuses it */
    rec.state = LJGAP_JOB_DONE;
    assert_non_null(json = ljgap__job_status_json(&rec));
    assert_non_null(strstr(json, "job-damaged"));
    free(json);
    ljgap__job_record_clear(&rec);
    val[LJGAP_PG_REQUEST] = "\\x7g";
    len[LJGAP_PG_REQUEST] = 4;
    memset(&rec, 0, sizeof rec);
    assert_int_equal(ljgap__jobstore_pg_row(&rec, val, len, LJGAP_PG_COLS), 0);
    assert_int_equal(rec.request_len, 0);
    ljgap__job_record_clear(&rec);
    /* without the request column: no request */
    memset(&rec, 0, sizeof rec);
    assert_int_equal(ljgap__jobstore_pg_row(&rec, val, len, LJGAP_PG_REQUEST), 0);
    assert_null(rec.request);
    ljgap__job_record_clear(&rec);
}

int main(void)
{
#define T(f) cmocka_unit_test_setup_teardown(f, setup, teardown)
    const struct CMUnitTest tests[] = {
        CONTRACT_TESTS(T),         T(test_pg_schema),         T(test_pg_concurrent_open),
        T(test_pg_two_daemons),    T(test_pg_reopen),         T(test_pg_concurrent_claims),
        T(test_pg_concurrent_cap), T(test_pg_reconnect),      T(test_pg_open_errors),
        T(test_pg_foreign_schema), T(test_pg_schema_too_new), cmocka_unit_test(test_pg_row),
    };
    if (!getenv("LJGAP_TEST_PG_URL")) {
        fprintf(stderr, "test_jobstore_pg: set LJGAP_TEST_PG_URL to a database of a private "
                        "cluster (tests/scaleout/run.sh does)\n");
        return 2;
    }
    return cmocka_run_group_tests_name("jobstore_pg", tests, NULL, NULL);
}
