/* test_jobstore.c -- the SQLite job store (server/jobs/jobstore_sqlite.c) on temporary directories:
 * the contract every backend keeps (jobstore_contract.h: the life of a job, FIFO order, the
 * queue cap, leases, eviction, damaged rows read back), and what is SQLite's own: what a
 * restart does to running jobs, and every way opening can fail (missing and uncreatable, not a
 * directory, not writable, locked by another owner, not a database, a corrupt page, another
 * program's database, a schema too new, a read-only file). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "statedir.h"

#include <fcntl.h>
#include <sys/wait.h>

#include "jobstatus.h"
#include "jobstore.h"

#define NOBODY 65534 /* uid and gid of the unprivileged user the permission tests run as */

typedef struct {
    char root[STATEDIR_LEN]; /* the temporary directory */
    char dir[STATEDIR_LEN];  /* root/state: the state directory */
} fixture;

static ljgap__jobstore *open_ok(const char *dir);

/* ---- the contract, on SQLite ---- */

static ljgap__jobstore *contract_open(void **state)
{
    return open_ok(((fixture *)*state)->dir);
}

static void contract_sql(void **state, const char *sql)
{
    statedir_sql(((fixture *)*state)->dir, sql);
}

#define CONTRACT_TABLE "jobs"
static const char *const contract_damages[] = {
    /* 1: an unknown state */ "state = 'weird'",
    /* 2: a result that is not JSON */ "state = 'done', answer = '{broken'",
    /* 3: invalid UTF-8 */ "state = 'done', answer = CAST(x'7b2261223a22ff227d' AS TEXT)",
    /* 4: a number that is not finite */ "state = 'done', answer = '{\"a\":1e999}'",
    /* 5: not an object */ "state = 'done', answer = '\"text\"'",
    /* 6: a lone surrogate */ "state = 'done', answer = '{\"a\":\"\\ud800\"}'",
    /* 7: done without a result */ "state = 'done', answer = NULL",
    /* 8: failed without a problem */ "state = 'failed', answer = NULL",
    /* 9: a NUL inside */ "state = 'failed', answer = CAST(x'7b7d007b7d' AS TEXT)",
    /* 10: trailing garbage */ "state = 'done', answer = '{} {}'",
    /* 11: a problem that is not one */ "state = 'failed', answer = '{\"x\":1}'",
    /* 12: errors that are not {pointer, detail} */
    "state = 'cancelled', answer = '{\"type\":\"" LJGAP_PROBLEM_BASE "x\",\"title\":\"t\","
    "\"status\":1,\"detail\":\"d\",\"errors\":[1]}'",
    /* 13: someone else's problem type */
    "state = 'failed', answer = '{\"type\":\"about:blank\",\"title\":\"t\","
    "\"status\":1,\"detail\":\"d\",\"errors\":[]}'",
};
#define CONTRACT_ODD_NUMBERS "progress = 7, created = -5, started = 1e300, finished = 2"
#define CONTRACT_RUNNING_JUNK "progress = -3, answer = 'junk'"

#include "jobstore_contract.h"

/* ---- SQLite's own ---- */

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    assert_non_null(f);
    statedir_make(f->root);
    snprintf(f->dir, sizeof f->dir, "%.200s/state", f->root);
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    statedir_remove(f->root);
    free(f);
    return 0;
}

static ljgap__jobstore *open_ok(const char *dir)
{
    ljgap__jobstore *st = NULL;
    char err[600] = "";
    int rc = ljgap__jobstore_open_sqlite(dir, &st, err, sizeof err);
    if (rc != LJGAP_JOBSTORE_OK) print_error("open %s: %s\n", dir, err);
    assert_int_equal(rc, LJGAP_JOBSTORE_OK);
    assert_non_null(st);
    return st;
}

/* Opening dir fails, and the message names `names` and contains `why`. */
static void open_fails(const char *dir, const char *names, const char *why)
{
    ljgap__jobstore *st = (ljgap__jobstore *)1;
    char err[600] = "";
    assert_int_not_equal(ljgap__jobstore_open_sqlite(dir, &st, err, sizeof err), LJGAP_JOBSTORE_OK);
    assert_null(st);
    if (!strstr(err, names) || !strstr(err, why))
        print_error("message \"%s\" should name %s and say \"%s\"\n", err, names, why);
    assert_non_null(strstr(err, names));
    assert_non_null(strstr(err, why));
}

