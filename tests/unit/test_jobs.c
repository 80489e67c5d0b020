/* test_jobs.c -- the daemon's job runner (server/jobs/jobs.c) on a real SQLite store in a temporary
 * directory, with test doubles for the work: a kind that answers at once (its body is a
 * number), one that fails, and one that holds its worker until a gate opens or it is
 * cancelled. States, progress, the queue bound, cancel (queued, running here, and asked
 * through the store as another daemon would), eviction by count and by age, shutdown that
 * puts running jobs back, a restart that runs them under the same ids and shows finished ones
 * byte for byte, and stored rows the runner cannot run (a body that does not parse, an
 * unknown kind, a job whose runs were lost too often). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "statedir.h"

#include <cjson/cJSON.h>
#include <stdatomic.h>

#include "jobs.h"

static atomic_int gate;     /* held jobs return when this is nonzero */
static atomic_int started;  /* runs begun */
static atomic_int saw_stop; /* held jobs that returned because of their cancel flag */

static void reply(ljgap__reply *out, int status, const char *body)
{
    out->status = status;
    out->body = strdup(body);
    out->len = strlen(body);
    out->content_type = "application/json";
}

/* Answers a problem of type slug with that status. */
static void reply_problem(ljgap__reply *out, int status, const char *slug)
{
    char buf[200];
    snprintf(buf, sizeof buf,
             "{\"type\":\"/problems/%s\",\"title\":\"t\",\"status\":%d,"
             "\"detail\":\"d\",\"errors\":[]}",
             slug, status);
    reply(out, status, buf);
    out->content_type = "application/problem+json";
}

/* Answers {"x": N} at once for the body "N"; 400 for a body that is not a number. */
static void run_fast(void *ctx, const char *body, size_t len, const ljgap__job_ctl *ctl,
                     ljgap__reply *out)
{
    char buf[64], *end = NULL;
    long v = strtol(body, &end, 10);
    (void)ctx;
    atomic_fetch_add(&started, 1);
    ctl->progress(ctl->ctx, 0.5);
    if (len == 0 || end != body + len) {
        reply_problem(out, 400, "malformed-json");
        return;
    }
    snprintf(buf, sizeof buf, "{\"x\":%ld}", v);
    reply(out, 200, buf);
}

/* Answers a 422 problem. */
static void run_fail(void *ctx, const char *body, size_t len, const ljgap__job_ctl *ctl,
                     ljgap__reply *out)
{
    (void)ctx, (void)body, (void)len, (void)ctl;
    atomic_fetch_add(&started, 1);
    reply_problem(out, 422, "no-answer");
}

/* Reports progress N/100 for the body "N" (then a smaller value, to be ignored) and holds its
 * worker until the gate opens (answer 200) or its cancel flag rises (a 503 problem); 10 s at
 * most. */
static void run_held(void *ctx, const char *body, size_t len, const ljgap__job_ctl *ctl,
                     ljgap__reply *out)
{
    (void)ctx, (void)len;
    atomic_fetch_add(&started, 1);
    ctl->progress(ctl->ctx, atoi(body) / 100.0);
    ctl->progress(ctl->ctx, 0.01);
    for (int i = 0; i < 10000 && !atomic_load(&gate) && !*ctl->cancel; i++)
        sleep_ms(1);
    if (*ctl->cancel) {
        atomic_fetch_add(&saw_stop, 1);
        reply_problem(out, 503, "unavailable");
    } else {
        reply(out, 200, "{\"held\":true}");
    }
}

static const ljgap__job_kind kinds[] = {
    {"fast", run_fast, NULL},
    {"fail", run_fail, NULL},
    {"held", run_held, NULL},
};
#define NKINDS (sizeof kinds / sizeof kinds[0])

typedef struct {
    char root[STATEDIR_LEN];
    ljgap__jobstore *store;
} fixture;

