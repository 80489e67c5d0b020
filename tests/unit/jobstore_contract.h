/* jobstore_contract.h -- the job store's contract (jobstore.h), as cmocka cases that any backend
 * must pass: the life of a job (create, claim, renew, finish, release, cancel), FIFO order, the
 * queue cap, leases that lapse, eviction by count and by age, damaged rows read back (shown as
 * failed jobs with valid JSON), and a finished job's status byte for byte across a reopen.
 * Included by the tests of each backend (tests/unit/test_jobstore.c: SQLite;
 * tests/scaleout/test_jobstore_pg.c: PostgreSQL), after cmocka.h, which define first:
 *   static ljgap__jobstore *contract_open(void **state);      open the store under test
 *   static void contract_sql(void **state, const char *sql); run SQL behind its back, checks
 *                                                            off (rows it would refuse too)
 *   CONTRACT_TABLE         the jobs table's name in that SQL
 *   contract_damages[]     SET clauses that damage a finished row (state, answer)
 *   CONTRACT_ODD_NUMBERS   a SET clause: progress above 1, a negative created, a started
 *                          that is no time, a finished before it (a sound answer stays shown)
 *   CONTRACT_RUNNING_JUNK  a SET clause: a running row's progress out of range, junk answer
 *   CONTRACT_TESTS(T)      (defined here) the cases, each wrapped in T
 */
#ifndef LJGAP_TEST_JOBSTORE_CONTRACT_H
#define LJGAP_TEST_JOBSTORE_CONTRACT_H

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "jobstatus.h"
#include "jobstore.h"
#include "textbuf.h" /* ljgap__utf8_span */

#define ID_A "00000000000000000000000000000001"
#define ID_B "00000000000000000000000000000002"
#define ID_C "00000000000000000000000000000003"
#define ID_D "00000000000000000000000000000004"

static void create_ok(ljgap__jobstore *st, const char *id, const char *body)
{
    assert_int_equal(ljgap__jobstore_create(st, id, "simulation", body, strlen(body), 0),
                     LJGAP_JOBSTORE_OK);
}

static ljgap__job_state state_of(ljgap__jobstore *st, const char *id)
{
    ljgap__job_record rec;
    ljgap__job_state s;
    assert_int_equal(ljgap__jobstore_get(st, id, &rec), LJGAP_JOBSTORE_OK);
    s = rec.state;
    ljgap__job_record_clear(&rec);
    return s;
}

