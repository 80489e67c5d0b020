/* pool.c -- compute slots, the fair wait queue and the hang-up watchdog (pool.h).
 *
 * One mutex guards two lists: the waiting tasks in submission order and the running ones.
 * `slots` threads take tasks from the first list; one watchdog thread polls the sockets of
 * the tasks in both lists for hang-ups and expires tasks that waited too long. Both lists are
 * short by construction (at most queue_cap + slots tasks), so every decision is a walk.
 *
 * Fairness. When a slot frees, the slot thread picks its successor before it gives its own
 * task's slot back: the waiting task whose client holds the fewest running tasks, counting the
 * finishing one, earliest first among equals. So with one slot, a client A with five queued
 * requests and a client B with one: A1 finishes while A still counts one slot and B none, so
 * B goes next; B then waits for at most one of A's requests. A slot thread that finds nothing
 * waiting sleeps on `work`; a submission that finds a slot idle wakes one.
 *
 * Hang-ups. A suspended connection is not watched by libmicrohttpd, so the watchdog polls the
 * tasks' sockets (POLLRDHUP: the peer closed or shut down its sending side; POLLHUP/POLLERR:
 * reset) every POOL_POLL_MS. Only sockets of tasks still in one of the lists are polled, and a
 * task leaves the lists (under the lock) before wake(t) lets the daemon resume and eventually
 * close its connection, so a polled descriptor is never a closed and reused one: a result of a
 * poll is matched to its task by serial number under the lock, after the poll.
 *
 * Callbacks: park(t) runs under the lock (it must not call back into the scheduler); run(t)
 * and wake(t) run without it. After wake(t) the task belongs to the caller again and the
 * scheduler never touches it.
 */
#include "clock.h"
#include "pool.h"
#include "ljgap.h"

#include <errno.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { T_WAITING = 1, T_RUNNING = 2, T_ENDED = 3 };

typedef struct {
    pool_task *head, *tail;
    unsigned n;
} task_list;

struct pool {
    pool_config cfg;
    pthread_mutex_t lock;
    pthread_cond_t work;  /* a task is waiting, or we are stopping */
    pthread_cond_t ended; /* a running task ended */
    task_list waiting;    /* in submission order */
    task_list running;    /* in start order */
    unsigned long serial; /* last serial given */
    int stopping;         /* pool_stop was called: no new tasks */
    int quit;             /* pool_free: the watchdog stops */
    pool_stats stats;     /* counters (running/waiting are filled on demand) */
    pthread_t *threads;   /* the slot threads */
    unsigned n_threads;   /* slot threads started */
    pthread_t watchdog;   /* the hang-up and expiry thread */
    int has_watchdog;     /* it was started */
    struct pollfd *pfd;   /* the watchdog's poll set (queue_cap + slots entries) */
    unsigned long *pser;  /* serial of each entry of pfd */
};

/* ---- lists (lock held) ---- */

static void list_append(task_list *l, pool_task *t)
{
    t->next = NULL;
    t->prev = l->tail;
    if (l->tail)
        l->tail->next = t;
    else
        l->head = t;
    l->tail = t;
    l->n++;
}

static void list_remove(task_list *l, pool_task *t)
{
    if (t->prev)
        t->prev->next = t->next;
    else
        l->head = t->next;
    if (t->next)
        t->next->prev = t->prev;
    else
        l->tail = t->prev;
    t->prev = t->next = NULL;
    l->n--;
}

static pool_task *list_find(const task_list *l, unsigned long serial)
{
    for (pool_task *t = l->head; t; t = t->next)
        if (t->serial == serial) return t;
    return NULL;
}

/* Slots held by client: the running tasks with that key (the finishing one still counts). */
static unsigned held_by(const pool *s, const char *client)
{
    unsigned n = 0;
    for (const pool_task *t = s->running.head; t; t = t->next)
        n += strcmp(t->client, client) == 0;
    return n;
}

/* The waiting task to run next: fewest slots held by its client, earliest among equals, among
 * those whose memory can be reserved now (it is reserved here); NULL when none fits. */
static pool_task *pick(const pool *s)
{
    unsigned top = 0;
    for (pool_task *t = s->waiting.head; t; t = t->next) {
        unsigned h = held_by(s, t->client);
        if (h > top) top = h;
    }
    for (unsigned h = 0; h <= top; h++)
        for (pool_task *t = s->waiting.head; t; t = t->next) {
            if (held_by(s, t->client) != h) continue;
            if (!s->cfg.mem || budget_try(s->cfg.mem, t->mem)) return t;
            t->starved = 1;
        }
    return NULL;
}

static void start_task(pool *s, pool_task *t)
{
    list_remove(&s->waiting, t);
    t->state = T_RUNNING;
    t->t_start = ljgap__clock_now();
    t->waited_s = t->t_start - t->t_submit;
    list_append(&s->running, t);
}

