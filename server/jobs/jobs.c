/* jobs.c -- the daemon's background jobs (jobs.h): workers and a keeper around a job store.
 *
 * The store (jobstore.h) holds every job; this file only runs them. Each worker owns a slot
 * that says what it runs now (id, claim, cancel flag, latest progress). A worker claims the
 * oldest job from the store, runs the kind's function on the stored body without any lock
 * held, and writes the answer back; then it evicts what expired and claims again. Idle
 * workers sleep on a condition variable that a submit in this process signals, and look at
 * the store every poll_seconds anyway (jobs queued by another process sharing the store, a
 * lapsed lease).
 *
 * The keeper thread does the store I/O of running jobs, so the computation's progress
 * callback only stores a number: every tick it writes a slot's progress when it rose (at most
 * every progress_seconds), renews the lease every third of it, and reads back a cancel asked
 * through the store. A cancel asked in this process raises the slot's flag at once.
 *
 * One mutex guards the slots and the flags; the computation reads its slot's `cancel`
 * without it (the core's volatile cancel flag). Store calls are never made with the mutex
 * held. Two condition variables on CLOCK_MONOTONIC: `work` (a job was submitted here, or
 * stopping) and `finished` (a job running here returned, or the keeper must wake).
 */
#include "clock.h"
#include "jobs.h"
#include "jobstatus.h"
#include "ljgap.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define EVICT_SECONDS 5.0  /* the keeper evicts expired jobs this often */
#define LOG_SECONDS 10.0   /* at most one store error logged per this many seconds */
#define FINISH_RETRY_S 0.5 /* a failed write of a job's end is tried again this often */

typedef struct slot {
    struct ljgap__jobs *js;         /* the runner (for the progress callback) */
    int busy;                      /* a job runs in this slot */
    char id[LJGAP_JOB_ID_LEN + 1]; /* its id */
    long run;                      /* its claim (the lease token) */
    volatile int cancel;           /* raised by cancel or shutdown; read by the run unlocked */
    int asked;                     /* a cancel was asked (here or through the store) */
    int lost;                      /* the store gave the job to someone else */
    double progress;               /* latest fraction reported, 0..1 */
    double written;                /* progress last written to the store */
    double renewed;                /* ljgap__clock_now() at the last renewal (0: due) */
} slot;

struct ljgap__jobs {
    ljgap__jobs_config cfg;   /* as given, checked */
    ljgap__jobstore *store;   /* the caller's */
    ljgap__job_kind *kinds;   /* copied at alloc */
    size_t nkinds;           /* entries in kinds */
    char owner[96];          /* host:pid, the name claims are made under */
    pthread_mutex_t lock;    /* guards everything below */
    pthread_cond_t work;     /* a job was submitted here, or stopping */
    pthread_cond_t finished; /* a job running here returned, or the keeper must quit */
    unsigned long submitted; /* jobs submitted here so far (a worker's claim saw up to...) */
    int stopping;            /* ljgap__jobs_shutdown was called */
    int keeper_quit;         /* the keeper must return */
    double logged;           /* ljgap__clock_now() of the last store error logged */
    slot *slots;             /* one per worker */
    pthread_t *threads;      /* the workers */
    unsigned n_threads;      /* workers started */
    pthread_t keeper;        /* the keeper */
    int keeper_started;      /* it was started */
};

void ljgap__jobs_config_default(ljgap__jobs_config *c)
{
    c->workers = 1;
    c->queue_cap = 8;
    c->keep_done = 64;
    c->keep_seconds = 3600.0;
    c->lease_seconds = 30.0;
    c->progress_seconds = 0.5;
    c->poll_seconds = 1.0;
    c->max_lost = 3;
}

/* Logs a store failure (what + the store's reason), at most once per LOG_SECONDS. */
static void log_store(ljgap__jobs *js, const char *what, const char *id)
{
    double now = ljgap__clock_now();
    int say;
    pthread_mutex_lock(&js->lock);
    say = js->logged == 0 || now - js->logged >= LOG_SECONDS;
    if (say) js->logged = now;
    pthread_mutex_unlock(&js->lock);
    if (say)
        fprintf(stderr, "ljgapd: job store: %s%s%s: %s\n", what, id ? " " : "", id ? id : "",
                ljgap__jobstore_errmsg());
}

