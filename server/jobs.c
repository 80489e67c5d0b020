/* jobs.c -- the daemon's background jobs (jobs.h): one list, one lock, a few workers.
 *
 * Every job, whatever its state, sits in one doubly-linked list in submission order, so the
 * oldest queued job is the first queued one found (FIFO) and lookups by id are a walk. The
 * list is short by construction: at most queue_cap queued, `workers` running and keep_done
 * finished jobs, a hundred or so, so a walk costs less than the HTTP request that asks for it.
 *
 * One mutex guards the list and every job's fields except `cancel`, which the running job's
 * computation reads without the lock (it is the core's volatile cancel flag). Two condition
 * variables on CLOCK_MONOTONIC: `work` wakes the workers (a job was queued, or shutdown) and
 * `finished` wakes whoever waits for a job to end (ljgap_jobs_cancel, ljgap_jobs_wait_idle).
 * A worker runs the job's function without the lock; the job cannot be evicted meanwhile,
 * because only finished jobs are.
 *
 * Ids are 128 bits from getrandom(2) in hex: not guessable, so one client cannot read or
 * cancel another's job by counting.
 */
#include "jobs.h"
#include "ljgap.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>

typedef enum { JOB_QUEUED, JOB_RUNNING, JOB_DONE, JOB_FAILED, JOB_CANCELLED } job_state;

static const char *const state_names[] = {"queued", "running", "done", "failed", "cancelled"};

typedef struct job {
    struct job *prev, *next;       /* the store's list, in submission order */
    struct ljgap_jobs *js;         /* the store (for the progress callback) */
    char id[LJGAP_JOB_ID_LEN + 1]; /* hex id */
    job_state state;               /* where it is in its life */
    ljgap_job_fn run;              /* the work */
    void *arg;                     /* its argument, owned; NULL once released */
    void (*free_arg)(void *);      /* releases arg (may be NULL) */
    volatile int cancel;           /* raised by cancel or shutdown; read by the run unlocked */
    double progress;               /* 0..1, never decreasing */
    double t_start, t_end;         /* ljgap_now() when it started running / finished */
    int reply_status;              /* HTTP status of the run's reply, when finished */
    char *reply;                   /* the run's reply body (JSON), owned; NULL if none */
} job;

struct ljgap_jobs {
    ljgap_jobs_config cfg; /* as given, checked */
    pthread_mutex_t lock;
    pthread_cond_t work;     /* a job was queued, or the store is stopping */
    pthread_cond_t finished; /* a job finished */
    job *head, *tail;        /* every job, oldest first */
    unsigned n_queued;       /* jobs in state queued */
    unsigned n_running;      /* jobs in state running */
    unsigned n_finished;     /* jobs in a final state */
    int stopping;            /* ljgap_jobs_shutdown was called */
    pthread_t *threads;      /* the workers */
    unsigned n_threads;      /* workers started */
};

void ljgap_jobs_config_default(ljgap_jobs_config *c)
{
    c->workers = 1;
    c->queue_cap = 8;
    c->keep_done = 64;
    c->keep_seconds = 3600.0;
}

/* ---- the list (lock held) ---- */

static job *find(ljgap_jobs *js, const char *id)
{
    for (job *j = js->head; j; j = j->next)
        if (strcmp(j->id, id) == 0) return j;
    return NULL;
}

static void unlink_job(ljgap_jobs *js, job *j)
{
    if (j->prev)
        j->prev->next = j->next;
    else
        js->head = j->next;
    if (j->next)
        j->next->prev = j->prev;
    else
        js->tail = j->prev;
}

static void release_arg(job *j)
{
    if (j->arg && j->free_arg) j->free_arg(j->arg);
    j->arg = NULL;
}

static void job_free(job *j)
{
    release_arg(j);
    free(j->reply);
    free(j);
}

/* Moves j (queued or running) to a final state, taking reply (may be NULL). */
static void finish(ljgap_jobs *js, job *j, job_state state, int status, char *reply)
{
    if (j->state == JOB_QUEUED)
        js->n_queued--;
    else
        js->n_running--;
    js->n_finished++;
    j->state = state;
    j->t_end = ljgap_now();
    j->reply_status = status;
    j->reply = reply;
    if (state == JOB_DONE) j->progress = 1.0;
    pthread_cond_broadcast(&js->finished);
}

/* Drops finished jobs older than keep_seconds, then the oldest finished ones beyond
 * keep_done. */
static void evict(ljgap_jobs *js)
{
    double now = ljgap_now();
    for (job *j = js->head, *next; j; j = next) {
        next = j->next;
        if (j->state >= JOB_DONE && now - j->t_end > js->cfg.keep_seconds) {
            unlink_job(js, j);
            js->n_finished--;
            job_free(j);
        }
    }
    while (js->n_finished > js->cfg.keep_done) {
        job *oldest = NULL;
        for (job *j = js->head; j; j = j->next)
            if (j->state >= JOB_DONE && (!oldest || j->t_end < oldest->t_end)) oldest = j;
        unlink_job(js, oldest);
        js->n_finished--;
        job_free(oldest);
    }
}