/* Moves a waiting task out with outcome o onto the singly-linked list *woken (via next). */
static void end_waiting(pool *s, pool_task *t, pool_outcome o, pool_task **woken)
{
    list_remove(&s->waiting, t);
    t->state = T_ENDED;
    t->outcome = o;
    t->waited_s = ljgap__clock_now() - t->t_submit;
    t->next = *woken;
    *woken = t;
}

static void wake_all(pool_task *woken)
{
    while (woken) {
        pool_task *next = woken->next;
        woken->next = NULL;
        woken->wake(woken); /* woken may be freed from here on */
        woken = next;
    }
}

/* ---- slot threads ---- */

static void *slot_main(void *arg)
{
    pool *s = arg;
    pool_task *t = NULL;

    pthread_mutex_lock(&s->lock);
    for (;;) {
        pool_task *next;
        if (!t) {
            /* nothing waits, or nothing that waits fits the budget now (the watchdog and
             * every ending task wake us to look again) */
            while (!s->stopping && !(s->waiting.head && (t = pick(s))))
                pthread_cond_wait(&s->work, &s->lock);
            if (!t) break; /* stopping, and pool_stop ended every waiting task */
            start_task(s, t);
        }
        pthread_mutex_unlock(&s->lock);

        t->run(t);

        pthread_mutex_lock(&s->lock);
        t->ran_s = ljgap__clock_now() - t->t_start;
        if (s->cfg.mem) budget_release(s->cfg.mem, t->mem);
        next = s->waiting.head ? pick(s) : NULL; /* chosen while t still holds its slot */
        if (s->waiting.head && s->cfg.mem) pthread_cond_broadcast(&s->work); /* bytes freed */
        list_remove(&s->running, t);
        t->state = T_ENDED;
        t->outcome = t->hung_up ? POOL_GONE : POOL_DONE;
        s->stats.mean_run_s =
            s->stats.served ? 0.8 * s->stats.mean_run_s + 0.2 * t->ran_s : t->ran_s;
        s->stats.served++;
        if (t->hung_up) s->stats.gone++;
        if (next) start_task(s, next);
        pthread_cond_broadcast(&s->ended);
        pthread_mutex_unlock(&s->lock);
        t->wake(t); /* t is the caller's again */
        pthread_mutex_lock(&s->lock);
        t = next;
    }
    pthread_mutex_unlock(&s->lock);
    return NULL;
}

/* ---- the watchdog ---- */

static void *watch_main(void *arg)
{
    pool *s = arg;

    pthread_mutex_lock(&s->lock);
    while (!s->quit) {
        const task_list *lists[2] = {&s->waiting, &s->running};
        pool_task *woken = NULL;
        nfds_t n = 0;
        double now;

        for (int l = 0; l < 2; l++)
            for (pool_task *t = lists[l]->head; t; t = t->next)
                if (t->fd >= 0 && !t->hung_up) {
                    s->pfd[n].fd = t->fd;
                    s->pfd[n].events = POLLRDHUP;
                    s->pfd[n].revents = 0;
                    s->pser[n++] = t->serial;
                }
        pthread_mutex_unlock(&s->lock);
        if (poll(s->pfd, n, POOL_POLL_MS) < 0 && errno != EINTR) {
            const struct timespec tick = {0, POOL_POLL_MS * 1000000L};
            nanosleep(&tick, NULL); /* cannot happen with valid arguments; never spin */
        }
        pthread_mutex_lock(&s->lock);

        for (nfds_t i = 0; i < n; i++) {
            pool_task *t;
            if (!(s->pfd[i].revents & (POLLRDHUP | POLLHUP | POLLERR | POLLNVAL))) continue;
            if ((t = list_find(&s->waiting, s->pser[i]))) {
                end_waiting(s, t, POOL_GONE, &woken);
                s->stats.gone++;
            } else if ((t = list_find(&s->running, s->pser[i]))) {
                t->hung_up = 1; /* counted when it ends */
                t->cancel = 1;
            }
        }
        now = ljgap__clock_now();
        for (pool_task *t = s->waiting.head, *next; t; t = next) {
            next = t->next;
            if (now - t->t_submit >= s->cfg.queue_wait) {
                end_waiting(s, t, POOL_EXPIRED, &woken);
                s->stats.expired++;
            }
        }
        /* bytes freed outside the pool (bodies) may let a waiting task fit an idle slot */
        if (s->cfg.mem && s->waiting.head && s->running.n < s->n_threads)
            pthread_cond_broadcast(&s->work);
        if (woken) {
            pthread_mutex_unlock(&s->lock);
            wake_all(woken);
            pthread_mutex_lock(&s->lock);
        }
    }
    pthread_mutex_unlock(&s->lock);
    return NULL;
}

/* ---- the interface ---- */