static int map_store(int st)
{
    switch (st) {
    case LJGAP_JOBSTORE_OK:
        return LJGAP_JOBS_OK;
    case LJGAP_JOBSTORE_UNKNOWN:
        return LJGAP_JOBS_UNKNOWN;
    case LJGAP_JOBSTORE_FULL:
        return LJGAP_JOBS_FULL;
    case LJGAP_JOBSTORE_NOMEM:
        return LJGAP_JOBS_NOMEM;
    default:
        return LJGAP_JOBS_STORE;
    }
}

static const ljgap__job_kind *find_kind(const ljgap__jobs *js, const char *name)
{
    for (size_t i = 0; i < js->nkinds; i++)
        if (strcmp(js->kinds[i].name, name) == 0) return &js->kinds[i];
    return NULL;
}

/* ---- workers ---- */

static void on_progress(void *ctx, double fraction)
{
    slot *sl = ctx;
    pthread_mutex_lock(&sl->js->lock);
    if (fraction > sl->progress) sl->progress = fraction < 1 ? fraction : 1;
    pthread_mutex_unlock(&sl->js->lock);
}

/* Writes the end of claim rec: finish in state with answer (may be NULL). While the store
 * fails (a database that went away), it is tried again every FINISH_RETRY_S for as long as the
 * claim's lease could still hold (the keeper renews it meanwhile, once the store is back); after
 * that another daemon may run the job again, and the run guard drops this answer anyway. A
 * shutdown stops the retries: the job then runs again once its lease lapses. */
static void finish(ljgap__jobs *js, const ljgap__job_record *rec, ljgap__job_state state,
                   const char *answer)
{
    double until = ljgap__clock_now() + js->cfg.lease_seconds;
    int st, failed = 0, stopping = 0;
    for (;;) {
        st = ljgap__jobstore_finish(js->store, rec->id, rec->run, state, answer,
                                   answer ? strlen(answer) : 0);
        if (st != LJGAP_JOBSTORE_ERROR || stopping || ljgap__clock_now() >= until) break;
        if (!failed) log_store(js, "cannot write the end of job (trying again)", rec->id);
        failed = 1;
        pthread_mutex_lock(&js->lock);
        if (!js->stopping) {
            struct timespec t = ljgap__deadline_in(FINISH_RETRY_S);
            pthread_cond_timedwait(&js->work, &js->lock, &t);
        }
        stopping = js->stopping;
        pthread_mutex_unlock(&js->lock);
    }
    if (st == LJGAP_JOBSTORE_LOST)
        fprintf(stderr,
                failed ? "ljgapd: job %s: its end was written while the job store failed, or its "
                         "lease lapsed meanwhile and it was claimed again\n"
                       : "ljgapd: job %s: its lease lapsed and it was claimed again; this run's "
                         "answer is dropped\n",
                rec->id);
    else if (st != LJGAP_JOBSTORE_OK)
        log_store(js, "cannot write the end of job", rec->id);
    else if (failed)
        fprintf(stderr, "ljgapd: job %s: its end was written once the job store was back\n",
                rec->id);
    if (ljgap__jobstore_evict(js->store, js->cfg.keep_done, js->cfg.keep_seconds, NULL) !=
        LJGAP_JOBSTORE_OK)
        log_store(js, "cannot evict finished jobs", NULL);
}

/* Finishes rec failed with a 500 problem of type slug. */
static void finish_problem(ljgap__jobs *js, const ljgap__job_record *rec, const char *slug,
                           const char *title, const char *detail)
{
    char *p = ljgap__job_problem(500, slug, title, detail);
    finish(js, rec, LJGAP_JOB_FAILED, p); /* NULL (out of memory): failed without a problem */
    free(p);
}

