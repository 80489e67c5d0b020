/* test_pool.c -- the daemon's compute slots and wait queue (server/ljgapd/pool.c) with test
 * tasks that hold their slot until released or cancelled: first come first served, fairness
 * between clients (one slot and two), the queue bound, expiry after queue_wait, a hang-up
 * while waiting (leaves the queue, never runs) and while running (cancel flag raised), stop
 * (waiting tasks end, running ones get their grace, then their cancel flag), and that park and
 * wake run exactly once per accepted task. Waits are bounded loops, never bare sleeps. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "pool.h"

#define MAXT 16

typedef struct {
    pool_task t;        /* first: the pool's view */
    atomic_int release; /* run returns when nonzero (or when cancelled) */
    atomic_int parked;  /* park calls */
    atomic_int woken;   /* wake calls */
    atomic_int ran;     /* run calls */
    int saw_cancel;     /* run returned because of the cancel flag */
} test_task;

static atomic_int order[MAXT]; /* index of each task in start order */
static atomic_int n_started;

static void sleep_ms(int ms)
{
    struct timespec t = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&t, NULL);
}

static void run_held(pool_task *t)
{
    test_task *x = (test_task *)t;
    int me = atomic_fetch_add(&n_started, 1);
    atomic_store(&order[me], (int)(intptr_t)t->arg);
    atomic_fetch_add(&x->ran, 1);
    for (int i = 0; i < 5000 && !atomic_load(&x->release); i++) {
        if (t->cancel) {
            x->saw_cancel = 1;
            return;
        }
        sleep_ms(1);
    }
}

static void on_park(pool_task *t)
{
    atomic_fetch_add(&((test_task *)t)->parked, 1);
}

static void on_wake(pool_task *t)
{
    atomic_fetch_add(&((test_task *)t)->woken, 1);
}

static void init_task(test_task *x, int index, const char *client, int fd)
{
    memset(x, 0, sizeof *x);
    x->t.run = run_held;
    x->t.park = on_park;
    x->t.wake = on_wake;
    x->t.arg = (void *)(intptr_t)index;
    snprintf(x->t.client, sizeof x->t.client, "%s", client);
    x->t.fd = fd;
}

/* Waits (bounded) until cond holds; the condition is re-read every millisecond. */
#define WAIT_FOR(cond)                                                                             \
    do {                                                                                           \
        for (int w_ = 0; w_ < 3000 && !(cond); w_++)                                               \
            sleep_ms(1);                                                                           \
        assert_true(cond);                                                                         \
    } while (0)

static pool *start(unsigned slots, unsigned cap, double wait)
{
    pool_config c = {slots, cap, wait, NULL};
    pool *p = pool_start(&c);
    assert_non_null(p);
    atomic_store(&n_started, 0);
    return p;
}

/* Releases task x and waits until its wake ran. */
static void finish(test_task *x)
{
    atomic_store(&x->release, 1);
    WAIT_FOR(atomic_load(&x->woken) == 1);
}

/* Releases tasks t[from..to), running or yet to run. */
static void release_all(test_task *t, int from, int to)
{
    for (int i = from; i < to; i++)
        atomic_store(&t[i].release, 1);
}

static void test_first_come_first_served(void **state)
{
    pool *p = start(1, 8, 10);
    test_task t[4];
    for (int i = 0; i < 4; i++) {
        init_task(&t[i], i, "a", -1);
        assert_int_equal(pool_submit(p, &t[i].t), POOL_OK);
        assert_int_equal(atomic_load(&t[i].parked), 1);
    }
    for (int i = 0; i < 4; i++) {
        WAIT_FOR(atomic_load(&n_started) == i + 1);
        assert_int_equal(atomic_load(&order[i]), i);
        finish(&t[i]);
        assert_int_equal(t[i].t.outcome, POOL_DONE);
    }
    pool_free(p);
    for (int i = 0; i < 4; i++)
        assert_int_equal(atomic_load(&t[i].woken), 1);
}