static ljgap__jobstore *open_store(const char *root)
{
    ljgap__jobstore *st = NULL;
    char err[600];
    if (ljgap__jobstore_open_sqlite(root, &st, err, sizeof err) != LJGAP_JOBSTORE_OK)
        print_error("%s\n", err);
    assert_non_null(st);
    return st;
}

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    assert_non_null(f);
    statedir_make(f->root);
    f->store = open_store(f->root);
    atomic_store(&gate, 0);
    atomic_store(&started, 0);
    atomic_store(&saw_stop, 0);
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    ljgap__jobstore_close(f->store);
    statedir_remove(f->root);
    free(f);
    return 0;
}

static void config(ljgap__jobs_config *c, unsigned workers, unsigned queue_cap, unsigned keep)
{
    ljgap__jobs_config_default(c);
    c->workers = workers;
    c->queue_cap = queue_cap;
    c->keep_done = keep;
    c->progress_seconds = 0.02;
    c->poll_seconds = 0.05;
}

static ljgap__jobs *runner_cfg(fixture *f, const ljgap__jobs_config *c)
{
    ljgap__jobs *js = ljgap__jobs_alloc(c, f->store, kinds, NKINDS);
    assert_non_null(js);
    return js;
}

static ljgap__jobs *runner(fixture *f, unsigned workers, unsigned queue_cap, unsigned keep)
{
    ljgap__jobs_config c;
    config(&c, workers, queue_cap, keep);
    return runner_cfg(f, &c);
}

/* The status object of id (fails the test when unknown). */
static cJSON *status(ljgap__jobs *js, const char *id)
{
    char *s = NULL;
    cJSON *doc;
    assert_int_equal(ljgap__jobs_status(js, id, &s), LJGAP_JOBS_OK);
    doc = cJSON_Parse(s);
    if (!doc) print_error("not JSON: %s\n", s);
    assert_non_null(doc);
    free(s);
    return doc;
}

static int state_is(const cJSON *doc, const char *want)
{
    const cJSON *st = cJSON_GetObjectItemCaseSensitive(doc, "status");
    return cJSON_IsString(st) && strcmp(st->valuestring, want) == 0;
}

static double num_of(const cJSON *doc, const char *key)
{
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(doc, key);
    assert_true(cJSON_IsNumber(it));
    return it->valuedouble;
}

static const char *type_of(const cJSON *doc)
{
    const cJSON *t = cJSON_GetObjectItem(cJSON_GetObjectItem(doc, "problem"), "type");
    return cJSON_IsString(t) ? t->valuestring : "";
}

/* Polls id until its status is want (5 s at most); returns the last status object. */
static cJSON *wait_for(ljgap__jobs *js, const char *id, const char *want)
{
    for (int i = 0; i < 5000; i++) {
        cJSON *doc = status(js, id);
        if (state_is(doc, want)) return doc;
        cJSON_Delete(doc);
        sleep_ms(1);
    }
    print_error("job %s never reached %s\n", id, want);
    fail();
    return NULL;
}

static void submit_ok(ljgap__jobs *js, const char *kind, const char *body, char *id)
{
    assert_int_equal(ljgap__jobs_submit(js, kind, body, strlen(body), id), LJGAP_JOBS_OK);
    assert_int_equal(strlen(id), LJGAP_JOB_ID_LEN);
    assert_int_equal(strspn(id, "0123456789abcdef"), LJGAP_JOB_ID_LEN);
}

static void test_done_with_result(void **state)
{
    fixture *f = *state;
    ljgap__jobs *js = runner(f, 1, 8, 8);
    char a[LJGAP_JOB_ID_LEN + 1], b[LJGAP_JOB_ID_LEN + 1];
    cJSON *doc, *res;
    submit_ok(js, "fast", "7", a);
    submit_ok(js, "fast", "8", b);
    assert_string_not_equal(a, b);
    doc = wait_for(js, a, "done");
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(doc, "id")->valuestring, a);
    assert_true(num_of(doc, "progress") == 1.0);
    assert_true(num_of(doc, "elapsed_ms") >= 0);
    for (const char *const *k = (const char *const[]){"created", "started", "finished", NULL}; *k;
         k++) {
        const cJSON *t = cJSON_GetObjectItem(doc, *k);
        assert_true(cJSON_IsString(t) && strlen(t->valuestring) == 24 && t->valuestring[23] == 'Z');
    }
    res = cJSON_GetObjectItemCaseSensitive(doc, "result");
    assert_true(cJSON_IsObject(res));
    assert_true(num_of(res, "x") == 7);
    assert_null(cJSON_GetObjectItemCaseSensitive(doc, "problem"));
    cJSON_Delete(doc);
    cJSON_Delete(wait_for(js, b, "done"));
    ljgap__jobs_free(js);
    assert_int_equal(atomic_load(&started), 2);
}