static void test_open_creates(void **state)
{
    fixture *f = *state;
    char deep[STATEDIR_LEN], path[PATH_MAX], text[64] = "";
    struct stat sb;
    ljgap__jobstore *st;
    sqlite3 *db;
    sqlite3_stmt *q;
    FILE *lock;
    long pid = 0;

    snprintf(deep, sizeof deep, "%.200s/a/b/state", f->root); /* parents are made too */
    st = open_ok(deep);
    assert_int_equal(stat(deep, &sb), 0);
    assert_int_equal(sb.st_mode & 0777, 0700);
    snprintf(path, sizeof path, "%s/lock", deep);
    assert_non_null(lock = fopen(path, "r"));
    assert_int_equal(fscanf(lock, "%ld", &pid), 1);
    fclose(lock);
    assert_int_equal(pid, (long)getpid());

    snprintf(path, sizeof path, "%s/jobs.sqlite", deep);
    assert_int_equal(sqlite3_open_v2(path, &db, SQLITE_OPEN_READONLY, NULL), SQLITE_OK);
    assert_int_equal(sqlite3_prepare_v2(db, "PRAGMA journal_mode", -1, &q, NULL), SQLITE_OK);
    assert_int_equal(sqlite3_step(q), SQLITE_ROW);
    snprintf(text, sizeof text, "%s", (const char *)sqlite3_column_text(q, 0));
    sqlite3_finalize(q);
    assert_string_equal(text, "wal");
    assert_int_equal(sqlite3_prepare_v2(db, "SELECT version FROM schema_version", -1, &q, NULL),
                     SQLITE_OK);
    assert_int_equal(sqlite3_step(q), SQLITE_ROW);
    assert_int_equal(sqlite3_column_int(q, 0), 1);
    sqlite3_finalize(q);
    sqlite3_close(db);
    ljgap__jobstore_close(st);
    ljgap__jobstore_close(open_ok(deep)); /* and opens again */
    ljgap__jobstore_close(NULL);
}

/* Closing with jobs running (a crash, as far as the file knows) and opening again: running
 * jobs are queued again (lost + 1), one whose cancel was asked is cancelled, finished ones read
 * back byte for byte. */