/* The status object of j as a malloc'd string, or NULL. */
static char *status_json(const job *j)
{
    double run_s = j->state == JOB_QUEUED    ? 0
                   : j->state == JOB_RUNNING ? ljgap_now() - j->t_start
                                             : j->t_end - j->t_start;
    const char *key = j->state == JOB_DONE ? "result" : "problem";
    int has_reply = j->reply && j->state != JOB_QUEUED && j->state != JOB_RUNNING;
    char *s = NULL;
    int n = asprintf(
        &s, "{\"id\":\"%s\",\"status\":\"%s\",\"progress\":%.6g,\"elapsed_ms\":%.3f%s%s%s%s}",
        j->id, state_names[j->state], j->progress, j->t_start > 0 ? 1e3 * run_s : 0.0,
        has_reply ? ",\"" : "", has_reply ? key : "", has_reply ? "\":" : "",
        has_reply ? j->reply : "");
    return n < 0 ? NULL : s;
}

/* ---- workers ---- */

static void on_progress(void *ctx, double fraction)
{
    job *j = ctx;
    pthread_mutex_lock(&j->js->lock);
    if (fraction > j->progress) j->progress = fraction < 1 ? fraction : 1;
    pthread_mutex_unlock(&j->js->lock);
}

static job *first_queued(ljgap_jobs *js)
{
    for (job *j = js->head; j; j = j->next)
        if (j->state == JOB_QUEUED) return j;
    return NULL;
}

static void *worker(void *arg)
{
    ljgap_jobs *js = arg;
    pthread_mutex_lock(&js->lock);
    for (;;) {
        job *j;
        ljgap_reply rep = {0};
        ljgap_job_ctl ctl;
        char *body;
        job_state state;
        while (!js->stopping && !(j = first_queued(js)))
            pthread_cond_wait(&js->work, &js->lock);
        if (js->stopping) break;
        j->state = JOB_RUNNING;
        js->n_queued--;
        js->n_running++;
        j->t_start = ljgap_now();
        pthread_mutex_unlock(&js->lock);

        ctl.cancel = &j->cancel;
        ctl.progress = on_progress;
        ctl.ctx = j;
        j->run(j->arg, &ctl, &rep);
        body = rep.body ? strndup(rep.body, rep.len) : NULL;
        if (rep.status >= 200 && rep.status < 300 && body)
            state = JOB_DONE;
        else
            state = j->cancel ? JOB_CANCELLED : JOB_FAILED;

        pthread_mutex_lock(&js->lock);
        release_arg(j);
        finish(js, j, state, body ? rep.status : 500, body);
        ljgap_reply_free(&rep);
        evict(js);
    }
    pthread_mutex_unlock(&js->lock);
    return NULL;
}

/* ---- the interface ---- */

ljgap_jobs *ljgap_jobs_alloc(const ljgap_jobs_config *c)
{
    ljgap_jobs *js;
    pthread_condattr_t ca;
    if (!c || c->workers < 1 || c->queue_cap < 1 || !(c->keep_seconds >= 0)) return NULL;
    if (!(js = calloc(1, sizeof *js))) return NULL;
    js->cfg = *c;
    if (!(js->threads = calloc(c->workers, sizeof *js->threads))) {
        free(js);
        return NULL;
    }
    pthread_mutex_init(&js->lock, NULL);
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&js->work, &ca);
    pthread_cond_init(&js->finished, &ca);
    pthread_condattr_destroy(&ca);
    while (js->n_threads < c->workers &&
           pthread_create(&js->threads[js->n_threads], NULL, worker, js) == 0)
        js->n_threads++;
    if (js->n_threads < c->workers) {
        ljgap_jobs_free(js);
        return NULL;
    }
    return js;
}

/* A fresh random id not in use (lock held); 0 on success. */
static int new_id(ljgap_jobs *js, char id[LJGAP_JOB_ID_LEN + 1])
{
    unsigned char raw[LJGAP_JOB_ID_LEN / 2];
    do {
        size_t got = 0;
        while (got < sizeof raw) {
            ssize_t n = getrandom(raw + got, sizeof raw - got, 0);
            if (n < 0 && errno != EINTR) return -1;
            if (n > 0) got += (size_t)n;
        }
        for (size_t i = 0; i < sizeof raw; i++)
            sprintf(id + 2 * i, "%02x", raw[i]);
    } while (find(js, id));
    return 0;
}