/* Runs claimed job rec in slot sl and writes its end. */
static void execute(ljgap__jobs *js, slot *sl, const ljgap__job_record *rec)
{
    const ljgap__job_kind *kind = find_kind(js, rec->kind);
    ljgap__job_ctl ctl = {&sl->cancel, on_progress, sl};
    ljgap__reply rep = {0};
    char detail[300];
    int asked, lost, stopping, done, ok;

    if (rec->cancel) { /* asked while a lost run had it */
        finish(js, rec, LJGAP_JOB_CANCELLED, NULL);
        return;
    }
    if (js->cfg.max_lost && rec->lost >= (long)js->cfg.max_lost) {
        snprintf(detail, sizeof detail,
                 "the job was started %ld times and each time the server stopped before it "
                 "finished (a crash or a kill); it is not run again: see the server's log, and "
                 "submit the request anew",
                 rec->lost);
        finish_problem(js, rec, "job-abandoned", "Job abandoned", detail);
        return;
    }
    if (!kind) {
        snprintf(detail, sizeof detail,
                 "the stored record of this job is damaged (its kind \"%.40s\" is not one this "
                 "server runs); it cannot be shown or run again: submit the request anew",
                 rec->kind);
        finish_problem(js, rec, "job-damaged", "Damaged job record", detail);
        return;
    }
    kind->run(kind->ctx, rec->request, rec->request_len, &ctl, &rep);

    pthread_mutex_lock(&js->lock);
    asked = sl->asked;
    lost = sl->lost;
    stopping = js->stopping;
    pthread_mutex_unlock(&js->lock);
    done = rep.status >= 200 && rep.status < 300;
    ok = rep.body && ljgap__job_answer_ok(rep.body, rep.len, !done);
    if (lost) {
        fprintf(stderr,
                "ljgapd: job %s: its lease lapsed and it was claimed again; this run "
                "stopped\n",
                rec->id);
    } else if (ok && done) {
        finish(js, rec, LJGAP_JOB_DONE, rep.body);
    } else if (asked) {
        finish(js, rec, LJGAP_JOB_CANCELLED, ok ? rep.body : NULL);
    } else if (stopping) { /* stopped by the shutdown: it runs again at the next start */
        if (ljgap__jobstore_release(js->store, rec->id, rec->run) == LJGAP_JOBSTORE_ERROR)
            log_store(js, "cannot put back job", rec->id);
    } else if (ok) {
        finish(js, rec, LJGAP_JOB_FAILED, rep.body);
    } else {
        finish_problem(js, rec, rep.body ? "job-damaged" : "out-of-memory",
                       rep.body ? "Damaged job record" : "Out of memory",
                       rep.body ? "the job's run gave an answer that is not one JSON object "
                                  "(or not a problem document)"
                                : "the job ran out of memory");
    }
    ljgap__reply_free(&rep);
}

static void *worker(void *arg)
{
    slot *sl = arg;
    ljgap__jobs *js = sl->js;
    pthread_mutex_lock(&js->lock);
    while (!js->stopping) {
        ljgap__job_record rec;
        unsigned long seen = js->submitted;
        int st;
        pthread_mutex_unlock(&js->lock);
        st = ljgap__jobstore_claim(js->store, js->owner, js->cfg.lease_seconds, &rec);
        if (st != LJGAP_JOBSTORE_OK && st != LJGAP_JOBSTORE_EMPTY) log_store(js, "claim", NULL);
        pthread_mutex_lock(&js->lock);
        if (st != LJGAP_JOBSTORE_OK) {
            struct timespec until = ljgap__deadline_in(js->cfg.poll_seconds);
            if (!js->stopping && js->submitted == seen)
                pthread_cond_timedwait(&js->work, &js->lock, &until);
            continue;
        }
        if (js->stopping) { /* claimed as we stop: give it back untouched */
            pthread_mutex_unlock(&js->lock);
            ljgap__jobstore_release(js->store, rec.id, rec.run);
            ljgap__job_record_clear(&rec);
            pthread_mutex_lock(&js->lock);
            break;
        }
        sl->busy = 1;
        memcpy(sl->id, rec.id, sizeof sl->id);
        sl->run = rec.run;
        sl->cancel = 0;
        sl->asked = sl->lost = 0;
        sl->progress = sl->written = 0;
        sl->renewed = 0; /* renewed at the keeper's next tick: a cancel asked between the claim
                          * and now (the slot was not busy yet) is seen within a tick */
        pthread_mutex_unlock(&js->lock);

        execute(js, sl, &rec);
        ljgap__job_record_clear(&rec);

        pthread_mutex_lock(&js->lock);
        sl->busy = 0;
        pthread_cond_broadcast(&js->finished);
    }
    pthread_mutex_unlock(&js->lock);
    return NULL;
}