/* Two slots free and two clients waiting: each client gets one at once. */
static void test_fair_free_slots(void **state)
{
    pool *p = start(2, 8, 10);
    test_task t[4];
    for (int i = 0; i < 4; i++)
        init_task(&t[i], i, i < 3 ? "a" : "b", -1);
    for (int i = 0; i < 4; i++)
        assert_int_equal(pool_submit(p, &t[i].t), POOL_OK);
    WAIT_FOR(atomic_load(&n_started) == 2);
    /* whatever the threads' timing, b's single task is among the first two or runs as soon
     * as a slot frees: it never waits behind a's second */
    if (atomic_load(&order[0]) != 3 && atomic_load(&order[1]) != 3) {
        finish(&t[atomic_load(&order[0])]);
        WAIT_FOR(atomic_load(&n_started) == 3);
        assert_int_equal(atomic_load(&order[2]), 3);
    }
    release_all(t, 0, 4);
    WAIT_FOR(atomic_load(&n_started) == 4);
    pool_free(p);
}

/* One slot: A sends five, B one after them; B runs right after A's first. */
static void test_fair_one_slot(void **state)
{
    pool *p = start(1, 8, 10);
    test_task t[6];
    const int expect[6] = {0, 5, 1, 2, 3, 4};
    for (int i = 0; i < 6; i++) {
        init_task(&t[i], i, i < 5 ? "127.0.0.2" : "127.0.0.3", -1);
        assert_int_equal(pool_submit(p, &t[i].t), POOL_OK);
    }
    for (int k = 0; k < 6; k++) {
        WAIT_FOR(atomic_load(&n_started) == k + 1);
        assert_int_equal(atomic_load(&order[k]), expect[k]);
        finish(&t[expect[k]]);
    }
    pool_free(p);
}

/* Two slots: A takes both; when one frees, B (holding none) goes before A's third. */
static void test_fair_two_slots(void **state)
{
    pool *p = start(2, 8, 10);
    test_task t[6];
    for (int i = 0; i < 6; i++)
        init_task(&t[i], i, i < 5 ? "a" : "b", -1);
    for (int i = 0; i < 5; i++)
        assert_int_equal(pool_submit(p, &t[i].t), POOL_OK);
    WAIT_FOR(atomic_load(&n_started) == 2); /* A holds both slots before B arrives */
    assert_int_equal(pool_submit(p, &t[5].t), POOL_OK);
    finish(&t[0]);
    WAIT_FOR(atomic_load(&n_started) == 3);
    assert_int_equal(atomic_load(&order[2]), 5); /* B's only request */
    finish(&t[1]);
    WAIT_FOR(atomic_load(&n_started) == 4);
    assert_int_equal(atomic_load(&order[3]), 2);
    release_all(t, 2, 6);
    WAIT_FOR(atomic_load(&n_started) == 6);
    pool_free(p);
}

static void test_queue_bound(void **state)
{
    pool *p = start(1, 2, 10);
    test_task t[4];
    pool_stats st;
    for (int i = 0; i < 3; i++) {
        init_task(&t[i], i, "a", -1);
        assert_int_equal(pool_submit(p, &t[i].t), POOL_OK);
    }
    init_task(&t[3], 3, "b", -1);
    assert_int_equal(pool_submit(p, &t[3].t), POOL_FULL);
    assert_int_equal(atomic_load(&t[3].parked), 0);
    pool_get_stats(p, &st);
    assert_int_equal(st.full, 1);
    assert_int_equal(st.running + st.waiting, 3);
    assert_true(pool_retry_after(p) >= 1 && pool_retry_after(p) <= 60);
    release_all(t, 0, 3);
    pool_free(p);
    assert_int_equal(atomic_load(&t[3].woken), 0);
}

static void test_no_queue(void **state)
{
    pool *p = start(1, 0, 10);
    test_task a, b;
    init_task(&a, 0, "a", -1);
    init_task(&b, 1, "b", -1);
    assert_int_equal(pool_submit(p, &a.t), POOL_OK);
    WAIT_FOR(atomic_load(&n_started) == 1);
    assert_int_equal(pool_submit(p, &b.t), POOL_FULL);
    finish(&a);
    pool_free(p);
}