static void test_failed_with_problem(void **state)
{
    fixture *f = *state;
    ljgap__jobs *js = runner(f, 1, 8, 8);
    char a[LJGAP_JOB_ID_LEN + 1];
    cJSON *doc, *p;
    submit_ok(js, "fail", "", a);
    doc = wait_for(js, a, "failed");
    p = cJSON_GetObjectItemCaseSensitive(doc, "problem");
    assert_true(cJSON_IsObject(p));
    assert_true(num_of(p, "status") == 422);
    assert_null(cJSON_GetObjectItemCaseSensitive(doc, "result"));
    cJSON_Delete(doc);
    ljgap__jobs_free(js);
}

static void test_unknown(void **state)
{
    fixture *f = *state;
    ljgap__jobs *js = runner(f, 1, 8, 8);
    char *s = (char *)"x", id[LJGAP_JOB_ID_LEN + 1];
    int final = -1;
    assert_int_equal(ljgap__jobs_status(js, "0123456789abcdef0123456789abcdef", &s),
                     LJGAP_JOBS_UNKNOWN);
    assert_null(s);
    assert_int_equal(ljgap__jobs_cancel(js, "nope", 0.1, &s, &final), LJGAP_JOBS_UNKNOWN);
    assert_null(s);
    assert_int_equal(ljgap__jobs_submit(js, "nosuchkind", "1", 1, id), LJGAP_JOBS_STORE);
    assert_string_equal(id, "");
    ljgap__jobs_free(js);
}

/* One worker held, queue of 2: the third waiting job is refused. */
static void test_queue_full(void **state)
{
    fixture *f = *state;
    ljgap__jobs *js = runner(f, 1, 2, 8);
    char a[LJGAP_JOB_ID_LEN + 1], b[LJGAP_JOB_ID_LEN + 1], c[LJGAP_JOB_ID_LEN + 1];
    char d[LJGAP_JOB_ID_LEN + 1];
    unsigned q, r;
    cJSON *doc;
    submit_ok(js, "held", "30", a);
    cJSON_Delete(wait_for(js, a, "running"));
    submit_ok(js, "fast", "1", b);
    submit_ok(js, "fast", "2", c);
    assert_int_equal(ljgap__jobs_counts(js, &q, &r), LJGAP_JOBS_OK);
    assert_int_equal(q, 2);
    assert_int_equal(r, 1);
    assert_int_equal(ljgap__jobs_submit(js, "fast", "3", 1, d), LJGAP_JOBS_FULL);
    assert_int_equal(d[0], '\0');
    doc = status(js, b);
    assert_true(state_is(doc, "queued"));
    assert_true(num_of(doc, "progress") == 0 && num_of(doc, "elapsed_ms") == 0);
    assert_null(cJSON_GetObjectItem(doc, "started"));
    cJSON_Delete(doc);
    atomic_store(&gate, 1);
    cJSON_Delete(wait_for(js, a, "done"));
    cJSON_Delete(wait_for(js, b, "done"));
    cJSON_Delete(wait_for(js, c, "done"));
    ljgap__jobs_free(js);
    assert_int_equal(atomic_load(&started), 3);
}