/* ---- the keeper ---- */

/* Renews slot sl if it is due (lock held; released around the store call). */
static void keep_slot(ljgap__jobs *js, slot *sl, double now)
{
    char id[LJGAP_JOB_ID_LEN + 1];
    long run = sl->run;
    double progress = sl->progress;
    int cancel = 0, st;
    if (!(sl->busy && !sl->lost &&
          ((progress > sl->written && now - sl->renewed >= js->cfg.progress_seconds) ||
           now - sl->renewed >= js->cfg.lease_seconds / 3)))
        return;
    memcpy(id, sl->id, sizeof id);
    pthread_mutex_unlock(&js->lock);
    st = ljgap__jobstore_renew(js->store, id, run, progress, js->cfg.lease_seconds, &cancel);
    if (st != LJGAP_JOBSTORE_OK && st != LJGAP_JOBSTORE_LOST) log_store(js, "renew", id);
    pthread_mutex_lock(&js->lock);
    if (!sl->busy || sl->run != run || strcmp(sl->id, id) != 0) return; /* it ended meanwhile */
    if (st == LJGAP_JOBSTORE_OK) {
        sl->written = progress;
        sl->renewed = now;
        if (cancel) sl->asked = sl->cancel = 1;
    } else if (st == LJGAP_JOBSTORE_LOST) {
        sl->lost = sl->cancel = 1;
    }
}

static void *keeper(void *arg)
{
    ljgap__jobs *js = arg;
    double tick = fmin(js->cfg.progress_seconds, js->cfg.lease_seconds / 3) / 2;
    double next_evict = ljgap__clock_now() + EVICT_SECONDS;
    pthread_mutex_lock(&js->lock);
    while (!js->keeper_quit) {
        struct timespec until = ljgap__deadline_in(tick);
        double now;
        pthread_cond_timedwait(&js->finished, &js->lock, &until);
        now = ljgap__clock_now();
        for (unsigned w = 0; w < js->n_threads && !js->keeper_quit; w++)
            keep_slot(js, &js->slots[w], now);
        if (now >= next_evict && !js->keeper_quit) {
            int st;
            next_evict = now + EVICT_SECONDS;
            pthread_mutex_unlock(&js->lock);
            st = ljgap__jobstore_evict(js->store, js->cfg.keep_done, js->cfg.keep_seconds, NULL);
            if (st != LJGAP_JOBSTORE_OK) log_store(js, "cannot evict finished jobs", NULL);
            pthread_mutex_lock(&js->lock);
        }
    }
    pthread_mutex_unlock(&js->lock);
    return NULL;
}

/* ---- the interface ---- */

