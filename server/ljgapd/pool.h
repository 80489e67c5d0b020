/* pool.h -- compute slots with a bounded, fair wait queue, for the HTTP daemon.
 *
 * A computation (a "task") runs on one of `slots` threads. A task that finds every slot busy
 * waits in a queue of at most `queue_cap` tasks for at most `queue_wait` seconds; the next free
 * slot goes to the waiting task whose client holds the fewest slots (counting the task that is
 * just finishing as still held, so a client's batch cannot take a slot back-to-back while
 * another client waits), first come first served among equals.
 *
 * Nothing here knows HTTP. The daemon hands over a task with three callbacks:
 *   park(t)  called once, under the scheduler's lock, when the task is accepted (the daemon
 *            suspends the connection here, before any slot thread can see the task);
 *   run(t)   called on a slot thread, without the lock: does the work (reads t->cancel);
 *   wake(t)  called once, without the lock, when the task has an outcome (the daemon resumes
 *            the connection and answers from t->outcome).
 * While a task waits or runs, a watchdog thread polls its socket (t->fd, or -1 for none) for a
 * hang-up every POOL_POLL_MS: a waiting task whose client went away leaves the queue at once
 * (outcome POOL_GONE); a running one has t->cancel raised, so the computation stops at its
 * next check and frees its slot, and ends with outcome POOL_GONE. The same thread expires
 * tasks that waited longer than queue_wait (POOL_EXPIRED).
 *
 * Memory. With a budget (pool_config.mem), a task also needs its t->mem bytes: the next free
 * slot goes to the fairest waiting task whose bytes can be reserved now (the others keep
 * waiting, as for a slot, and expire after queue_wait); the bytes go back when run(t) returns.
 * Memory freed elsewhere (a request body) is noticed within POOL_POLL_MS. A task larger than
 * the whole budget would only expire: the caller refuses it before submitting.
 *
 *   pool *s = pool_start(&cfg);                     slot threads and the watchdog start
 *   t->run = ...; t->park = ...; t->wake = ...; t->client = "127.0.0.1"; t->fd = fd;
 *   switch (pool_submit(s, t)) ...                   POOL_OK: park(t) ran; wake(t) will run
 *   pool_stop(s, grace_s);                           waiting tasks end POOL_STOPPING, running
 *                                                     ones get grace_s, then their cancel flag
 *   pool_free(s);                                    joins the threads
 */
#ifndef LJGAPD_POOL_H
#define LJGAPD_POOL_H

#include "budget.h"

#include <stddef.h>

#define POOL_CLIENT_MAX 64 /* longest client key kept (an IPv6 address is at most 45) */
#define POOL_POLL_MS 20    /* how often waiting and running tasks' sockets are checked */

typedef enum {
    POOL_OK = 0,       /* submit: accepted; park(t) has run, wake(t) will run once */
    POOL_FULL = 1,     /* submit: every slot busy and queue_cap tasks waiting */
    POOL_STOPPING = 2, /* submit: pool_stop was called */
} pool_status;

typedef enum {
    POOL_DONE = 0,    /* run(t) returned (its result is in the task's payload) */
    POOL_EXPIRED = 1, /* waited queue_wait seconds without getting a slot; never ran */
    POOL_GONE = 2,    /* the client hung up (while waiting: never ran; while running: the
                       * computation was cancelled) */
    POOL_STOPPED = 3, /* the scheduler stopped before the task got a slot; never ran */
} pool_outcome;

typedef struct pool_task pool_task;

struct pool_task {
    /* set by the caller before pool_submit */
    void (*run)(pool_task *t);    /* the work, on a slot thread */
    void (*park)(pool_task *t);   /* on acceptance, under the lock; may be NULL */
    void (*wake)(pool_task *t);   /* once, with the outcome; never NULL */
    void *arg;                    /* the caller's payload */
    char client[POOL_CLIENT_MAX]; /* who asked (fairness is between these keys) */
    int fd;                       /* socket polled for hang-ups, or -1 */
    size_t mem;                   /* bytes reserved from the pool's budget while it runs */
    /* set by the scheduler */
    volatile int cancel;  /* raised to stop run(t) early (hang-up, stop) */
    pool_outcome outcome; /* valid in wake(t) */
    double waited_s;      /* seconds from submit to a slot (or to the end) */
    double ran_s;         /* seconds run(t) took (0 if it never ran) */
    int starved;          /* it waited (also) because its memory did not fit the budget */
    /* private */
    pool_task *prev, *next;   /* the waiting or the running list */
    unsigned long serial;     /* submission number (identifies it to the watchdog) */
    double t_submit, t_start; /* ljgap__clock_now() at submit and at slot */
    int state;                /* waiting, running, ended */
    int hung_up;              /* the watchdog saw the hang-up */
};

typedef struct {
    unsigned slots;     /* slot threads: computations at once (>= 1) */
    unsigned queue_cap; /* tasks waiting at most (0: none wait, busy means POOL_FULL) */
    double queue_wait;  /* seconds a task may wait for a slot (> 0) */
    budget *mem;        /* a task gets a slot only once its t->mem bytes are reserved here
                         * (released when run(t) returns); NULL: no budget */
} pool_config;

typedef struct pool pool;

/* Starts the slot threads and the watchdog; NULL if memory or threads run out. */
pool *pool_start(const pool_config *c);

/* Accepts t (POOL_OK: park(t) ran under the lock, wake(t) will follow exactly once) or
 * refuses it (POOL_FULL, POOL_STOPPING: no callback runs, the task is the caller's). */
pool_status pool_submit(pool *s, pool_task *t);

/* Figures for logs, /healthz-like reports and Retry-After. */
typedef struct {
    unsigned running;      /* tasks on a slot now */
    unsigned waiting;      /* tasks in the queue now */
    double mean_run_s;     /* running mean of run(t)'s duration (0 before the first) */
    unsigned long served;  /* tasks that ran to the end */
    unsigned long gone;    /* tasks whose client hung up */
    unsigned long expired; /* tasks that waited too long */
    unsigned long full;    /* submissions refused with POOL_FULL */
} pool_stats;

void pool_get_stats(pool *s, pool_stats *st);

/* The queue_cap it was started with. */
unsigned pool_queue_cap(const pool *s);

/* Seconds a client refused now should wait before retrying: the expected time for the queue
 * ahead to drain (mean run time x (waiting + 1) / slots), between 1 and 60. */
unsigned pool_retry_after(pool *s);

/* Stops taking tasks: every waiting task ends POOL_STOPPED (wake runs), running ones may go
 * on for grace_s seconds, then get their cancel flag. Returns when no task is running, or
 * after grace_s + wait_s seconds; 1 when none is left running. */
int pool_stop(pool *s, double grace_s, double wait_s);

/* Stops (if not yet) and joins the threads. NULL is fine. */
void pool_free(pool *s);

#endif