/* Progress reaches the store, never decreasing; cancel a queued and a running job. */
static void test_progress_and_cancel(void **state)
{
    fixture *f = *state;
    ljgap__jobs *js = runner(f, 1, 8, 8);
    char a[LJGAP_JOB_ID_LEN + 1], b[LJGAP_JOB_ID_LEN + 1];
    char *s = NULL;
    int final = -1;
    cJSON *doc;
    submit_ok(js, "held", "40", a);
    submit_ok(js, "fast", "5", b);
    doc = wait_for(js, a, "running");
    for (int i = 0; i < 2000 && num_of(doc, "progress") < 0.4; i++) {
        cJSON_Delete(doc);
        sleep_ms(1);
        doc = status(js, a);
    }
    assert_true(num_of(doc, "progress") == 0.4);
    assert_non_null(cJSON_GetObjectItem(doc, "started"));
    assert_null(cJSON_GetObjectItem(doc, "finished"));
    cJSON_Delete(doc);

    /* the queued job is cancelled at once, without running */
    assert_int_equal(ljgap__jobs_cancel(js, b, 0, &s, &final), LJGAP_JOBS_OK);
    assert_int_equal(final, 1);
    doc = cJSON_Parse(s);
    free(s);
    assert_true(state_is(doc, "cancelled"));
    assert_null(cJSON_GetObjectItemCaseSensitive(doc, "result"));
    assert_true(num_of(doc, "elapsed_ms") == 0);
    cJSON_Delete(doc);

    /* the running one sees its flag at once and ends within the wait */
    assert_int_equal(ljgap__jobs_cancel(js, a, 5.0, &s, &final), LJGAP_JOBS_OK);
    assert_int_equal(final, 1);
    doc = cJSON_Parse(s);
    free(s);
    assert_true(state_is(doc, "cancelled"));
    assert_non_null(strstr(type_of(doc), "/unavailable"));
    cJSON_Delete(doc);
    assert_int_equal(atomic_load(&saw_stop), 1);
    assert_int_equal(atomic_load(&started), 1);

    /* cancelling a finished job leaves it as it is */
    assert_int_equal(ljgap__jobs_cancel(js, a, 0, &s, &final), LJGAP_JOBS_OK);
    assert_int_equal(final, 1);
    assert_non_null(strstr(s, "\"cancelled\""));
    free(s);
    ljgap__jobs_free(js);
}

/* A cancel written to the store (as another daemon sharing it would) reaches the worker at its
 * next lease renewal. */
static void test_cancel_through_store(void **state)
{
    fixture *f = *state;
    ljgap__jobs_config c;
    ljgap__jobs *js;
    char a[LJGAP_JOB_ID_LEN + 1], sql[200];
    cJSON *doc;
    config(&c, 1, 8, 8);
    c.lease_seconds = 0.3; /* renewed every 0.1 s */
    js = runner_cfg(f, &c);
    submit_ok(js, "held", "10", a);
    cJSON_Delete(wait_for(js, a, "running"));
    snprintf(sql, sizeof sql, "UPDATE jobs SET cancel = 1 WHERE id = '%s'", a);
    statedir_sql(f->root, sql);
    doc = wait_for(js, a, "cancelled");
    assert_non_null(strstr(type_of(doc), "/unavailable"));
    cJSON_Delete(doc);
    assert_int_equal(atomic_load(&saw_stop), 1);
    ljgap__jobs_free(js);
}

/* keep_done = 2: after four jobs the two that finished first are gone. */
static void test_evict_oldest_finished(void **state)
{
    fixture *f = *state;
    ljgap__jobs *js = runner(f, 1, 8, 2);
    char id[4][LJGAP_JOB_ID_LEN + 1];
    char *s = NULL;
    for (int i = 0; i < 4; i++) {
        submit_ok(js, "fast", "1", id[i]);
        cJSON_Delete(wait_for(js, id[i], "done"));
    }
    ljgap__jobs_free(js); /* the worker evicts after each finish: wait until it has */
    js = runner(f, 1, 8, 2);
    assert_int_equal(ljgap__jobs_status(js, id[0], &s), LJGAP_JOBS_UNKNOWN);
    assert_int_equal(ljgap__jobs_status(js, id[1], &s), LJGAP_JOBS_UNKNOWN);
    cJSON_Delete(status(js, id[2]));
    cJSON_Delete(status(js, id[3]));
    ljgap__jobs_free(js);
}