ljgap__jobs *ljgap__jobs_alloc(const ljgap__jobs_config *c, ljgap__jobstore *store,
                             const ljgap__job_kind *kinds, size_t nkinds)
{
    ljgap__jobs *js;
    char host[64] = "localhost";
    if (!c || !store || !kinds || !nkinds || c->workers < 1 || c->queue_cap < 1 ||
        !(c->keep_seconds >= 0) || !(c->lease_seconds > 0 && c->lease_seconds <= 86400) ||
        !(c->progress_seconds > 0 && c->progress_seconds <= 3600) ||
        !(c->poll_seconds > 0 && c->poll_seconds <= 3600))
        return NULL;
    for (size_t i = 0; i < nkinds; i++)
        if (!ljgap__job_kind_valid(kinds[i].name) || !kinds[i].run) return NULL;
    if (!(js = calloc(1, sizeof *js))) return NULL;
    js->cfg = *c;
    js->store = store;
    js->nkinds = nkinds;
    if (!(js->kinds = malloc(nkinds * sizeof *kinds)) ||
        !(js->slots = calloc(c->workers, sizeof *js->slots)) ||
        !(js->threads = calloc(c->workers, sizeof *js->threads))) {
        free(js->kinds);
        free(js->slots);
        free(js);
        return NULL;
    }
    memcpy(js->kinds, kinds, nkinds * sizeof *kinds);
    gethostname(host, sizeof host - 1);
    host[sizeof host - 1] = '\0';
    snprintf(js->owner, sizeof js->owner, "%s:%ld", host, (long)getpid());
    pthread_mutex_init(&js->lock, NULL);
    ljgap__cond_init_monotonic(&js->work);
    ljgap__cond_init_monotonic(&js->finished);
    for (unsigned w = 0; w < c->workers; w++)
        js->slots[w].js = js;
    while (js->n_threads < c->workers && pthread_create(&js->threads[js->n_threads], NULL, worker,
                                                        &js->slots[js->n_threads]) == 0)
        js->n_threads++;
    js->keeper_started =
        js->n_threads == c->workers && pthread_create(&js->keeper, NULL, keeper, js) == 0;
    if (!js->keeper_started) {
        ljgap__jobs_free(js);
        return NULL;
    }
    return js;
}

int ljgap__jobs_submit(ljgap__jobs *js, const char *kind, const char *body, size_t len,
                      char id[LJGAP_JOB_ID_LEN + 1])
{
    char fresh[LJGAP_JOB_ID_LEN + 1];
    int st = LJGAP_JOBSTORE_EXISTS, stopping;
    id[0] = '\0';
    pthread_mutex_lock(&js->lock);
    stopping = js->stopping;
    pthread_mutex_unlock(&js->lock);
    if (stopping) return LJGAP_JOBS_STOPPING;
    if (!find_kind(js, kind)) {
        ljgap__jobstore_set_errmsg("no job kind \"%.40s\"", kind);
        return LJGAP_JOBS_STORE;
    }
    /* 128 random bits: a second try is for the record, not for the odds */
    for (int i = 0; i < 3 && st == LJGAP_JOBSTORE_EXISTS; i++) {
        if (ljgap__job_id_new(fresh) != 0) {
            ljgap__jobstore_set_errmsg("no random bits for a job id");
            return LJGAP_JOBS_STORE;
        }
        st = ljgap__jobstore_create(js->store, fresh, kind, body, len, js->cfg.queue_cap);
    }
    if (st != LJGAP_JOBSTORE_OK) return map_store(st);
    memcpy(id, fresh, sizeof fresh);
    pthread_mutex_lock(&js->lock);
    js->submitted++;
    pthread_cond_broadcast(&js->work);
    pthread_mutex_unlock(&js->lock);
    return LJGAP_JOBS_OK;
}

/* Has finished job rec outlived keep_seconds? (Eviction removes it soon; until then it is
 * not shown.) */
static int expired(const ljgap__jobs *js, const ljgap__job_record *rec)
{
    return rec->state >= LJGAP_JOB_DONE && rec->finished > 0 &&
           rec->now - rec->finished > js->cfg.keep_seconds;
}

/* The status of rec into *json; the status code. */
static int render(ljgap__jobs *js, const ljgap__job_record *rec, char **json)
{
    if (expired(js, rec)) return LJGAP_JOBS_UNKNOWN;
    return (*json = ljgap__job_status_json(rec)) ? LJGAP_JOBS_OK : LJGAP_JOBS_NOMEM;
}

