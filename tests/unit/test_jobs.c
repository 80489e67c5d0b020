/* test_jobs.c -- the daemon's job store (server/jobs.c) with test doubles for the work: a job
 * that answers at once, one that fails, and one that holds its worker until a gate opens or it
 * is cancelled. States, progress, the queue bound, cancel (queued and running), eviction by
 * count and by age, shutdown with work in flight, and that every argument is released once. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <cjson/cJSON.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "jobs.h"

static atomic_int gate;     /* held jobs return when this is nonzero */
static atomic_int freed;    /* arguments released */
static atomic_int started;  /* runs begun */
static atomic_int saw_stop; /* held jobs that returned because of their cancel flag */

static void sleep_ms(int ms)
{
    struct timespec t = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&t, NULL);
}

static void free_arg(void *arg)
{
    free(arg);
    atomic_fetch_add(&freed, 1);
}

static int *new_arg(int v)
{
    int *p = malloc(sizeof *p);
    assert_non_null(p);
    *p = v;
    return p;
}

static void reply(ljgap_reply *out, int status, const char *body)
{
    out->status = status;
    out->body = strdup(body);
    out->len = strlen(body);
    out->content_type = "application/json";
}

/* Answers {"x": arg} at once. */
static void run_fast(void *arg, const ljgap_job_ctl *ctl, ljgap_reply *out)
{
    char buf[64];
    atomic_fetch_add(&started, 1);
    ctl->progress(ctl->ctx, 0.5);
    snprintf(buf, sizeof buf, "{\"x\":%d}", *(int *)arg);
    reply(out, 200, buf);
}

/* Answers a 422 problem. */
static void run_fail(void *arg, const ljgap_job_ctl *ctl, ljgap_reply *out)
{
    (void)arg;
    (void)ctl;
    atomic_fetch_add(&started, 1);
    reply(out, 422, "{\"type\":\"/problems/no-answer\",\"status\":422}");
}

/* Reports progress arg/100 (then a smaller value, to be ignored) and holds its worker until
 * the gate opens (answer 200) or its cancel flag rises (a 503 problem); 10 s at most. */
static void run_held(void *arg, const ljgap_job_ctl *ctl, ljgap_reply *out)
{
    atomic_fetch_add(&started, 1);
    ctl->progress(ctl->ctx, *(int *)arg / 100.0);
    ctl->progress(ctl->ctx, 0.01);
    for (int i = 0; i < 10000 && !atomic_load(&gate) && !*ctl->cancel; i++)
        sleep_ms(1);
    if (*ctl->cancel) {
        atomic_fetch_add(&saw_stop, 1);
        reply(out, 503, "{\"type\":\"/problems/unavailable\"}");
    } else {
        reply(out, 200, "{\"held\":true}");
    }
}

static int setup(void **state)
{
    (void)state;
    atomic_store(&gate, 0);
    atomic_store(&freed, 0);
    atomic_store(&started, 0);
    atomic_store(&saw_stop, 0);
    return 0;
}

static ljgap_jobs *store(unsigned workers, unsigned queue_cap, unsigned keep_done)
{
    ljgap_jobs_config c;
    ljgap_jobs *js;
    ljgap_jobs_config_default(&c);
    c.workers = workers;
    c.queue_cap = queue_cap;
    c.keep_done = keep_done;
    js = ljgap_jobs_alloc(&c);
    assert_non_null(js);
    return js;
}

