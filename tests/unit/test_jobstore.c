/* test_jobstore.c -- the SQLite job store (server/jobstore_sqlite.c) on temporary directories:
 * the life of a job (create, claim, renew, finish, release, cancel), FIFO order, the queue cap,
 * leases that lapse, eviction by count and by age, what a restart does to running jobs, and
 * every way opening can fail (missing and uncreatable, not a directory, not writable, locked
 * by another owner, not a database, a corrupt page, another program's database, a schema too
 * new, a read-only file). Damaged rows read back are shown as failed jobs with valid JSON. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "statedir.h"

#include <cjson/cJSON.h>
#include <fcntl.h>
#include <math.h>
#include <sys/wait.h>

#include "jobstatus.h"
#include "jobstore.h"
#include "request.h" /* ljgap_utf8_span */

#define ID_A "00000000000000000000000000000001"
#define ID_B "00000000000000000000000000000002"
#define ID_C "00000000000000000000000000000003"
#define ID_D "00000000000000000000000000000004"
#define NOBODY 65534 /* uid and gid of the unprivileged user the permission tests run as */

typedef struct {
    char root[STATEDIR_LEN]; /* the temporary directory */
    char dir[STATEDIR_LEN];  /* root/state: the state directory */
} fixture;

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

static ljgap_jobstore *open_ok(const char *dir)
{
    ljgap_jobstore *st = NULL;
    char err[600] = "";
    int rc = ljgap_jobstore_open_sqlite(dir, &st, err, sizeof err);
    if (rc != LJGAP_JOBSTORE_OK) print_error("open %s: %s\n", dir, err);
    assert_int_equal(rc, LJGAP_JOBSTORE_OK);
    assert_non_null(st);
    return st;
}

/* Opening dir fails, and the message names `names` and contains `why`. */
static void open_fails(const char *dir, const char *names, const char *why)
{
    ljgap_jobstore *st = (ljgap_jobstore *)1;
    char err[600] = "";
    assert_int_not_equal(ljgap_jobstore_open_sqlite(dir, &st, err, sizeof err), LJGAP_JOBSTORE_OK);
    assert_null(st);
    if (!strstr(err, names) || !strstr(err, why))
        print_error("message \"%s\" should name %s and say \"%s\"\n", err, names, why);
    assert_non_null(strstr(err, names));
    assert_non_null(strstr(err, why));
}

static void create_ok(ljgap_jobstore *st, const char *id, const char *body)
{
    assert_int_equal(ljgap_jobstore_create(st, id, "simulation", body, strlen(body), 0),
                     LJGAP_JOBSTORE_OK);
}

static ljgap_job_state state_of(ljgap_jobstore *st, const char *id)
{
    ljgap_job_record rec;
    ljgap_job_state s;
    assert_int_equal(ljgap_jobstore_get(st, id, &rec), LJGAP_JOBSTORE_OK);
    s = rec.state;
    ljgap_job_record_clear(&rec);
    return s;
}