/* claims the next job, which must be id; returns its run */
static long claim_ok(ljgap__jobstore *st, const char *id, double lease)
{
    ljgap__job_record rec;
    long run;
    assert_int_equal(ljgap__jobstore_claim(st, "test:1", lease, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, id);
    assert_int_equal(rec.state, LJGAP_JOB_RUNNING);
    run = rec.run;
    ljgap__job_record_clear(&rec);
    return run;
}

/* create, get, claim (FIFO, with the request as sent), renew, finish; counts throughout */
static void test_life(void **state)
{
    ljgap__jobstore *st = contract_open(state);
    static const char body[] = "{\"a\":1}\0tail"; /* bytes after a NUL come back too */
    ljgap__job_record rec;
    unsigned q, r;
    int cancel = 7;
    long run;
    double t0 = ljgap__jobstore_wallclock();

    assert_int_equal(ljgap__jobstore_create(st, ID_A, "simulation", body, sizeof body - 1, 0),
                     LJGAP_JOBSTORE_OK);
    create_ok(st, ID_B, "{}");
    assert_int_equal(ljgap__jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, ID_A);
    assert_string_equal(rec.kind, "simulation");
    assert_int_equal(rec.state, LJGAP_JOB_QUEUED);
    assert_true(rec.progress == 0 && rec.started == 0 && rec.finished == 0);
    assert_true(fabs(rec.created - t0) < 5 && rec.now >= rec.created);
    assert_null(rec.answer);
    assert_null(rec.request); /* get does not read the request */
    ljgap__job_record_clear(&rec);
    assert_int_equal(ljgap__jobstore_counts(st, &q, &r), LJGAP_JOBSTORE_OK);
    assert_true(q == 2 && r == 0);

    assert_int_equal(ljgap__jobstore_claim(st, "test:1", 30, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, ID_A); /* the oldest first */
    assert_int_equal(rec.request_len, sizeof body - 1);
    assert_memory_equal(rec.request, body, sizeof body - 1);
    assert_true(rec.run == 1 && rec.lost == 0 && rec.cancel == 0 && rec.started >= rec.created);
    run = rec.run;
    ljgap__job_record_clear(&rec);
    assert_int_equal(ljgap__jobstore_counts(st, &q, &r), LJGAP_JOBSTORE_OK);
    assert_true(q == 1 && r == 1);

    assert_int_equal(ljgap__jobstore_renew(st, ID_A, run, 0.4, 30, &cancel), LJGAP_JOBSTORE_OK);
    assert_int_equal(cancel, 0);
    assert_int_equal(ljgap__jobstore_renew(st, ID_A, run, 0.2, 30, &cancel), LJGAP_JOBSTORE_OK);
    assert_int_equal(ljgap__jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_true(rec.progress == 0.4); /* never lowered */
    assert_int_equal(rec.state, LJGAP_JOB_RUNNING);
    ljgap__job_record_clear(&rec);

    assert_int_equal(ljgap__jobstore_finish(st, ID_A, run, LJGAP_JOB_DONE, "{\"x\":1}", 7),
                     LJGAP_JOBSTORE_OK);
    assert_int_equal(ljgap__jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_int_equal(rec.state, LJGAP_JOB_DONE);
    assert_true(rec.progress == 1 && rec.finished >= rec.started && rec.started > 0);
    assert_string_equal(rec.answer, "{\"x\":1}");
    assert_int_equal(rec.answer_len, 7);
    ljgap__job_record_clear(&rec);
    /* a finished claim cannot be finished, renewed or released again */
    assert_int_equal(ljgap__jobstore_finish(st, ID_A, run, LJGAP_JOB_FAILED, NULL, 0),
                     LJGAP_JOBSTORE_LOST);
    assert_int_equal(ljgap__jobstore_renew(st, ID_A, run, 0.5, 30, &cancel), LJGAP_JOBSTORE_LOST);
    assert_int_equal(ljgap__jobstore_release(st, ID_A, run), LJGAP_JOBSTORE_LOST);

    run = claim_ok(st, ID_B, 30);
    assert_int_equal(ljgap__jobstore_claim(st, "test:1", 30, &rec), LJGAP_JOBSTORE_EMPTY);
    assert_int_equal(ljgap__jobstore_finish(st, ID_B, run, LJGAP_JOB_FAILED, "{\"status\":422}", 14),
                     LJGAP_JOBSTORE_OK);
    assert_int_equal(state_of(st, ID_B), LJGAP_JOB_FAILED);
    assert_int_equal(ljgap__jobstore_counts(st, &q, &r), LJGAP_JOBSTORE_OK);
    assert_true(q == 0 && r == 0);
    ljgap__jobstore_close(st);
}

static void test_create_refusals(void **state)
{
    ljgap__jobstore *st = contract_open(state);
    ljgap__job_record rec;
    int cancel;
    assert_int_equal(ljgap__jobstore_create(st, ID_A, "simulation", "{}", 2, 2), 0);
    assert_int_equal(ljgap__jobstore_create(st, ID_B, "simulation", "{}", 2, 2), 0);
    assert_int_equal(ljgap__jobstore_create(st, ID_C, "simulation", "{}", 2, 2),
                     LJGAP_JOBSTORE_FULL);
    assert_int_equal(ljgap__jobstore_get(st, ID_C, &rec), LJGAP_JOBSTORE_UNKNOWN);
    assert_int_equal(ljgap__jobstore_create(st, ID_C, "simulation", "{}", 2, 0), 0); /* no cap */
    assert_int_equal(ljgap__jobstore_create(st, ID_A, "simulation", "{}", 2, 0),
                     LJGAP_JOBSTORE_EXISTS);
    assert_int_equal(ljgap__jobstore_create(st, "0123", "simulation", "{}", 2, 0),
                     LJGAP_JOBSTORE_INVALID);
    assert_int_equal(
        ljgap__jobstore_create(st, "0000000000000000000000000000000G", "simulation", "{}", 2, 0),
        LJGAP_JOBSTORE_INVALID);
    assert_int_equal(ljgap__jobstore_create(st, ID_D, "Sim", "{}", 2, 0), LJGAP_JOBSTORE_INVALID);
    assert_int_equal(ljgap__jobstore_create(st, ID_D, "", "{}", 2, 0), LJGAP_JOBSTORE_INVALID);
    assert_non_null(strstr(ljgap__jobstore_errmsg(), "kind"));
    assert_int_equal(ljgap__jobstore_claim(st, "t", 0, &rec), LJGAP_JOBSTORE_INVALID);
    assert_int_equal(ljgap__jobstore_renew(st, "x", 1, 0, 30, &cancel), LJGAP_JOBSTORE_INVALID);
    assert_int_equal(ljgap__jobstore_finish(st, ID_A, 1, LJGAP_JOB_RUNNING, NULL, 0),
                     LJGAP_JOBSTORE_INVALID);
    assert_int_equal(ljgap__jobstore_get(st, "../etc", &rec), LJGAP_JOBSTORE_UNKNOWN);
    assert_int_equal(ljgap__jobstore_get(st, ID_D, &rec), LJGAP_JOBSTORE_UNKNOWN);
    ljgap__jobstore_close(st);
}

/* A lease that lapses: the job is claimed again (run + 1, lost + 1) and the first claim is
 * LOST for every write. */
static void test_lease_lapses(void **state)
{
    ljgap__jobstore *st = contract_open(state);
    ljgap__job_record rec;
    int cancel;
    long run1, run2;
    create_ok(st, ID_A, "{}");
    run1 = claim_ok(st, ID_A, 0.05);
    assert_int_equal(ljgap__jobstore_claim(st, "test:2", 30, &rec), LJGAP_JOBSTORE_EMPTY);
    sleep_ms(100);
    assert_int_equal(ljgap__jobstore_claim(st, "test:2", 30, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, ID_A);
    assert_int_equal(rec.run, run1 + 1);
    assert_int_equal(rec.lost, 1);
    run2 = rec.run;
    ljgap__job_record_clear(&rec);
    assert_int_equal(ljgap__jobstore_renew(st, ID_A, run1, 0.9, 30, &cancel), LJGAP_JOBSTORE_LOST);
    assert_int_equal(ljgap__jobstore_finish(st, ID_A, run1, LJGAP_JOB_DONE, "{}", 2),
                     LJGAP_JOBSTORE_LOST);
    assert_int_equal(ljgap__jobstore_release(st, ID_A, run1), LJGAP_JOBSTORE_LOST);
    /* a renewed lease does not lapse */
    assert_int_equal(ljgap__jobstore_renew(st, ID_A, run2, 0.1, 0.2, &cancel), LJGAP_JOBSTORE_OK);
    sleep_ms(50);
    assert_int_equal(ljgap__jobstore_renew(st, ID_A, run2, 0.2, 0.2, &cancel), LJGAP_JOBSTORE_OK);
    sleep_ms(100);
    assert_int_equal(ljgap__jobstore_claim(st, "test:3", 30, &rec), LJGAP_JOBSTORE_EMPTY);
    assert_int_equal(ljgap__jobstore_finish(st, ID_A, run2, LJGAP_JOB_DONE, "{}", 2),
                     LJGAP_JOBSTORE_OK);
    ljgap__jobstore_close(st);
}

/* Cancel: a queued job at once, a running one flagged (renew reads the flag), a finished one
 * left alone. */
static void test_cancel(void **state)
{
    ljgap__jobstore *st = contract_open(state);
    ljgap__job_record rec;
    int cancel = 0;
    long run;
    create_ok(st, ID_A, "{}");
    create_ok(st, ID_B, "{}");
    run = claim_ok(st, ID_A, 30);

    assert_int_equal(ljgap__jobstore_cancel(st, ID_B, &rec), LJGAP_JOBSTORE_OK);
    assert_int_equal(rec.state, LJGAP_JOB_CANCELLED);
    assert_true(rec.finished > 0 && rec.started == 0 && !rec.answer);
    ljgap__job_record_clear(&rec);
    assert_int_equal(ljgap__jobstore_claim(st, "t", 30, &rec), LJGAP_JOBSTORE_EMPTY);

    assert_int_equal(ljgap__jobstore_cancel(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_int_equal(rec.state, LJGAP_JOB_RUNNING);
    assert_int_equal(rec.cancel, 1);
    ljgap__job_record_clear(&rec);
    assert_int_equal(ljgap__jobstore_renew(st, ID_A, run, 0.5, 30, &cancel), LJGAP_JOBSTORE_OK);
    assert_int_equal(cancel, 1);
    assert_int_equal(ljgap__jobstore_finish(st, ID_A, run, LJGAP_JOB_CANCELLED, "{\"p\":1}", 7),
                     LJGAP_JOBSTORE_OK);
    assert_int_equal(ljgap__jobstore_cancel(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_int_equal(rec.state, LJGAP_JOB_CANCELLED);
    assert_string_equal(rec.answer, "{\"p\":1}");
    ljgap__job_record_clear(&rec);

    create_ok(st, ID_C, "{}");
    run = claim_ok(st, ID_C, 30);
    assert_int_equal(ljgap__jobstore_finish(st, ID_C, run, LJGAP_JOB_DONE, "{}", 2), 0);
    assert_int_equal(ljgap__jobstore_cancel(st, ID_C, &rec), LJGAP_JOBSTORE_OK);
    assert_int_equal(rec.state, LJGAP_JOB_DONE);
    ljgap__job_record_clear(&rec);
    assert_int_equal(ljgap__jobstore_cancel(st, ID_D, &rec), LJGAP_JOBSTORE_UNKNOWN);
    assert_int_equal(ljgap__jobstore_cancel(st, "nope", &rec), LJGAP_JOBSTORE_UNKNOWN);
    ljgap__jobstore_close(st);
}

/* Release puts a job back in its old place: it is claimed before a later one. */
static void test_release(void **state)
{
    ljgap__jobstore *st = contract_open(state);
    ljgap__job_record rec;
    int cancel;
    long run;
    create_ok(st, ID_A, "{}");
    create_ok(st, ID_B, "{}");
    run = claim_ok(st, ID_A, 30);
    assert_int_equal(ljgap__jobstore_renew(st, ID_A, run, 0.7, 30, &cancel), 0);
    assert_int_equal(ljgap__jobstore_release(st, ID_A, run), LJGAP_JOBSTORE_OK);
    assert_int_equal(ljgap__jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_OK);
    assert_true(rec.state == LJGAP_JOB_QUEUED && rec.progress == 0 && rec.started == 0);
    ljgap__job_record_clear(&rec);
    assert_int_equal(ljgap__jobstore_claim(st, "t", 30, &rec), LJGAP_JOBSTORE_OK);
    assert_string_equal(rec.id, ID_A);
    assert_true(rec.run == run + 1 && rec.lost == 0); /* given back, not lost */
    ljgap__job_record_clear(&rec);
    ljgap__jobstore_close(st);
}

/* finishes job id (claiming it first) with answer */
static void run_to_done(ljgap__jobstore *st, const char *id, const char *answer)
{
    long run;
    create_ok(st, id, "{}");
    run = claim_ok(st, id, 30);
    assert_int_equal(ljgap__jobstore_finish(st, id, run, LJGAP_JOB_DONE, answer, strlen(answer)),
                     LJGAP_JOBSTORE_OK);
}

static void test_evict(void **state)
{
    ljgap__jobstore *st = contract_open(state);
    const char *ids[] = {ID_A, ID_B, ID_C, ID_D};
    ljgap__job_record rec;
    unsigned n = 99;
    for (int i = 0; i < 4; i++)
        run_to_done(st, ids[i], "{}");
    create_ok(st, "00000000000000000000000000000005", "{}"); /* queued: never evicted */
    assert_int_equal(ljgap__jobstore_evict(st, 2, 3600, &n), LJGAP_JOBSTORE_OK);
    assert_int_equal(n, 2); /* the two that finished first */
    assert_int_equal(ljgap__jobstore_get(st, ID_A, &rec), LJGAP_JOBSTORE_UNKNOWN);
    assert_int_equal(ljgap__jobstore_get(st, ID_B, &rec), LJGAP_JOBSTORE_UNKNOWN);
    assert_int_equal(state_of(st, ID_C), LJGAP_JOB_DONE);
    assert_int_equal(state_of(st, ID_D), LJGAP_JOB_DONE);
    sleep_ms(20);
    assert_int_equal(ljgap__jobstore_evict(st, 100, 0.01, &n), LJGAP_JOBSTORE_OK);
    assert_int_equal(n, 2); /* by age */
    assert_int_equal(ljgap__jobstore_get(st, ID_D, &rec), LJGAP_JOBSTORE_UNKNOWN);
    assert_int_equal(state_of(st, "00000000000000000000000000000005"), LJGAP_JOB_QUEUED);
    assert_int_equal(ljgap__jobstore_evict(st, 100, -1, &n), LJGAP_JOBSTORE_INVALID);
    ljgap__jobstore_close(st);
}

/* The status object of id, parsed; checks it is valid UTF-8 JSON with the required fields. */
static cJSON *status_doc(ljgap__jobstore *st, const char *id)
{
    ljgap__job_record rec;
    char *s;
    cJSON *doc;
    const cJSON *p;
    assert_int_equal(ljgap__jobstore_get(st, id, &rec), LJGAP_JOBSTORE_OK);
    s = ljgap__job_status_json(&rec);
    ljgap__job_record_clear(&rec);
    assert_non_null(s);
    assert_int_equal(ljgap__utf8_span(s, strlen(s)), strlen(s));
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
static void damaged(ljgap__jobstore *st, const char *id)
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
    ljgap__jobstore *st = contract_open(state);
    char sql[600], id[LJGAP_JOB_ID_LEN + 1];
    cJSON *doc;
    for (size_t i = 0; i < sizeof contract_damages / sizeof contract_damages[0]; i++) {
        snprintf(id, sizeof id, "%032zx", i + 0x100);
        run_to_done(st, id, "{}");
        snprintf(sql, sizeof sql, "UPDATE " CONTRACT_TABLE " SET %s WHERE id = '%s'",
                 contract_damages[i], id);
        contract_sql(state, sql);
        damaged(st, id);
    }
    /* sound answers, odd numbers: shown, clamped, dropped */
    run_to_done(st, ID_A, "{\"x\":1}");
    contract_sql(state,
                 "UPDATE " CONTRACT_TABLE " SET " CONTRACT_ODD_NUMBERS " WHERE id = '" ID_A "'");
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
    contract_sql(state,
                 "UPDATE " CONTRACT_TABLE " SET " CONTRACT_RUNNING_JUNK " WHERE id = '" ID_B "'");
    doc = status_doc(st, ID_B);
    assert_string_equal(cJSON_GetObjectItem(doc, "status")->valuestring, "running");
    assert_null(cJSON_GetObjectItem(doc, "result"));
    assert_null(cJSON_GetObjectItem(doc, "problem"));
    cJSON_Delete(doc);
    ljgap__jobstore_close(st);
}

/* A sound finished job's status carries its answer byte for byte, and reads the same after
 * a reopen. */
static void test_status_exact(void **state)
{
    ljgap__jobstore *st = contract_open(state);
    cJSON *doc = cJSON_CreateObject();
    char *answer, *s1, *s2;
    ljgap__job_record rec;
    cJSON_AddNumberToObject(doc, "a", 0.1);
    cJSON_AddNumberToObject(doc, "b", 1.0 / 3.0);
    cJSON_AddNumberToObject(doc, "c", -2.5e-300);
    cJSON_AddStringToObject(doc, "d", "caf\xc3\xa9 \"q\" \\ \x01");
    answer = cJSON_PrintUnformatted(doc);
    cJSON_Delete(doc);
    run_to_done(st, ID_A, answer);
    assert_int_equal(ljgap__jobstore_get(st, ID_A, &rec), 0);
    s1 = ljgap__job_status_json(&rec);
    ljgap__job_record_clear(&rec);
    assert_non_null(strstr(s1, answer));
    ljgap__jobstore_close(st);
    st = contract_open(state);
    assert_int_equal(ljgap__jobstore_get(st, ID_A, &rec), 0);
    s2 = ljgap__job_status_json(&rec);
    ljgap__job_record_clear(&rec);
    assert_string_equal(s1, s2);
    free(s1);
    free(s2);
    free(answer);
    ljgap__jobstore_close(st);
}

#define CONTRACT_TESTS(T)                                                                          \
    T(test_life), T(test_create_refusals), T(test_lease_lapses), T(test_cancel), T(test_release),  \
        T(test_evict), T(test_damaged_rows), T(test_status_exact)

#endif
