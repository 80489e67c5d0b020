/* jobstore.c -- the job store's public calls (jobstore.h): argument checks, then the backend.
 *
 * Every backend gets its arguments checked here once (ids, kinds, states, leases, progress),
 * so each only has to do its database work. The helpers every backend and caller share live
 * here too: ids, state names, records, the per-thread error message and the wall clock.
 */
#include "jobstore.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>

static _Thread_local char errmsg[512]; /* the calling thread's last error */

const char *ljgap__jobstore_errmsg(void)
{
    return errmsg;
}

void ljgap__jobstore_set_errmsg(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(errmsg, sizeof errmsg, fmt, ap);
    va_end(ap);
}

static const char *const state_names[] = {"queued", "running", "done", "failed", "cancelled"};

const char *ljgap__job_state_name(ljgap__job_state s)
{
    return s >= LJGAP_JOB_QUEUED && s < LJGAP_JOB_BAD ? state_names[s] : NULL;
}

ljgap__job_state ljgap__job_state_parse(const char *s)
{
    for (int i = 0; s && i < LJGAP_JOB_BAD; i++)
        if (strcmp(s, state_names[i]) == 0) return (ljgap__job_state)i;
    return LJGAP_JOB_BAD;
}

int ljgap__job_id_new(char id[LJGAP_JOB_ID_LEN + 1])
{
    unsigned char raw[LJGAP_JOB_ID_LEN / 2];
    size_t got = 0;
    while (got < sizeof raw) {
        ssize_t n = getrandom(raw + got, sizeof raw - got, 0);
        if (n < 0 && errno != EINTR) return -1;
        if (n > 0) got += (size_t)n;
    }
    for (size_t i = 0; i < sizeof raw; i++)
        sprintf(id + 2 * i, "%02x", raw[i]);
    return 0;
}

int ljgap__job_id_valid(const char *s)
{
    return s && strlen(s) == LJGAP_JOB_ID_LEN && strspn(s, "0123456789abcdef") == LJGAP_JOB_ID_LEN;
}

int ljgap__job_kind_valid(const char *s)
{
    size_t n = s ? strlen(s) : 0;
    return n >= 1 && n <= LJGAP_JOB_KIND_MAX &&
           strspn(s, "abcdefghijklmnopqrstuvwxyz0123456789_") == n;
}

void ljgap__job_record_clear(ljgap__job_record *rec)
{
    if (!rec) return;
    free(rec->request);
    free(rec->answer);
    memset(rec, 0, sizeof *rec);
}

double ljgap__jobstore_wallclock(void)
{
    struct timespec t;
    clock_gettime(CLOCK_REALTIME, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* ---- the operations: check, then call the backend ---- */

static int bad(const char *what)
{
    ljgap__jobstore_set_errmsg("invalid argument: %s", what);
    return LJGAP_JOBSTORE_INVALID;
}

static int lease_ok(double lease_s)
{
    return lease_s > 0 && lease_s <= 86400.0;
}

void ljgap__jobstore_close(ljgap__jobstore *st)
{
    if (st) st->ops->close(st);
}

int ljgap__jobstore_create(ljgap__jobstore *st, const char *id, const char *kind, const char *request,
                          size_t len, unsigned max_queued)
{
    if (!ljgap__job_id_valid(id)) return bad("job id");
    if (!ljgap__job_kind_valid(kind)) return bad("job kind");
    if (!request && len) return bad("request");
    return st->ops->create(st, id, kind, request ? request : "", len, max_queued);
}

int ljgap__jobstore_claim(ljgap__jobstore *st, const char *owner, double lease_s,
                         ljgap__job_record *rec)
{
    memset(rec, 0, sizeof *rec);
    if (!owner || !lease_ok(lease_s)) return bad("owner or lease");
    return st->ops->claim(st, owner, lease_s, rec);
}

int ljgap__jobstore_renew(ljgap__jobstore *st, const char *id, long run, double progress,
                         double lease_s, int *cancel)
{
    *cancel = 0;
    if (!ljgap__job_id_valid(id) || !lease_ok(lease_s)) return bad("job id or lease");
    if (!(progress >= 0)) progress = 0; /* NaN too */
    if (progress > 1) progress = 1;
    return st->ops->renew(st, id, run, progress, lease_s, cancel);
}

int ljgap__jobstore_finish(ljgap__jobstore *st, const char *id, long run, ljgap__job_state state,
                          const char *answer, size_t answer_len)
{
    if (!ljgap__job_id_valid(id)) return bad("job id");
    if (state != LJGAP_JOB_DONE && state != LJGAP_JOB_FAILED && state != LJGAP_JOB_CANCELLED)
        return bad("a final state");
    if (answer && strlen(answer) != answer_len) return bad("answer length");
    return st->ops->finish(st, id, run, state, answer, answer ? answer_len : 0);
}

int ljgap__jobstore_release(ljgap__jobstore *st, const char *id, long run)
{
    if (!ljgap__job_id_valid(id)) return bad("job id");
    return st->ops->release(st, id, run);
}

int ljgap__jobstore_get(ljgap__jobstore *st, const char *id, ljgap__job_record *rec)
{
    memset(rec, 0, sizeof *rec);
    if (!ljgap__job_id_valid(id)) return LJGAP_JOBSTORE_UNKNOWN; /* no such job can exist */
    return st->ops->get(st, id, rec);
}

int ljgap__jobstore_cancel(ljgap__jobstore *st, const char *id, ljgap__job_record *rec)
{
    memset(rec, 0, sizeof *rec);
    if (!ljgap__job_id_valid(id)) return LJGAP_JOBSTORE_UNKNOWN;
    return st->ops->cancel(st, id, rec);
}

int ljgap__jobstore_counts(ljgap__jobstore *st, unsigned *queued, unsigned *running)
{
    *queued = *running = 0;
    return st->ops->counts(st, queued, running);
}

int ljgap__jobstore_evict(ljgap__jobstore *st, unsigned keep_done, double keep_seconds,
                         unsigned *evicted)
{
    unsigned dummy;
    if (!evicted) evicted = &dummy;
    *evicted = 0;
    if (!(keep_seconds >= 0)) return bad("keep_seconds");
    if (keep_seconds > 1e9) keep_seconds = 1e9;
    return st->ops->evict(st, keep_done, keep_seconds, evicted);
}