/* The status object of id (fails the test when unknown). */
static cJSON *status(ljgap_jobs *js, const char *id)
{
    char *s = NULL;
    cJSON *doc;
    assert_int_equal(ljgap_jobs_status(js, id, &s), LJGAP_JOBS_OK);
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

/* Polls id until its status is want (5 s at most); returns the last status object. */
static cJSON *wait_for(ljgap_jobs *js, const char *id, const char *want)
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

static void submit_ok(ljgap_jobs *js, ljgap_job_fn fn, int v, char *id)
{
    assert_int_equal(ljgap_jobs_submit(js, fn, new_arg(v), free_arg, id), LJGAP_JOBS_OK);
    assert_int_equal(strlen(id), LJGAP_JOB_ID_LEN);
    assert_int_equal(strspn(id, "0123456789abcdef"), LJGAP_JOB_ID_LEN);
}

static void test_done_with_result(void **state)
{
    (void)state;
    ljgap_jobs *js = store(1, 8, 8);
    char a[LJGAP_JOB_ID_LEN + 1], b[LJGAP_JOB_ID_LEN + 1];
    cJSON *doc, *res;
    submit_ok(js, run_fast, 7, a);
    submit_ok(js, run_fast, 8, b);
    assert_string_not_equal(a, b);
    doc = wait_for(js, a, "done");
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(doc, "id")->valuestring, a);
    assert_true(num_of(doc, "progress") == 1.0);
    assert_true(num_of(doc, "elapsed_ms") >= 0);
    res = cJSON_GetObjectItemCaseSensitive(doc, "result");
    assert_true(cJSON_IsObject(res));
    assert_true(num_of(res, "x") == 7);
    assert_null(cJSON_GetObjectItemCaseSensitive(doc, "problem"));
    cJSON_Delete(doc);
    cJSON_Delete(wait_for(js, b, "done"));
    ljgap_jobs_free(js);
    assert_int_equal(atomic_load(&freed), 2);
}

static void test_failed_with_problem(void **state)
{
    (void)state;
    ljgap_jobs *js = store(1, 8, 8);
    char a[LJGAP_JOB_ID_LEN + 1];
    cJSON *doc, *p;
    submit_ok(js, run_fail, 0, a);
    doc = wait_for(js, a, "failed");
    p = cJSON_GetObjectItemCaseSensitive(doc, "problem");
    assert_true(cJSON_IsObject(p));
    assert_true(num_of(p, "status") == 422);
    assert_null(cJSON_GetObjectItemCaseSensitive(doc, "result"));
    cJSON_Delete(doc);
    ljgap_jobs_free(js);
    assert_int_equal(atomic_load(&freed), 1);
}

static void test_unknown_id(void **state)
{
    (void)state;
    ljgap_jobs *js = store(1, 8, 8);
    char *s = (char *)"x";
    int final = -1;
    assert_int_equal(ljgap_jobs_status(js, "0123456789abcdef0123456789abcdef", &s),
                     LJGAP_JOBS_UNKNOWN);
    assert_null(s);
    assert_int_equal(ljgap_jobs_cancel(js, "nope", 0.1, &s, &final), LJGAP_JOBS_UNKNOWN);
    assert_null(s);
    ljgap_jobs_free(js);
}

/* One worker held, queue of 2: the third waiting job is refused and its argument released. */
static void test_queue_full(void **state)
{
    (void)state;
    ljgap_jobs *js = store(1, 2, 8);
    char a[LJGAP_JOB_ID_LEN + 1], b[LJGAP_JOB_ID_LEN + 1], c[LJGAP_JOB_ID_LEN + 1];
    char d[LJGAP_JOB_ID_LEN + 1];
    unsigned q, r;
    cJSON *doc;
    submit_ok(js, run_held, 30, a);
    cJSON_Delete(wait_for(js, a, "running"));
    submit_ok(js, run_fast, 1, b);
    submit_ok(js, run_fast, 2, c);
    ljgap_jobs_counts(js, &q, &r);
    assert_int_equal(q, 2);
    assert_int_equal(r, 1);
    assert_int_equal(ljgap_jobs_submit(js, run_fast, new_arg(3), free_arg, d), LJGAP_JOBS_FULL);
    assert_int_equal(d[0], '\0');
    assert_int_equal(atomic_load(&freed), 1);
    doc = status(js, b);
    assert_true(state_is(doc, "queued"));
    assert_true(num_of(doc, "progress") == 0 && num_of(doc, "elapsed_ms") == 0);
    cJSON_Delete(doc);
    atomic_store(&gate, 1);
    cJSON_Delete(wait_for(js, a, "done"));
    cJSON_Delete(wait_for(js, b, "done"));
    cJSON_Delete(wait_for(js, c, "done"));
    ljgap_jobs_free(js);
    assert_int_equal(atomic_load(&freed), 4);
    assert_int_equal(atomic_load(&started), 3);
}