/* keep_seconds = 0: a finished job is gone at the next look, a running one stays. */
static void test_evict_by_age(void **state)
{
    fixture *f = *state;
    ljgap__jobs_config c;
    ljgap__jobs *js;
    char a[LJGAP_JOB_ID_LEN + 1];
    char *s = NULL;
    config(&c, 1, 8, 8);
    c.keep_seconds = 0;
    js = runner_cfg(f, &c);
    submit_ok(js, "held", "10", a);
    cJSON_Delete(wait_for(js, a, "running"));
    sleep_ms(5);
    cJSON_Delete(status(js, a)); /* running: kept however old */
    atomic_store(&gate, 1);
    for (int i = 0; i < 5000 && ljgap__jobs_wait_idle(js, 0) == 0; i++)
        sleep_ms(1);
    sleep_ms(2);
    assert_int_equal(ljgap__jobs_status(js, a, &s), LJGAP_JOBS_UNKNOWN);
    ljgap__jobs_free(js);
}

/* Shutdown with two jobs running and two queued: the running ones stop and go back to the
 * queue, the queued ones stay, new jobs are refused; a new runner on the store (a restart)
 * runs all four under their ids. A finished job reads the same across the restart. */
static void test_shutdown_and_restart(void **state)
{
    fixture *f = *state;
    ljgap__jobs *js = runner(f, 2, 8, 8);
    char id[5][LJGAP_JOB_ID_LEN + 1], e[LJGAP_JOB_ID_LEN + 1];
    char *before = NULL, *after = NULL;
    cJSON *doc;
    submit_ok(js, "fast", "3", id[4]);
    cJSON_Delete(wait_for(js, id[4], "done"));
    assert_int_equal(ljgap__jobs_status(js, id[4], &before), LJGAP_JOBS_OK);
    submit_ok(js, "held", "10", id[0]);
    submit_ok(js, "held", "20", id[1]);
    cJSON_Delete(wait_for(js, id[0], "running"));
    cJSON_Delete(wait_for(js, id[1], "running"));
    submit_ok(js, "fast", "1", id[2]);
    submit_ok(js, "fast", "2", id[3]);
    ljgap__jobs_shutdown(js);
    assert_int_equal(ljgap__jobs_submit(js, "fast", "3", 1, e), LJGAP_JOBS_STOPPING);
    assert_int_equal(ljgap__jobs_wait_idle(js, 5.0), 1);
    ljgap__jobs_free(js);
    assert_int_equal(atomic_load(&saw_stop), 2);
    for (int i = 0; i < 4; i++) { /* all four wait in the store */
        ljgap__job_record rec;
        assert_int_equal(ljgap__jobstore_get(f->store, id[i], &rec), LJGAP_JOBSTORE_OK);
        assert_int_equal(rec.state, LJGAP_JOB_QUEUED);
        ljgap__job_record_clear(&rec);
    }
    atomic_store(&gate, 1);
    ljgap__jobstore_close(f->store); /* a restart: the store too */
    f->store = open_store(f->root);
    js = runner(f, 2, 8, 8);
    for (int i = 0; i < 4; i++) {
        doc = wait_for(js, id[i], "done");
        if (i < 2)
            assert_true(
                cJSON_IsTrue(cJSON_GetObjectItem(cJSON_GetObjectItem(doc, "result"), "held")));
        else
            assert_true(num_of(cJSON_GetObjectItem(doc, "result"), "x") == i - 1);
        cJSON_Delete(doc);
    }
    assert_int_equal(ljgap__jobs_status(js, id[4], &after), LJGAP_JOBS_OK);
    assert_string_equal(before, after);
    free(before);
    free(after);
    ljgap__jobs_free(js);
}