int ljgap__jobs_status(ljgap__jobs *js, const char *id, char **json)
{
    ljgap__job_record rec;
    int st;
    *json = NULL;
    st = map_store(ljgap__jobstore_get(js->store, id, &rec));
    if (st == LJGAP_JOBS_OK) st = render(js, &rec, json);
    ljgap__job_record_clear(&rec);
    return st;
}

int ljgap__jobs_cancel(ljgap__jobs *js, const char *id, double wait_s, char **json, int *final)
{
    double until = ljgap__clock_now() + (wait_s > 0 ? fmin(wait_s, 1e6) : 0);
    ljgap__job_record rec;
    int st;
    *json = NULL;
    *final = 0;
    st = map_store(ljgap__jobstore_cancel(js->store, id, &rec));
    if (st == LJGAP_JOBS_OK && rec.state == LJGAP_JOB_RUNNING) {
        pthread_mutex_lock(&js->lock);
        for (unsigned w = 0; w < js->n_threads; w++) {
            slot *sl = &js->slots[w];
            if (sl->busy && strcmp(sl->id, rec.id) == 0) sl->asked = sl->cancel = 1;
        }
        pthread_mutex_unlock(&js->lock);
    }
    while (st == LJGAP_JOBS_OK && rec.state == LJGAP_JOB_RUNNING && ljgap__clock_now() < until) {
        /* woken when a job here returns; a job running elsewhere is looked at every 0.1 s */
        struct timespec t = ljgap__deadline_in(fmin(until - ljgap__clock_now(), 0.1));
        pthread_mutex_lock(&js->lock);
        pthread_cond_timedwait(&js->finished, &js->lock, &t);
        pthread_mutex_unlock(&js->lock);
        ljgap__job_record_clear(&rec);
        st = map_store(ljgap__jobstore_get(js->store, id, &rec));
    }
    if (st == LJGAP_JOBS_OK) {
        *final = rec.state != LJGAP_JOB_RUNNING && rec.state != LJGAP_JOB_QUEUED;
        st = render(js, &rec, json);
    }
    ljgap__job_record_clear(&rec);
    return st;
}

int ljgap__jobs_counts(ljgap__jobs *js, unsigned *queued, unsigned *running)
{
    return map_store(ljgap__jobstore_counts(js->store, queued, running));
}

void ljgap__jobs_shutdown(ljgap__jobs *js)
{
    pthread_mutex_lock(&js->lock);
    js->stopping = 1;
    for (unsigned w = 0; w < js->n_threads; w++)
        if (js->slots[w].busy) js->slots[w].cancel = 1;
    pthread_cond_broadcast(&js->work);
    pthread_mutex_unlock(&js->lock);
}

static int any_busy(const ljgap__jobs *js)
{
    for (unsigned w = 0; w < js->n_threads; w++)
        if (js->slots[w].busy) return 1;
    return 0;
}

int ljgap__jobs_wait_idle(ljgap__jobs *js, double wait_s)
{
    struct timespec until = ljgap__deadline_in(wait_s);
    int idle;
    pthread_mutex_lock(&js->lock);
    while (any_busy(js) && pthread_cond_timedwait(&js->finished, &js->lock, &until) == 0)
        ;
    idle = !any_busy(js);
    pthread_mutex_unlock(&js->lock);
    return idle;
}

void ljgap__jobs_free(ljgap__jobs *js)
{
    if (!js) return;
    ljgap__jobs_shutdown(js);
    for (unsigned t = 0; t < js->n_threads; t++)
        pthread_join(js->threads[t], NULL);
    if (js->keeper_started) {
        pthread_mutex_lock(&js->lock);
        js->keeper_quit = 1;
        pthread_cond_broadcast(&js->finished);
        pthread_mutex_unlock(&js->lock);
        pthread_join(js->keeper, NULL);
    }
    pthread_cond_destroy(&js->work);
    pthread_cond_destroy(&js->finished);
    pthread_mutex_destroy(&js->lock);
    free(js->threads);
    free(js->slots);
    free(js->kinds);
    free(js);
}