/* claims the next job, which must be id; returns its run */
static long claim_ok(ljgap_jobstore *st, const char *id, double lease)
{
    ljgap_job_record rec;
    long run;
    assert_int_equal(ljgap_jobstore_claim(st, "test:1", lease, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, id);
    assert_int_equal(rec.state, LJGAP_JOB_RUNNING);
    run = rec.run;
    ljgap_job_record_clear(&rec);
    return run;
}

static void test_open_creates(void **state)
{
    fixture *f = *state;
    char deep[STATEDIR_LEN], path[PATH_MAX], text[64] = "";
    struct stat sb;
    ljgap_jobstore *st;
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
    ljgap_jobstore_close(st);
    ljgap_jobstore_close(open_ok(deep)); /* and opens again */
    ljgap_jobstore_close(NULL);
}

/* create, get, claim (FIFO, with the request as sent), renew, finish; counts throughout */
static void test_life(void **state)
{
    fixture *f = *state;
    ljgap_jobstore *st = open_ok(f->dir);
    static const char body[] = "{\"a\":1}\0tail"; /* bytes after a NUL come back too */
    ljgap_job_record rec;
    unsigned q, r;
    int cancel = 7;
    long run;
    double t0 = ljgap_jobstore_wallclock();

    assert_int_equal(ljgap_jobstore_create(st, ID_A, "simulation", body, sizeof body - 1, 0),
                     LJGAP_JOBSTORE_OK);
    create_ok(st, ID_B, "{}");
    assert_int_equal(ljgap_jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, ID_A);
    assert_string_equal(rec.kind, "simulation");
    assert_int_equal(rec.state, LJGAP_JOB_QUEUED);
    assert_true(rec.progress == 0 && rec.started == 0 && rec.finished == 0);
    assert_true(fabs(rec.created - t0) < 5 && rec.now >= rec.created);
    assert_null(rec.answer);
    assert_null(rec.request); /* get does not read the request */
    ljgap_job_record_clear(&rec);
    assert_int_equal(ljgap_jobstore_counts(st, &q, &r), LJGAP_JOBSTORE_OK);
    assert_true(q == 2 && r == 0);

    assert_int_equal(ljgap_jobstore_claim(st, "test:1", 30, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, ID_A); /* the oldest first */
    assert_int_equal(rec.request_len, sizeof body - 1);
    assert_memory_equal(rec.request, body, sizeof body - 1);
    assert_true(rec.run == 1 && rec.lost == 0 && rec.cancel == 0 && rec.started >= rec.created);
    run = rec.run;
    ljgap_job_record_clear(&rec);
    assert_int_equal(ljgap_jobstore_counts(st, &q, &r), LJGAP_JOBSTORE_OK);
    assert_true(q == 1 && r == 1);

    assert_int_equal(ljgap_jobstore_renew(st, ID_A, run, 0.4, 30, &cancel), LJGAP_JOBSTORE_OK);
    assert_int_equal(cancel, 0);
    assert_int_equal(ljgap_jobstore_renew(st, ID_A, run, 0.2, 30, &cancel), LJGAP_JOBSTORE_OK);
    assert_int_equal(ljgap_jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_true(rec.progress == 0.4); /* never lowered */
    assert_int_equal(rec.state, LJGAP_JOB_RUNNING);
    ljgap_job_record_clear(&rec);

    assert_int_equal(ljgap_jobstore_finish(st, ID_A, run, LJGAP_JOB_DONE, "{\"x\":1}", 7),
                     LJGAP_JOBSTORE_OK);
    assert_int_equal(ljgap_jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_int_equal(rec.state, LJGAP_JOB_DONE);
    assert_true(rec.progress == 1 && rec.finished >= rec.started && rec.started > 0);
    assert_string_equal(rec.answer, "{\"x\":1}");
    assert_int_equal(rec.answer_len, 7);
    ljgap_job_record_clear(&rec);
    /* a finished claim cannot be finished, renewed or released again */
    assert_int_equal(ljgap_jobstore_finish(st, ID_A, run, LJGAP_JOB_FAILED, NULL, 0),
                     LJGAP_JOBSTORE_LOST);
    assert_int_equal(ljgap_jobstore_renew(st, ID_A, run, 0.5, 30, &cancel), LJGAP_JOBSTORE_LOST);
    assert_int_equal(ljgap_jobstore_release(st, ID_A, run), LJGAP_JOBSTORE_LOST);

    run = claim_ok(st, ID_B, 30);
    assert_int_equal(ljgap_jobstore_claim(st, "test:1", 30, &rec), LJGAP_JOBSTORE_EMPTY);
    assert_int_equal(ljgap_jobstore_finish(st, ID_B, run, LJGAP_JOB_FAILED, "{\"status\":422}", 14),
                     LJGAP_JOBSTORE_OK);
    assert_int_equal(state_of(st, ID_B), LJGAP_JOB_FAILED);
    assert_int_equal(ljgap_jobstore_counts(st, &q, &r), LJGAP_JOBSTORE_OK);
    assert_true(q == 0 && r == 0);
    ljgap_jobstore_close(st);
}

static void test_create_refusals(void **state)
{
    fixture *f = *state;
    ljgap_jobstore *st = open_ok(f->dir);
    ljgap_job_record rec;
    int cancel;
    assert_int_equal(ljgap_jobstore_create(st, ID_A, "simulation", "{}", 2, 2), 0);
    assert_int_equal(ljgap_jobstore_create(st, ID_B, "simulation", "{}", 2, 2), 0);
    assert_int_equal(ljgap_jobstore_create(st, ID_C, "simulation", "{}", 2, 2),
                     LJGAP_JOBSTORE_FULL);
    assert_int_equal(ljgap_jobstore_get(st, ID_C, &rec), LJGAP_JOBSTORE_UNKNOWN);
    assert_int_equal(ljgap_jobstore_create(st, ID_C, "simulation", "{}", 2, 0), 0); /* no cap */
    assert_int_equal(ljgap_jobstore_create(st, ID_A, "simulation", "{}", 2, 0),
                     LJGAP_JOBSTORE_EXISTS);
    assert_int_equal(ljgap_jobstore_create(st, "0123", "simulation", "{}", 2, 0),
                     LJGAP_JOBSTORE_INVALID);
    assert_int_equal(
        ljgap_jobstore_create(st, "0000000000000000000000000000000G", "simulation", "{}", 2, 0),
        LJGAP_JOBSTORE_INVALID);
    assert_int_equal(ljgap_jobstore_create(st, ID_D, "Sim", "{}", 2, 0), LJGAP_JOBSTORE_INVALID);
    assert_int_equal(ljgap_jobstore_create(st, ID_D, "", "{}", 2, 0), LJGAP_JOBSTORE_INVALID);
    assert_non_null(strstr(ljgap_jobstore_errmsg(), "kind"));
    assert_int_equal(ljgap_jobstore_claim(st, "t", 0, &rec), LJGAP_JOBSTORE_INVALID);
    assert_int_equal(ljgap_jobstore_renew(st, "x", 1, 0, 30, &cancel), LJGAP_JOBSTORE_INVALID);
    assert_int_equal(ljgap_jobstore_finish(st, ID_A, 1, LJGAP_JOB_RUNNING, NULL, 0),
                     LJGAP_JOBSTORE_INVALID);
    assert_int_equal(ljgap_jobstore_get(st, "../etc", &rec), LJGAP_JOBSTORE_UNKNOWN);
    assert_int_equal(ljgap_jobstore_get(st, ID_D, &rec), LJGAP_JOBSTORE_UNKNOWN);
    ljgap_jobstore_close(st);
}

/* A lease that lapses: the job is claimed again (run + 1, lost + 1) and the first claim is
 * LOST for every write. */
static void test_lease_lapses(void **state)
{
    fixture *f = *state;
    ljgap_jobstore *st = open_ok(f->dir);
    ljgap_job_record rec;
    int cancel;
    long run1, run2;
    create_ok(st, ID_A, "{}");
    run1 = claim_ok(st, ID_A, 0.05);
    assert_int_equal(ljgap_jobstore_claim(st, "test:2", 30, &rec), LJGAP_JOBSTORE_EMPTY);
    sleep_ms(100);
    assert_int_equal(ljgap_jobstore_claim(st, "test:2", 30, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, ID_A);
    assert_int_equal(rec.run, run1 + 1);
    assert_int_equal(rec.lost, 1);
    run2 = rec.run;
    ljgap_job_record_clear(&rec);
    assert_int_equal(ljgap_jobstore_renew(st, ID_A, run1, 0.9, 30, &cancel), LJGAP_JOBSTORE_LOST);
    assert_int_equal(ljgap_jobstore_finish(st, ID_A, run1, LJGAP_JOB_DONE, "{}", 2),
                     LJGAP_JOBSTORE_LOST);
    assert_int_equal(ljgap_jobstore_release(st, ID_A, run1), LJGAP_JOBSTORE_LOST);
    /* a renewed lease does not lapse */
    assert_int_equal(ljgap_jobstore_renew(st, ID_A, run2, 0.1, 0.2, &cancel), LJGAP_JOBSTORE_OK);
    sleep_ms(50);
    assert_int_equal(ljgap_jobstore_renew(st, ID_A, run2, 0.2, 0.2, &cancel), LJGAP_JOBSTORE_OK);
    sleep_ms(100);
    assert_int_equal(ljgap_jobstore_claim(st, "test:3", 30, &rec), LJGAP_JOBSTORE_EMPTY);
    assert_int_equal(ljgap_jobstore_finish(st, ID_A, run2, LJGAP_JOB_DONE, "{}", 2),
                     LJGAP_JOBSTORE_OK);
    ljgap_jobstore_close(st);
}

/* Cancel: a queued job at once, a running one flagged (renew reads the flag), a finished one
 * left alone. */
static void test_cancel(void **state)
{
    fixture *f = *state;
    ljgap_jobstore *st = open_ok(f->dir);
    ljgap_job_record rec;
    int cancel = 0;
    long run;
    create_ok(st, ID_A, "{}");
    create_ok(st, ID_B, "{}");
    run = claim_ok(st, ID_A, 30);

    assert_int_equal(ljgap_jobstore_cancel(st, ID_B, &rec), LJGAP_JOBSTORE_OK);
    assert_int_equal(rec.state, LJGAP_JOB_CANCELLED);
    assert_true(rec.finished > 0 && rec.started == 0 && !rec.answer);
    ljgap_job_record_clear(&rec);
    assert_int_equal(ljgap_jobstore_claim(st, "t", 30, &rec), LJGAP_JOBSTORE_EMPTY);

    assert_int_equal(ljgap_jobstore_cancel(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_int_equal(rec.state, LJGAP_JOB_RUNNING);
    assert_int_equal(rec.cancel, 1);
    ljgap_job_record_clear(&rec);
    assert_int_equal(ljgap_jobstore_renew(st, ID_A, run, 0.5, 30, &cancel), LJGAP_JOBSTORE_OK);
    assert_int_equal(cancel, 1);
    assert_int_equal(ljgap_jobstore_finish(st, ID_A, run, LJGAP_JOB_CANCELLED, "{\"p\":1}", 7),
                     LJGAP_JOBSTORE_OK);
    assert_int_equal(ljgap_jobstore_cancel(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_int_equal(rec.state, LJGAP_JOB_CANCELLED);
    assert_string_equal(rec.answer, "{\"p\":1}");
    ljgap_job_record_clear(&rec);

    create_ok(st, ID_C, "{}");
    run = claim_ok(st, ID_C, 30);
    assert_int_equal(ljgap_jobstore_finish(st, ID_C, run, LJGAP_JOB_DONE, "{}", 2), 0);
    assert_int_equal(ljgap_jobstore_cancel(st, ID_C, &rec), LJGAP_JOBSTORE_OK);
    assert_int_equal(rec.state, LJGAP_JOB_DONE);
    ljgap_job_record_clear(&rec);
    assert_int_equal(ljgap_jobstore_cancel(st, ID_D, &rec), LJGAP_JOBSTORE_UNKNOWN);
    assert_int_equal(ljgap_jobstore_cancel(st, "nope", &rec), LJGAP_JOBSTORE_UNKNOWN);
    ljgap_jobstore_close(st);
}

/* Release puts a job back in its old place: it is claimed before a later one. */
static void test_release(void **state)
{
    fixture *f = *state;
    ljgap_jobstore *st = open_ok(f->dir);
    ljgap_job_record rec;
    int cancel;
    long run;
    create_ok(st, ID_A, "{}");
    create_ok(st, ID_B, "{}");
    run = claim_ok(st, ID_A, 30);
    assert_int_equal(ljgap_jobstore_renew(st, ID_A, run, 0.7, 30, &cancel), 0);
    assert_int_equal(ljgap_jobstore_release(st, ID_A, run), LJGAP_JOBSTORE_OK);
    assert_int_equal(ljgap_jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_true(rec.state == LJGAP_JOB_QUEUED && rec.progress == 0 && rec.started == 0);
    ljgap_job_record_clear(&rec);
    assert_int_equal(ljgap_jobstore_claim(st, "t", 30, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, ID_A);
    assert_true(rec.run == run + 1 && rec.lost == 0); /* given back, not lost */
    ljgap_job_record_clear(&rec);
    ljgap_jobstore_close(st);
}

/* finishes job id (claiming it first) with answer */
static void run_to_done(ljgap_jobstore *st, const char *id, const char *answer)
{
    long run;
    create_ok(st, id, "{}");
    run = claim_ok(st, id, 30);
    assert_int_equal(ljgap_jobstore_finish(st, id, run, LJGAP_JOB_DONE, answer, strlen(answer)),
                     LJGAP_JOBSTORE_OK);
}

static void test_evict(void **state)
{
    fixture *f = *state;
    ljgap_jobstore *st = open_ok(f->dir);
    const char *ids[] = {ID_A, ID_B, ID_C, ID_D};
    ljgap_job_record rec;
    unsigned n = 99;
    for (int i = 0; i < 4; i++)
        run_to_done(st, ids[i], "{}");
    create_ok(st, "00000000000000000000000000000005", "{}"); /* queued: never evicted */
    assert_int_equal(ljgap_jobstore_evict(st, 2, 3600, &n), LJGAP_JOBSTORE_OK);
    assert_int_equal(n, 2); /* the two that finished first */
    assert_int_equal(ljgap_jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_UNKNOWN);
    assert_int_equal(ljgap_jobstore_get(st, ID_B, &rec), LJGAP_JOBSTORE_UNKNOWN);
    assert_int_equal(state_of(st, ID_C), LJGAP_JOB_DONE);
    assert_int_equal(state_of(st, ID_D), LJGAP_JOB_DONE);
    sleep_ms(20);
    assert_int_equal(ljgap_jobstore_evict(st, 100, 0.01, &n), LJGAP_JOBSTORE_OK);
    assert_int_equal(n, 2); /* by age */
    assert_int_equal(ljgap_jobstore_get(st, ID_D, &rec), LJGAP_JOBSTORE_UNKNOWN);
    assert_int_equal(state_of(st, "00000000000000000000000000000005"), LJGAP_JOB_QUEUED);
    assert_int_equal(ljgap_jobstore_evict(st, 100, -1, &n), LJGAP_JOBSTORE_INVALID);
    ljgap_jobstore_close(st);
}

/* Closing with jobs running (a crash, as far as the file knows) and opening again: running
 * jobs are queued again (lost + 1), one whose cancel was asked is cancelled, finished ones read
 * back byte for byte. */
static void test_reopen(void **state)
{
    fixture *f = *state;
    ljgap_jobstore *st = open_ok(f->dir);
    static const char answer[] = "{\"sigma\":[0.1,2.5e-07,-3],\"s\":\"\xc3\xa9\"}";
    ljgap_job_record rec;
    run_to_done(st, ID_D, answer);
    create_ok(st, ID_A, "{\"a\":1}");
    create_ok(st, ID_B, "{}");
    create_ok(st, ID_C, "{}");
    claim_ok(st, ID_A, 30);
    claim_ok(st, ID_B, 30);
    assert_int_equal(ljgap_jobstore_cancel(st, ID_B, &rec), LJGAP_JOBSTORE_OK);
    ljgap_job_record_clear(&rec);
    ljgap_jobstore_close(st);

    st = open_ok(f->dir);
    assert_int_equal(ljgap_jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_true(rec.state == LJGAP_JOB_QUEUED && rec.lost == 1 && rec.progress == 0);
    ljgap_job_record_clear(&rec);
    assert_int_equal(state_of(st, ID_B), LJGAP_JOB_CANCELLED);
    assert_int_equal(state_of(st, ID_C), LJGAP_JOB_QUEUED);
    assert_int_equal(ljgap_jobstore_get(st, ID_D, &rec), LJGAP_JOBSTORE_OK);
    assert_int_equal(rec.answer_len, sizeof answer - 1);
    assert_memory_equal(rec.answer, answer, sizeof answer - 1);
    ljgap_job_record_clear(&rec);
    assert_int_equal(ljgap_jobstore_claim(st, "t", 30, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, ID_A); /* in its old place */
    assert_string_equal(rec.request, "{\"a\":1}");
    ljgap_job_record_clear(&rec);
    ljgap_jobstore_close(st);
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
    ljgap_jobstore *st = open_ok(f->dir);
    char pid[32];
    snprintf(pid, sizeof pid, "pid %ld", (long)getpid());
    open_fails(f->dir, f->dir, "in use by another process");
    open_fails(f->dir, f->dir, pid);
    ljgap_jobstore_close(st);
    ljgap_jobstore_close(open_ok(f->dir)); /* free again once closed */
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
    ljgap_jobstore *st = open_ok(f->dir);
    char junk[512];
    char id[LJGAP_JOB_ID_LEN + 1];
    for (int i = 0; i < 20; i++) {
        assert_int_equal(ljgap_job_id_new(id), 0);
        create_ok(st, id, "{\"some\":\"request body of a fair length to fill pages\"}");
    }
    ljgap_jobstore_close(st); /* checkpoints the WAL into the file */
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
    ljgap_jobstore_close(open_ok(f->dir));
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
    ljgap_jobstore *st = NULL;
    char err[600] = "";
    if (ljgap_jobstore_open_sqlite(dir, &st, err, sizeof err) == LJGAP_JOBSTORE_OK) {
        ljgap_jobstore_close(st);
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
    ljgap_jobstore_close(open_ok(f->dir));
    snprintf(path, sizeof path, "%s/lock", f->dir);
    assert_int_equal(chmod(path, 0666), 0);
    snprintf(path, sizeof path, "%s/jobs.sqlite", f->dir);
    assert_int_equal(chmod(path, 0444), 0);
    as_nobody(f->dir, readonly_file);
}

/* ---- damaged rows: whatever a row holds, the status is valid JSON ---- */

/* The status object of id, parsed; checks it is valid UTF-8 JSON with the required fields. */
static cJSON *status_doc(ljgap_jobstore *st, const char *id)
{
    ljgap_job_record rec;
    char *s;
    cJSON *doc;
    const cJSON *p;
    assert_int_equal(ljgap_jobstore_get(st, id, &rec), LJGAP_JOBSTORE_OK);
    s = ljgap_job_status_json(&rec);
    ljgap_job_record_clear(&rec);
    assert_non_null(s);
    assert_int_equal(ljgap_utf8_span(s, strlen(s)), strlen(s));
    doc = cJSON_Parse(s);
    if (!doc) print_error("not JSON: %s\n", s);
    free(s);
    assert_non_null(doc);
    assert_true(cJSON_IsString(cJSON_GetObjectItem(doc, "status")));
    p = cJSON_GetObjectItem(doc, "progress");
    assert_true(cJSON_IsNumber(p) && p->valuedouble >= 0 && p->valuedouble <= 1);
    p = cJSON_GetObjectItem(doc, "elapsed_ms");
    assert_true(cJSON_IsNumber(p) && p->valuedouble >= 0 && isfinite(p->valuedouble));
    return doc;
}

/* id's status is failed with a job-damaged problem */
static void damaged(ljgap_jobstore *st, const char *id)
{
    cJSON *doc = status_doc(st, id);
    const cJSON *type = cJSON_GetObjectItem(cJSON_GetObjectItem(doc, "problem"), "type");
    if (!cJSON_IsString(type) || !strstr(type->valuestring, "job-damaged")) {
        char *s = cJSON_PrintUnformatted(doc);
        print_error("%s: %s\n", id, s);
        free(s);
    }
    assert_string_equal(cJSON_GetObjectItem(doc, "status")->valuestring, "failed");
    assert_true(cJSON_IsString(type) && strstr(type->valuestring, "/job-damaged"));
    assert_null(cJSON_GetObjectItem(doc, "result"));
    cJSON_Delete(doc);
}

static void test_damaged_rows(void **state)
{
    fixture *f = *state;
    ljgap_jobstore *st = open_ok(f->dir);
    static const char *const rows[] = {
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
    char sql[600], id[LJGAP_JOB_ID_LEN + 1];
    cJSON *doc;
    for (size_t i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        snprintf(id, sizeof id, "%032zx", i + 0x100);
        run_to_done(st, id, "{}");
        snprintf(sql, sizeof sql, "UPDATE jobs SET %s WHERE id = '%s'", rows[i], id);
        statedir_sql(f->dir, sql);
        damaged(st, id);
    }
    /* sound answers, odd numbers: shown, clamped, dropped */
    run_to_done(st, ID_A, "{\"x\":1}");
    statedir_sql(f->dir, "UPDATE jobs SET progress = 7, created = -5, started = 1e300, finished "
                         "= 2 WHERE id = '" ID_A "'");
    doc = status_doc(st, ID_A);
    assert_string_equal(cJSON_GetObjectItem(doc, "status")->valuestring, "done");
    assert_null(cJSON_GetObjectItem(doc, "created"));
    assert_null(cJSON_GetObjectItem(doc, "started"));
    assert_true(cJSON_GetObjectItem(doc, "elapsed_ms")->valuedouble == 0);
    assert_true(cJSON_IsObject(cJSON_GetObjectItem(doc, "result")));
    cJSON_Delete(doc);
    /* a running row with an answer and progress out of range */
    create_ok(st, ID_B, "{}");
    claim_ok(st, ID_B, 30);
    statedir_sql(f->dir, "UPDATE jobs SET progress = -3, answer = 'junk' WHERE id = '" ID_B "'");
    doc = status_doc(st, ID_B);
    assert_string_equal(cJSON_GetObjectItem(doc, "status")->valuestring, "running");
    assert_null(cJSON_GetObjectItem(doc, "result"));
    assert_null(cJSON_GetObjectItem(doc, "problem"));
    cJSON_Delete(doc);
    ljgap_jobstore_close(st);
}

/* A sound finished job's status carries its answer byte for byte, and reads the same after
 * a reopen. */
static void test_status_exact(void **state)
{
    fixture *f = *state;
    ljgap_jobstore *st = open_ok(f->dir);
    cJSON *doc = cJSON_CreateObject();
    char *answer, *s1, *s2;
    ljgap_job_record rec;
    cJSON_AddNumberToObject(doc, "a", 0.1);
    cJSON_AddNumberToObject(doc, "b", 1.0 / 3.0);
    cJSON_AddNumberToObject(doc, "c", -2.5e-300);
    cJSON_AddStringToObject(doc, "d", "caf\xc3\xa9 \"q\" \\ \x01");
    answer = cJSON_PrintUnformatted(doc);
    cJSON_Delete(doc);
    run_to_done(st, ID_A, answer);
    assert_int_equal(ljgap_jobstore_get(st, ID_A, &rec), 0);
    s1 = ljgap_job_status_json(&rec);
    ljgap_job_record_clear(&rec);
    assert_non_null(strstr(s1, answer));
    ljgap_jobstore_close(st);
    st = open_ok(f->dir);
    assert_int_equal(ljgap_jobstore_get(st, ID_A, &rec), 0);
    s2 = ljgap_job_status_json(&rec);
    ljgap_job_record_clear(&rec);
    assert_string_equal(s1, s2);
    free(s1);
    free(s2);
    free(answer);
    ljgap_jobstore_close(st);
}

static void test_rfc3339(void **state)
{
    char buf[40];
    (void)state;
    ljgap_rfc3339(0, buf, sizeof buf);
    assert_string_equal(buf, "1970-01-01T00:00:00.000Z");
    ljgap_rfc3339(1700000000.9996, buf, sizeof buf); /* rounds up into the next second */
    assert_string_equal(buf, "2023-11-14T22:13:21.000Z");
    ljgap_rfc3339(951782400.25, buf, sizeof buf);
    assert_string_equal(buf, "2000-02-29T00:00:00.250Z");
}

int main(void)
{
#define T(f) cmocka_unit_test_setup_teardown(f, setup, teardown)
    const struct CMUnitTest tests[] = {
        T(test_open_creates),
        T(test_life),
        T(test_create_refusals),
        T(test_lease_lapses),
        T(test_cancel),
        T(test_release),
        T(test_evict),
        T(test_reopen),
        T(test_uncreatable),
        T(test_locked),
        T(test_not_a_database),
        T(test_corrupt_page),
        T(test_foreign_database),
        T(test_schema_too_new),
        T(test_unwritable),
        T(test_damaged_rows),
        T(test_status_exact),
        cmocka_unit_test(test_rfc3339),
    };
    return cmocka_run_group_tests_name("jobstore", tests, NULL, NULL);
}