/* Rows the runner cannot run end failed with a problem that says why. */
static void test_unrunnable_rows(void **state)
{
    fixture *f = *state;
    const char bad_body[] = "00000000000000000000000000000001";
    const char bad_kind[] = "00000000000000000000000000000002";
    const char lost[] = "00000000000000000000000000000003";
    ljgap__job_record rec;
    ljgap__jobs *js;
    cJSON *doc;
    /* a job whose daemon died three times while running it (the oldest: claimed first) */
    assert_int_equal(ljgap__jobstore_create(f->store, lost, "fast", "12", 2, 0), 0);
    for (int i = 0; i < 3; i++) {
        assert_int_equal(ljgap__jobstore_claim(f->store, "t", 30, &rec), LJGAP_JOBSTORE_OK);
        assert_string_equal(rec.id, lost);
        ljgap__job_record_clear(&rec);
        ljgap__jobstore_close(f->store); /* with the job running: a crash */
        f->store = open_store(f->root);
    }
    /* written to the store, then damaged behind its back */
    assert_int_equal(ljgap__jobstore_create(f->store, bad_body, "fast", "12", 2, 0), 0);
    assert_int_equal(ljgap__jobstore_create(f->store, bad_kind, "fast", "12", 2, 0), 0);
    statedir_sql(f->root, "UPDATE jobs SET request = x'ff00' WHERE id = "
                          "'00000000000000000000000000000001';"
                          "UPDATE jobs SET kind = 'nosuch' WHERE id = "
                          "'00000000000000000000000000000002'");
    js = runner(f, 1, 8, 8);
    doc = wait_for(js, bad_body, "failed");
    assert_true(num_of(cJSON_GetObjectItem(doc, "problem"), "status") == 400);
    cJSON_Delete(doc);
    doc = wait_for(js, bad_kind, "failed");
    assert_non_null(strstr(type_of(doc), "/job-damaged"));
    assert_non_null(strstr(
        cJSON_GetObjectItem(cJSON_GetObjectItem(doc, "problem"), "detail")->valuestring, "nosuch"));
    cJSON_Delete(doc);
    doc = wait_for(js, lost, "failed");
    assert_non_null(strstr(type_of(doc), "/job-abandoned"));
    cJSON_Delete(doc);
    ljgap__jobs_free(js);
    assert_int_equal(atomic_load(&started), 1); /* only the one with the bad body ran */
}

static void test_bad_config(void **state)
{
    fixture *f = *state;
    ljgap__jobs_config c;
    const ljgap__job_kind bad[] = {{"Bad Name", run_fast, NULL}};
    ljgap__jobs_config_default(&c);
    assert_int_equal(c.workers, 1);
    c.workers = 0;
    assert_null(ljgap__jobs_alloc(&c, f->store, kinds, NKINDS));
    ljgap__jobs_config_default(&c);
    c.queue_cap = 0;
    assert_null(ljgap__jobs_alloc(&c, f->store, kinds, NKINDS));
    ljgap__jobs_config_default(&c);
    c.lease_seconds = 0;
    assert_null(ljgap__jobs_alloc(&c, f->store, kinds, NKINDS));
    ljgap__jobs_config_default(&c);
    assert_null(ljgap__jobs_alloc(NULL, f->store, kinds, NKINDS));
    assert_null(ljgap__jobs_alloc(&c, NULL, kinds, NKINDS));
    assert_null(ljgap__jobs_alloc(&c, f->store, kinds, 0));
    assert_null(ljgap__jobs_alloc(&c, f->store, bad, 1));
    ljgap__jobs_free(NULL);
}

int main(void)
{
#define T(f) cmocka_unit_test_setup_teardown(f, setup, teardown)
    const struct CMUnitTest tests[] = {
        T(test_done_with_result),
        T(test_failed_with_problem),
        T(test_unknown),
        T(test_queue_full),
        T(test_progress_and_cancel),
        T(test_cancel_through_store),
        T(test_evict_oldest_finished),
        T(test_evict_by_age),
        T(test_shutdown_and_restart),
        T(test_unrunnable_rows),
        T(test_bad_config),
    };
    return cmocka_run_group_tests_name("jobs", tests, NULL, NULL);
}