int ljgap_jobs_submit(ljgap_jobs *js, ljgap_job_fn run, void *arg, void (*free_arg)(void *),
                      char id[LJGAP_JOB_ID_LEN + 1])
{
    job *j = calloc(1, sizeof *j);
    int st = LJGAP_JOBS_OK;
    id[0] = '\0';
    if (!j) {
        if (free_arg) free_arg(arg);
        return LJGAP_JOBS_NOMEM;
    }
    j->js = js;
    j->run = run;
    j->arg = arg;
    j->free_arg = free_arg;
    pthread_mutex_lock(&js->lock);
    evict(js);
    if (js->stopping)
        st = LJGAP_JOBS_STOPPING;
    else if (js->n_queued >= js->cfg.queue_cap)
        st = LJGAP_JOBS_FULL;
    else if (new_id(js, j->id) != 0)
        st = LJGAP_JOBS_NOMEM;
    if (st == LJGAP_JOBS_OK) {
        j->state = JOB_QUEUED;
        j->prev = js->tail;
        if (js->tail)
            js->tail->next = j;
        else
            js->head = j;
        js->tail = j;
        js->n_queued++;
        memcpy(id, j->id, sizeof j->id);
        pthread_cond_signal(&js->work);
    }
    pthread_mutex_unlock(&js->lock);
    if (st != LJGAP_JOBS_OK) job_free(j);
    return st;
}

int ljgap_jobs_status(ljgap_jobs *js, const char *id, char **json)
{
    job *j;
    int st = LJGAP_JOBS_OK;
    *json = NULL;
    pthread_mutex_lock(&js->lock);
    evict(js);
    if (!(j = find(js, id)))
        st = LJGAP_JOBS_UNKNOWN;
    else if (!(*json = status_json(j)))
        st = LJGAP_JOBS_NOMEM;
    pthread_mutex_unlock(&js->lock);
    return st;
}

/* Absolute CLOCK_MONOTONIC time s seconds from now. */
static struct timespec deadline_in(double s)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    if (!(s > 0)) return t;
    if (s > 1e6) s = 1e6;
    t.tv_sec += (time_t)s;
    t.tv_nsec += (long)((s - floor(s)) * 1e9);
    if (t.tv_nsec >= 1000000000L) {
        t.tv_sec++;
        t.tv_nsec -= 1000000000L;
    }
    return t;
}

int ljgap_jobs_cancel(ljgap_jobs *js, const char *id, double wait_s, char **json, int *final)
{
    struct timespec until = deadline_in(wait_s);
    job *j;
    int st = LJGAP_JOBS_OK;
    *json = NULL;
    *final = 0;
    pthread_mutex_lock(&js->lock);
    evict(js);
    j = find(js, id);
    if (j && j->state == JOB_QUEUED) {
        release_arg(j);
        finish(js, j, JOB_CANCELLED, 0, NULL);
    } else if (j && j->state == JOB_RUNNING) {
        j->cancel = 1;
        /* the job may finish and even be evicted while we wait: look it up again */
        while ((j = find(js, id)) && j->state == JOB_RUNNING &&
               pthread_cond_timedwait(&js->finished, &js->lock, &until) == 0)
            ;
        j = find(js, id);
    }
    if (!j) {
        st = LJGAP_JOBS_UNKNOWN;
    } else {
        *final = j->state != JOB_RUNNING;
        if (!(*json = status_json(j))) st = LJGAP_JOBS_NOMEM;
    }
    pthread_mutex_unlock(&js->lock);
    return st;
}

void ljgap_jobs_counts(ljgap_jobs *js, unsigned *queued, unsigned *running)
{
    pthread_mutex_lock(&js->lock);
    *queued = js->n_queued;
    *running = js->n_running;
    pthread_mutex_unlock(&js->lock);
}

void ljgap_jobs_shutdown(ljgap_jobs *js)
{
    pthread_mutex_lock(&js->lock);
    js->stopping = 1;
    for (job *j = js->head; j; j = j->next) {
        if (j->state == JOB_QUEUED) {
            release_arg(j);
            finish(js, j, JOB_CANCELLED, 0, NULL);
        } else if (j->state == JOB_RUNNING) {
            j->cancel = 1;
        }
    }
    pthread_cond_broadcast(&js->work);
    pthread_mutex_unlock(&js->lock);
}

int ljgap_jobs_wait_idle(ljgap_jobs *js, double wait_s)
{
    struct timespec until = deadline_in(wait_s);
    int idle;
    pthread_mutex_lock(&js->lock);
    while (js->n_running > 0 && pthread_cond_timedwait(&js->finished, &js->lock, &until) == 0)
        ;
    idle = js->n_running == 0;
    pthread_mutex_unlock(&js->lock);
    return idle;
}

void ljgap_jobs_free(ljgap_jobs *js)
{
    if (!js) return;
    ljgap_jobs_shutdown(js);
    for (unsigned t = 0; t < js->n_threads; t++)
        pthread_join(js->threads[t], NULL);
    for (job *j = js->head, *next; j; j = next) {
        next = j->next;
        job_free(j);
    }
    pthread_cond_destroy(&js->work);
    pthread_cond_destroy(&js->finished);
    pthread_mutex_destroy(&js->lock);
    free(js->threads);
    free(js);
}