pool *pool_start(const pool_config *c)
{
    pool *s;
    size_t npoll;

    if (!c || c->slots < 1 || !(c->queue_wait > 0)) return NULL;
    if (!(s = calloc(1, sizeof *s))) return NULL;
    s->cfg = *c;
    npoll = (size_t)c->queue_cap + c->slots;
    s->threads = calloc(c->slots, sizeof *s->threads);
    s->pfd = calloc(npoll, sizeof *s->pfd);
    s->pser = calloc(npoll, sizeof *s->pser);
    pthread_mutex_init(&s->lock, NULL);
    ljgap__cond_init_monotonic(&s->work);
    ljgap__cond_init_monotonic(&s->ended);
    if (!s->threads || !s->pfd || !s->pser) {
        pool_free(s);
        return NULL;
    }
    while (s->n_threads < c->slots &&
           pthread_create(&s->threads[s->n_threads], NULL, slot_main, s) == 0)
        s->n_threads++;
    if (s->n_threads == c->slots && pthread_create(&s->watchdog, NULL, watch_main, s) == 0)
        s->has_watchdog = 1;
    if (!s->has_watchdog) {
        pool_free(s);
        return NULL;
    }
    return s;
}

pool_status pool_submit(pool *s, pool_task *t)
{
    pool_status st = POOL_OK;

    pthread_mutex_lock(&s->lock);
    if (s->stopping) {
        st = POOL_STOPPING;
    } else if (s->waiting.n + s->running.n >= s->cfg.slots + s->cfg.queue_cap) {
        st = POOL_FULL;
        s->stats.full++;
    } else {
        t->serial = ++s->serial;
        t->t_submit = ljgap__clock_now();
        t->t_start = 0;
        t->waited_s = t->ran_s = 0;
        t->cancel = 0;
        t->hung_up = 0;
        t->starved = 0;
        t->outcome = POOL_DONE;
        t->client[POOL_CLIENT_MAX - 1] = '\0';
        t->state = T_WAITING;
        list_append(&s->waiting, t);
        if (t->park) t->park(t);
        pthread_cond_signal(&s->work);
    }
    pthread_mutex_unlock(&s->lock);
    return st;
}

void pool_get_stats(pool *s, pool_stats *st)
{
    pthread_mutex_lock(&s->lock);
    *st = s->stats;
    st->running = s->running.n;
    st->waiting = s->waiting.n;
    pthread_mutex_unlock(&s->lock);
}

unsigned pool_queue_cap(const pool *s)
{
    return s->cfg.queue_cap;
}

unsigned pool_retry_after(pool *s)
{
    double r;
    pthread_mutex_lock(&s->lock);
    r = ceil(s->stats.mean_run_s * (s->waiting.n + 1) / s->cfg.slots);
    pthread_mutex_unlock(&s->lock);
    return r < 1 ? 1 : r > 60 ? 60 : (unsigned)r;
}

/* Waits (lock held) until nothing runs or `until`; 1 when nothing runs. */
static int wait_running(pool *s, const struct timespec *until)
{
    while (s->running.n > 0 && pthread_cond_timedwait(&s->ended, &s->lock, until) == 0)
        ;
    return s->running.n == 0;
}

int pool_stop(pool *s, double grace_s, double wait_s)
{
    struct timespec grace = ljgap__deadline_in(grace_s), until = ljgap__deadline_in(grace_s + wait_s);
    pool_task *woken = NULL;
    int idle;

    pthread_mutex_lock(&s->lock);
    s->stopping = 1;
    while (s->waiting.head)
        end_waiting(s, s->waiting.head, POOL_STOPPED, &woken);
    pthread_cond_broadcast(&s->work);
    pthread_mutex_unlock(&s->lock);
    wake_all(woken);

    pthread_mutex_lock(&s->lock);
    if (!wait_running(s, &grace)) {
        for (pool_task *t = s->running.head; t; t = t->next)
            t->cancel = 1;
        wait_running(s, &until);
    }
    idle = s->running.n == 0;
    pthread_mutex_unlock(&s->lock);
    return idle;
}

void pool_free(pool *s)
{
    if (!s) return;
    if (s->n_threads) {
        int stopped;
        pthread_mutex_lock(&s->lock);
        stopped = s->stopping;
        pthread_mutex_unlock(&s->lock);
        if (!stopped) pool_stop(s, 0, 10);
    }
    pthread_mutex_lock(&s->lock);
    s->stopping = 1;
    s->quit = 1;
    pthread_cond_broadcast(&s->work);
    pthread_mutex_unlock(&s->lock);
    for (unsigned i = 0; i < s->n_threads; i++)
        pthread_join(s->threads[i], NULL);
    if (s->has_watchdog) pthread_join(s->watchdog, NULL);
    pthread_cond_destroy(&s->work);
    pthread_cond_destroy(&s->ended);
    pthread_mutex_destroy(&s->lock);
    free(s->threads);
    free(s->pfd);
    free(s->pser);
    free(s);
}