static void test_expiry(void **state)
{
    pool *p = start(1, 4, 0.1);
    test_task a, b;
    init_task(&a, 0, "a", -1);
    init_task(&b, 1, "b", -1);
    assert_int_equal(pool_submit(p, &a.t), POOL_OK);
    assert_int_equal(pool_submit(p, &b.t), POOL_OK);
    WAIT_FOR(atomic_load(&b.woken) == 1);
    assert_int_equal(b.t.outcome, POOL_EXPIRED);
    assert_int_equal(atomic_load(&b.ran), 0);
    assert_true(b.t.waited_s >= 0.1);
    finish(&a);
    pool_free(p);
}

static void test_hangup_while_waiting(void **state)
{
    pool *p = start(1, 4, 10);
    test_task a, b;
    int sv[2];
    pool_stats st;
    assert_int_equal(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    init_task(&a, 0, "a", -1);
    init_task(&b, 1, "b", sv[0]);
    assert_int_equal(pool_submit(p, &a.t), POOL_OK);
    assert_int_equal(pool_submit(p, &b.t), POOL_OK);
    sleep_ms(3 * POOL_POLL_MS);
    assert_int_equal(atomic_load(&b.woken), 0); /* still waiting: nothing happened to it */
    close(sv[1]);
    WAIT_FOR(atomic_load(&b.woken) == 1);
    assert_int_equal(b.t.outcome, POOL_GONE);
    assert_int_equal(atomic_load(&b.ran), 0);
    pool_get_stats(p, &st);
    assert_int_equal(st.gone, 1);
    assert_int_equal(st.waiting, 0);
    finish(&a);
    pool_free(p);
    close(sv[0]);
}

static void test_hangup_while_running(void **state)
{
    pool *p = start(1, 4, 10);
    test_task a;
    int sv[2];
    assert_int_equal(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    init_task(&a, 0, "a", sv[0]);
    assert_int_equal(pool_submit(p, &a.t), POOL_OK);
    WAIT_FOR(atomic_load(&a.ran) == 1);
    close(sv[1]);
    WAIT_FOR(atomic_load(&a.woken) == 1);
    assert_true(a.saw_cancel);
    assert_int_equal(a.t.outcome, POOL_GONE);
    pool_free(p);
    close(sv[0]);
}

/* Data from the client (a pipelined request) is not a hang-up. */
static void test_data_is_not_hangup(void **state)
{
    pool *p = start(1, 4, 10);
    test_task a;
    int sv[2];
    assert_int_equal(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    init_task(&a, 0, "a", sv[0]);
    assert_int_equal(pool_submit(p, &a.t), POOL_OK);
    WAIT_FOR(atomic_load(&a.ran) == 1);
    assert_int_equal(write(sv[1], "GET / HTTP/1.1\r\n", 16), 16);
    sleep_ms(4 * POOL_POLL_MS);
    assert_false(a.t.cancel);
    finish(&a);
    assert_int_equal(a.t.outcome, POOL_DONE);
    pool_free(p);
    close(sv[0]);
    close(sv[1]);
}

static void test_stop(void **state)
{
    pool *p = start(1, 4, 10);
    test_task a, b;
    init_task(&a, 0, "a", -1);
    init_task(&b, 1, "b", -1);
    assert_int_equal(pool_submit(p, &a.t), POOL_OK);
    assert_int_equal(pool_submit(p, &b.t), POOL_OK);
    WAIT_FOR(atomic_load(&a.ran) == 1);
    /* a never finishes by itself: the grace passes and its cancel flag stops it */
    assert_int_equal(pool_stop(p, 0.05, 2), 1);
    assert_int_equal(atomic_load(&b.woken), 1);
    assert_int_equal(b.t.outcome, POOL_STOPPED);
    assert_int_equal(atomic_load(&b.ran), 0);
    assert_true(a.saw_cancel);
    assert_int_equal(atomic_load(&a.woken), 1);
    init_task(&b, 2, "b", -1);
    assert_int_equal(pool_submit(p, &b.t), POOL_STOPPING);
    pool_free(p);
}

/* A task that finishes within the grace period is not cancelled. */
static void test_stop_grace(void **state)
{
    pool *p = start(1, 4, 10);
    test_task a;
    init_task(&a, 0, "a", -1);
    assert_int_equal(pool_submit(p, &a.t), POOL_OK);
    WAIT_FOR(atomic_load(&a.ran) == 1);
    atomic_store(&a.release, 1);
    assert_int_equal(pool_stop(p, 2, 2), 1);
    assert_false(a.saw_cancel);
    assert_int_equal(a.t.outcome, POOL_DONE);
    pool_free(p);
}

/* With a memory budget: a task runs only once its bytes are reserved. Two slots, a budget of
 * 100 bytes: a (60) runs, b (60) waits although a slot is free, c (30) runs beside a; when a
 * ends its bytes go back and b runs. A task whose bytes are held elsewhere (a body) starts
 * within a poll once they are released; one that never fits expires, marked starved. */
static void test_memory(void **state)
{
    budget *b = budget_new(100, NULL);
    pool_config c = {2, 8, 10, b};
    pool *p = pool_start(&c);
    test_task t[3];
    budget_stats st;
    assert_non_null(p);
    atomic_store(&n_started, 0);
    for (int i = 0; i < 3; i++) {
        init_task(&t[i], i, "a", -1);
        t[i].t.mem = i < 2 ? 60 : 30;
    }
    assert_int_equal(pool_submit(p, &t[0].t), POOL_OK);
    WAIT_FOR(atomic_load(&n_started) == 1);
    assert_int_equal(pool_submit(p, &t[1].t), POOL_OK);
    sleep_ms(3 * POOL_POLL_MS);
    assert_int_equal(atomic_load(&t[1].ran), 0); /* a slot is free, the memory is not */
    assert_int_equal(pool_submit(p, &t[2].t), POOL_OK);
    WAIT_FOR(atomic_load(&t[2].ran) == 1); /* 30 bytes fit beside a's 60 */
    budget_get(b, &st);
    assert_int_equal(st.used, 90);
    finish(&t[2]);
    finish(&t[0]);
    WAIT_FOR(atomic_load(&t[1].ran) == 1);
    assert_true(t[1].t.starved);
    finish(&t[1]);
    WAIT_FOR((budget_get(b, &st), st.used == 0));
    assert_int_equal(st.peak, 90);
    pool_free(p);

    /* bytes held outside the pool: the waiting task starts once they are given back */
    pool_config c2 = {1, 8, 0.5, b};
    p = pool_start(&c2);
    assert_non_null(p);
    assert_true(budget_try(b, 80));
    init_task(&t[0], 0, "a", -1);
    t[0].t.mem = 50;
    init_task(&t[1], 1, "b", -1);
    t[1].t.mem = 101; /* never fits */
    assert_int_equal(pool_submit(p, &t[0].t), POOL_OK);
    assert_int_equal(pool_submit(p, &t[1].t), POOL_OK);
    sleep_ms(3 * POOL_POLL_MS);
    assert_int_equal(atomic_load(&t[0].ran), 0);
    budget_release(b, 80);
    WAIT_FOR(atomic_load(&t[0].ran) == 1);
    finish(&t[0]);
    WAIT_FOR(atomic_load(&t[1].woken) == 1);
    assert_int_equal(t[1].t.outcome, POOL_EXPIRED);
    assert_true(t[1].t.starved);
    assert_int_equal(atomic_load(&t[1].ran), 0);
    pool_free(p);
    budget_get(b, &st);
    assert_int_equal(st.used, 0);
    budget_free(b);
}

static void test_bad_config(void **state)
{
    pool_config c0 = {0, 4, 10, NULL}, c1 = {1, 4, 0, NULL};
    assert_null(pool_start(&c0));
    assert_null(pool_start(&c1));
    assert_null(pool_start(NULL));
    pool_free(NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_first_come_first_served),
        cmocka_unit_test(test_fair_one_slot),
        cmocka_unit_test(test_fair_two_slots),
        cmocka_unit_test(test_fair_free_slots),
        cmocka_unit_test(test_queue_bound),
        cmocka_unit_test(test_no_queue),
        cmocka_unit_test(test_expiry),
        cmocka_unit_test(test_hangup_while_waiting),
        cmocka_unit_test(test_hangup_while_running),
        cmocka_unit_test(test_data_is_not_hangup),
        cmocka_unit_test(test_stop),
        cmocka_unit_test(test_stop_grace),
        cmocka_unit_test(test_memory),
        cmocka_unit_test(test_bad_config),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