static void test_reopen(void **state)
{
    fixture *f = *state;
    ljgap__jobstore *st = open_ok(f->dir);
    static const char answer[] = "{\"sigma\":[0.1,2.5e-07,-3],\"s\":\"\xc3\xa9\"}";
    ljgap__job_record rec;
    run_to_done(st, ID_D, answer);
    create_ok(st, ID_A, "{\"a\":1}");
    create_ok(st, ID_B, "{}");
    create_ok(st, ID_C, "{}");
    claim_ok(st, ID_A, 30);
    claim_ok(st, ID_B, 30);
    assert_int_equal(ljgap__jobstore_cancel(st, ID_B, &rec), LJGAP_JOBSTORE_OK);
    ljgap__job_record_clear(&rec);
    ljgap__jobstore_close(st);

    st = open_ok(f->dir);
    assert_int_equal(ljgap__jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_true(rec.state == LJGAP_JOB_QUEUED && rec.lost == 1 && rec.progress == 0);
    ljgap__job_record_clear(&rec);
    assert_int_equal(state_of(st, ID_B), LJGAP_JOB_CANCELLED);
    assert_int_equal(state_of(st, ID_C), LJGAP_JOB_QUEUED);
    assert_int_equal(ljgap__jobstore_get(st, ID_D, &rec), LJGAP_JOBSTORE_OK);
    assert_int_equal(rec.answer_len, sizeof answer - 1);
    assert_memory_equal(rec.answer, answer, sizeof answer - 1);
    ljgap__job_record_clear(&rec);
    assert_int_equal(ljgap__jobstore_claim(st, "t", 30, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, ID_A); /* in its old place */
    assert_string_equal(rec.request, "{\"a\":1}");
    ljgap__job_record_clear(&rec);
    ljgap__jobstore_close(st);
}

/* ---- opening fails, with the path and the reason ---- */

static void test_uncreatable(void **state)
{
    fixture *f = *state;
    char file[STATEDIR_LEN], under[PATH_MAX];
    FILE *fp;
    snprintf(file, sizeof file, "%.200s/plain", f->root);
    assert_non_null(fp = fopen(file, "w"));
    fclose(fp);
    snprintf(under, sizeof under, "%s/state", file);
    open_fails(under, under, "Not a directory");
    open_fails(file, file, "is not a directory");
    open_fails("", "", "no state directory");
}

static void test_locked(void **state)
{
    fixture *f = *state;
    ljgap__jobstore *st = open_ok(f->dir);
    char pid[32];
    snprintf(pid, sizeof pid, "pid %ld", (long)getpid());
    open_fails(f->dir, f->dir, "in use by another process");
    open_fails(f->dir, f->dir, pid);
    ljgap__jobstore_close(st);
    ljgap__jobstore_close(open_ok(f->dir)); /* free again once closed */
}

/* writes n bytes of text at offset into dir/jobs.sqlite (creating it) */
static void scribble(const char *dir, long offset, const char *text, size_t n)
{
    char path[PATH_MAX];
    int fd;
    snprintf(path, sizeof path, "%s/jobs.sqlite", dir);
    assert_true((fd = open(path, O_WRONLY | O_CREAT, 0600)) >= 0);
    assert_int_equal(pwrite(fd, text, n, offset), (ssize_t)n);
    close(fd);
}

static void test_not_a_database(void **state)
{
    fixture *f = *state;
    char junk[4096];
    memset(junk, 'x', sizeof junk);
    assert_int_equal(mkdir(f->dir, 0700), 0);
    scribble(f->dir, 0, junk, sizeof junk);
    open_fails(f->dir, "jobs.sqlite", "not a database");
}

/* A good store whose table page is then overwritten: quick_check (or the first read) says so. */
static void test_corrupt_page(void **state)
{
    fixture *f = *state;
    ljgap__jobstore *st = open_ok(f->dir);
    char junk[512];
    char id[LJGAP_JOB_ID_LEN + 1];
    for (int i = 0; i < 20; i++) {
        assert_int_equal(ljgap__job_id_new(id), 0);
        create_ok(st, id, "{\"some\":\"request body of a fair length to fill pages\"}");
    }
    ljgap__jobstore_close(st); /* checkpoints the WAL into the file */
    memset(junk, 0xa5, sizeof junk);
    scribble(f->dir, 4096 + 0, junk, sizeof junk); /* page 2: the jobs table's root */
    open_fails(f->dir, "jobs.sqlite", "corrupt");
}

static void test_foreign_database(void **state)
{
    fixture *f = *state;
    assert_int_equal(mkdir(f->dir, 0700), 0);
    statedir_sql(f->dir, "CREATE TABLE notes (t TEXT); INSERT INTO notes VALUES ('mine');");
    open_fails(f->dir, "jobs.sqlite", "not an ljgapd job store");
}

static void test_schema_too_new(void **state)
{
    fixture *f = *state;
    ljgap__jobstore_close(open_ok(f->dir));
    statedir_sql(f->dir, "UPDATE schema_version SET version = 99");
    open_fails(f->dir, "jobs.sqlite", "schema version 99");
    statedir_sql(f->dir, "DROP TABLE schema_version");
    open_fails(f->dir, "jobs.sqlite", "no schema version");
}

/* Runs check(dir) as an unprivileged user when we are root (root writes anywhere), else
 * directly; the check's exit status says whether opening failed as it should. */
static void as_nobody(const char *dir, int (*check)(const char *dir))
{
    pid_t pid;
    int status = -1;
    if (geteuid() != 0) {
        assert_int_equal(check(dir), 0);
        return;
    }
    pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        if (setgid(NOBODY) != 0 || setuid(NOBODY) != 0) _exit(3);
        _exit(check(dir));
    }
    assert_int_equal(waitpid(pid, &status, 0), pid);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        print_error("the unprivileged check on %s ended with status %d\n", dir, status);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

/* 0 when opening dir fails naming it with the reason `want` */
static int fails_with(const char *dir, const char *want)
{
    ljgap__jobstore *st = NULL;
    char err[600] = "";
    if (ljgap__jobstore_open_sqlite(dir, &st, err, sizeof err) == LJGAP_JOBSTORE_OK) {
        ljgap__jobstore_close(st);
        return 1;
    }
    if (!strstr(err, dir) || !strstr(err, want)) {
        fprintf(stderr, "unexpected message: %s\n", err);
        return 2;
    }
    return 0;
}

static int unwritable_dir(const char *dir)
{
    return fails_with(dir, "not writable");
}

static int readonly_file(const char *dir)
{
    return fails_with(dir, "read-only");
}

static int uncreatable_dir(const char *dir)
{
    char sub[PATH_MAX];
    snprintf(sub, sizeof sub, "%s/sub", dir);
    return fails_with(sub, "Permission denied");
}

static void test_unwritable(void **state)
{
    fixture *f = *state;
    char path[PATH_MAX];
    assert_int_equal(mkdir(f->dir, 0555), 0);
    as_nobody(f->dir, unwritable_dir);
    as_nobody(f->dir, uncreatable_dir);
    /* a writable directory, but the database file is read-only */
    assert_int_equal(chmod(f->dir, 0777), 0);
    ljgap__jobstore_close(open_ok(f->dir));
    snprintf(path, sizeof path, "%s/lock", f->dir);
    assert_int_equal(chmod(path, 0666), 0);
    snprintf(path, sizeof path, "%s/jobs.sqlite", f->dir);
    assert_int_equal(chmod(path, 0444), 0);
    as_nobody(f->dir, readonly_file);
}

/* ---- damaged rows: whatever a row holds, the status is valid JSON ---- */

static void test_rfc3339(void **state)
{
    char buf[40];
    (void)state;
    ljgap__rfc3339(0, buf, sizeof buf);
    assert_string_equal(buf, "1970-01-01T00:00:00.000Z");
    ljgap__rfc3339(1700000000.9996, buf, sizeof buf); /* rounds up into the next second */
    assert_string_equal(buf, "2023-11-14T22:13:21.000Z");
    ljgap__rfc3339(951782400.25, buf, sizeof buf);
    assert_string_equal(buf, "2000-02-29T00:00:00.250Z");
}

int main(void)
{
#define T(f) cmocka_unit_test_setup_teardown(f, setup, teardown)
    const struct CMUnitTest tests[] = {
        CONTRACT_TESTS(T),
        T(test_open_creates),
        T(test_reopen),
        T(test_uncreatable),
        T(test_locked),
        T(test_not_a_database),
        T(test_corrupt_page),
        T(test_foreign_database),
        T(test_schema_too_new),
        T(test_unwritable),
        cmocka_unit_test(test_rfc3339),
    };
    return cmocka_run_group_tests_name("jobstore", tests, NULL, NULL);
}