/* Progress from the callback, never decreasing; cancel a running and a queued job. */
static void test_progress_and_cancel(void **state)
{
    (void)state;
    ljgap_jobs *js = store(1, 8, 8);
    char a[LJGAP_JOB_ID_LEN + 1], b[LJGAP_JOB_ID_LEN + 1];
    char *s = NULL;
    int final = -1;
    cJSON *doc;
    submit_ok(js, run_held, 40, a);
    submit_ok(js, run_fast, 5, b);
    doc = wait_for(js, a, "running");
    for (int i = 0; i < 1000 && num_of(doc, "progress") < 0.4; i++) {
        cJSON_Delete(doc);
        sleep_ms(1);
        doc = status(js, a);
    }
    assert_true(num_of(doc, "progress") == 0.4);
    cJSON_Delete(doc);

    /* the queued job is cancelled at once, without running */
    assert_int_equal(ljgap_jobs_cancel(js, b, 0, &s, &final), LJGAP_JOBS_OK);
    assert_int_equal(final, 1);
    doc = cJSON_Parse(s);
    free(s);
    assert_true(state_is(doc, "cancelled"));
    assert_null(cJSON_GetObjectItemCaseSensitive(doc, "result"));
    cJSON_Delete(doc);
    assert_int_equal(atomic_load(&freed), 1);

    /* the running one sees its flag and ends within the wait */
    assert_int_equal(ljgap_jobs_cancel(js, a, 5.0, &s, &final), LJGAP_JOBS_OK);
    assert_int_equal(final, 1);
    doc = cJSON_Parse(s);
    free(s);
    assert_true(state_is(doc, "cancelled"));
    assert_true(cJSON_IsObject(cJSON_GetObjectItemCaseSensitive(doc, "problem")));
    cJSON_Delete(doc);
    assert_int_equal(atomic_load(&saw_stop), 1);
    assert_int_equal(atomic_load(&started), 1);

    /* cancelling a finished job leaves it as it is */
    assert_int_equal(ljgap_jobs_cancel(js, a, 0, &s, &final), LJGAP_JOBS_OK);
    assert_int_equal(final, 1);
    assert_non_null(strstr(s, "\"cancelled\""));
    free(s);
    ljgap_jobs_free(js);
    assert_int_equal(atomic_load(&freed), 2);
}

/* keep_done = 2: after four jobs the two that finished first are gone. */
static void test_evict_oldest_finished(void **state)
{
    (void)state;
    ljgap_jobs *js = store(1, 8, 2);
    char id[4][LJGAP_JOB_ID_LEN + 1];
    char *s = NULL;
    for (int i = 0; i < 4; i++) {
        submit_ok(js, run_fast, i, id[i]);
        cJSON_Delete(wait_for(js, id[i], "done"));
    }
    assert_int_equal(ljgap_jobs_status(js, id[0], &s), LJGAP_JOBS_UNKNOWN);
    assert_int_equal(ljgap_jobs_status(js, id[1], &s), LJGAP_JOBS_UNKNOWN);
    cJSON_Delete(status(js, id[2]));
    cJSON_Delete(status(js, id[3]));
    ljgap_jobs_free(js);
    assert_int_equal(atomic_load(&freed), 4);
}

/* keep_seconds = 0: a finished job is gone at the next look, a running one stays. */
static void test_evict_by_age(void **state)
{
    (void)state;
    ljgap_jobs_config c;
    ljgap_jobs *js;
    char a[LJGAP_JOB_ID_LEN + 1], b[LJGAP_JOB_ID_LEN + 1];
    char *s = NULL;
    unsigned q = 9, r = 9;
    ljgap_jobs_config_default(&c);
    c.keep_seconds = 0;
    js = ljgap_jobs_alloc(&c);
    assert_non_null(js);
    submit_ok(js, run_held, 10, a);
    cJSON_Delete(wait_for(js, a, "running"));
    sleep_ms(5);
    cJSON_Delete(status(js, a)); /* running: kept however old */
    atomic_store(&gate, 1);
    for (int i = 0; i < 5000 && (q || r); i++) {
        sleep_ms(1);
        ljgap_jobs_counts(js, &q, &r);
    }
    sleep_ms(2);
    assert_int_equal(ljgap_jobs_status(js, a, &s), LJGAP_JOBS_UNKNOWN);
    submit_ok(js, run_fast, 1, b);
    ljgap_jobs_free(js);
    assert_int_equal(atomic_load(&freed), 2);
}

/* Shutdown with one job running and two queued: the running one is cancelled, the queued ones
 * never run, new jobs are refused, free joins and releases everything. */
static void test_shutdown_in_flight(void **state)
{
    (void)state;
    ljgap_jobs *js = store(2, 8, 8);
    char a[LJGAP_JOB_ID_LEN + 1], b[LJGAP_JOB_ID_LEN + 1], c[LJGAP_JOB_ID_LEN + 1];
    char d[LJGAP_JOB_ID_LEN + 1], e[LJGAP_JOB_ID_LEN + 1];
    cJSON *doc;
    submit_ok(js, run_held, 10, a);
    submit_ok(js, run_held, 20, b);
    cJSON_Delete(wait_for(js, a, "running"));
    cJSON_Delete(wait_for(js, b, "running"));
    submit_ok(js, run_fast, 1, c);
    submit_ok(js, run_fast, 2, d);
    ljgap_jobs_shutdown(js);
    assert_int_equal(ljgap_jobs_submit(js, run_fast, new_arg(3), free_arg, e), LJGAP_JOBS_STOPPING);
    doc = status(js, c);
    assert_true(state_is(doc, "cancelled"));
    cJSON_Delete(doc);
    assert_int_equal(ljgap_jobs_wait_idle(js, 5.0), 1);
    cJSON_Delete(wait_for(js, a, "cancelled"));
    ljgap_jobs_free(js);
    assert_int_equal(atomic_load(&saw_stop), 2);
    assert_int_equal(atomic_load(&started), 2);
    assert_int_equal(atomic_load(&freed), 5);
    ljgap_jobs_free(NULL);
}

static void test_bad_config(void **state)
{
    (void)state;
    ljgap_jobs_config c;
    ljgap_jobs_config_default(&c);
    assert_int_equal(c.workers, 1);
    c.workers = 0;
    assert_null(ljgap_jobs_alloc(&c));
    ljgap_jobs_config_default(&c);
    c.queue_cap = 0;
    assert_null(ljgap_jobs_alloc(&c));
    assert_null(ljgap_jobs_alloc(NULL));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_done_with_result, setup),
        cmocka_unit_test_setup(test_failed_with_problem, setup),
        cmocka_unit_test_setup(test_unknown_id, setup),
        cmocka_unit_test_setup(test_queue_full, setup),
        cmocka_unit_test_setup(test_progress_and_cancel, setup),
        cmocka_unit_test_setup(test_evict_oldest_finished, setup),
        cmocka_unit_test_setup(test_evict_by_age, setup),
        cmocka_unit_test_setup(test_shutdown_in_flight, setup),
        cmocka_unit_test_setup(test_bad_config, setup),
    };
    return cmocka_run_group_tests_name("jobs", tests, NULL, NULL);
}
