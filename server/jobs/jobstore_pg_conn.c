/* jobstore_pg_conn.c -- the PostgreSQL job store's connections (jobstore_pg_conn.h): a small
 * pool of libpq connections with a deadline on every operation, the store's down state (one
 * thread probes while the others answer at once), and messages on one line with the password
 * scrubbed. The operations, the rows and the opening are jobstore_pg.c's.
 */
#include "clock.h"
#include "jobstore.h"
#include "jobstore_pg_conn.h"
#include "ljgap.h"

#include <errno.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Session settings of every connection: the server gives up when we do; bytea in hex and
 * floats in full precision, which is what ljgap__jobstore_pg_row reads. */
static const char sql_session[] =
    "SET statement_timeout = 5000; SET lock_timeout = 4000; SET bytea_output = 'hex'; "
    "SET extra_float_digits = 3";

/* ---- messages: one line, no password ---- */

/* Copies msg into out (cap bytes) on one line (runs of newlines, tabs and spaces become one
 * space, trailing space dropped) with every form of the password replaced by "***". */
void pgs_clean_msg(const pg_store *s, const char *msg, char *out, size_t cap)
{
    size_t o = 0;
    if (!cap) return;
    for (const char *p = msg ? msg : ""; *p && o + 1 < cap;) {
        size_t hit = 0;
        for (int i = 0; i < SECRETS && !hit; i++)
            if (s->secret[i] && s->secret[i][0] &&
                strncmp(p, s->secret[i], strlen(s->secret[i])) == 0)
                hit = strlen(s->secret[i]);
        if (hit) {
            for (const char *r = "***"; *r && o + 1 < cap; r++)
                out[o++] = *r;
            p += hit;
            continue;
        }
        if (*p == '\n' || *p == '\t' || *p == '\r' || *p == ' ') {
            if (o > 0 && out[o - 1] != ' ') out[o++] = ' ';
        } else {
            out[o++] = *p;
        }
        p++;
    }
    while (o > 0 && out[o - 1] == ' ')
        o--;
    out[o] = '\0';
}

/* Sets the calling thread's error: "<where>: <what>: <why>". */
static void set_error(const pg_store *s, const char *what, const char *why)
{
    char clean[MSG_MAX];
    pgs_clean_msg(s, why, clean, sizeof clean);
    ljgap__jobstore_set_errmsg("%s: %s: %s", s->safe, what, clean);
}

int pgs_hexval(char c)
{
    return c >= '0' && c <= '9'   ? c - '0'
           : c >= 'a' && c <= 'f' ? c - 'a' + 10
           : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                  : -1;
}

/* A malloc'd copy of the percent-decoded s[0..n) (invalid escapes kept as they are). */
static char *pct_decode(const char *s, size_t n)
{
    char *d = malloc(n + 1), *o = d;
    if (!d) return NULL;
    for (size_t i = 0; i < n; i++) {
        if (s[i] == '%' && i + 2 < n && pgs_hexval(s[i + 1]) >= 0 && pgs_hexval(s[i + 2]) >= 0) {
            *o++ = (char)(pgs_hexval(s[i + 1]) * 16 + pgs_hexval(s[i + 2]));
            i += 2;
        } else {
            *o++ = s[i];
        }
    }
    *o = '\0';
    return d;
}

/* Finds the password in url however it is written (user:PASSWORD@ in the authority, or a
 * password= query parameter; raw and percent-decoded), so that no message shows it, whether or
 * not libpq can parse the URL. */
void pgs_find_secrets(pg_store *s, const char *url)
{
    const char *auth = strstr(url, "://"), *end, *at = NULL, *colon, *q;
    int n = 0;
    if (auth) {
        auth += 3;
        end = auth + strcspn(auth, "/?#");
        for (const char *p = auth; p < end; p++)
            if (*p == '@') at = p;
        colon = at ? memchr(auth, ':', (size_t)(at - auth)) : NULL;
        if (colon && at > colon + 1) {
            s->secret[n++] = strndup(colon + 1, (size_t)(at - colon - 1));
            s->secret[n++] = pct_decode(colon + 1, (size_t)(at - colon - 1));
        }
    }
    for (q = strstr(url, "password="); q && n + 2 <= SECRETS; q = strstr(q + 1, "password=")) {
        const char *v = q + strlen("password=");
        size_t len = strcspn(v, "&#");
        if (len) {
            s->secret[n++] = strndup(v, len);
            s->secret[n++] = pct_decode(v, len);
        }
    }
}

/* The option named key of a parsed conninfo, or NULL when unset or empty. */
const char *pgs_opt(const PQconninfoOption *o, const char *key)
{
    for (; o && o->keyword; o++)
        if (strcmp(o->keyword, key) == 0) return o->val && o->val[0] ? o->val : NULL;
    return NULL;
}

/* ---- connections ---- */

static void quiet(void *arg, const char *message)
{
    (void)arg, (void)message; /* notices (and a FATAL before a close) are no log lines of ours */
}

/* Waits until fd is ready for events or deadline (ljgap__clock_now) passes: 1 ready, 0 timed out, -1
 * a bad descriptor. */
static int wait_socket(int fd, short events, double deadline)
{
    struct pollfd p = {fd, events, 0};
    if (fd < 0) return -1;
    for (;;) {
        double left = deadline - ljgap__clock_now();
        int rc;
        if (left <= 0) return 0;
        rc = poll(&p, 1, (int)ceil(left * 1e3));
        if (rc > 0) return 1;
        if (rc == 0) return 0;
        if (errno != EINTR) return -1;
    }
}

/* Runs sql (with nparams >= 0 one statement with parameters; with nparams < 0 a text of
 * statements without) on c, waiting at most until deadline. Returns its result (the first that
 * failed, else the last) with *fail X_OK; NULL with X_BROKEN when the connection broke (or
 * memory ran out), X_TIMEOUT when the deadline passed; the connection is then unusable. */
PGresult *pgs_exec(PGconn *c, const char *sql, int nparams, const char *const *vals,
                   const int *lens, const int *fmts, double deadline, exec_fail *fail)
{
    PGresult *res = NULL, *r;
    int sent = nparams < 0 ? PQsendQuery(c, sql)
                           : PQsendQueryParams(c, sql, nparams, NULL, vals, lens, fmts, 0);
    *fail = X_BROKEN;
    if (!sent) return NULL;
    for (int f; (f = PQflush(c)) != 0;) {
        int w;
        if (f < 0) return NULL;
        if ((w = wait_socket(PQsocket(c), POLLIN | POLLOUT, deadline)) <= 0) {
            *fail = w == 0 ? X_TIMEOUT : X_BROKEN;
            return NULL;
        }
        if (!PQconsumeInput(c)) return NULL;
    }
    for (;;) {
        int w;
        while (!PQisBusy(c)) {
            if (!(r = PQgetResult(c))) {
                if (res && PQstatus(c) == CONNECTION_OK) *fail = X_OK;
                if (*fail != X_OK) PQclear(res);
                return *fail == X_OK ? res : NULL;
            }
            if (res && PQresultStatus(res) == PGRES_FATAL_ERROR) {
                PQclear(r);
            } else {
                PQclear(res);
                res = r;
            }
        }
        if ((w = wait_socket(PQsocket(c), POLLIN, deadline)) <= 0 || !PQconsumeInput(c)) {
            *fail = w == 0 ? X_TIMEOUT : X_BROKEN;
            PQclear(res);
            return NULL;
        }
    }
}

/* Opens a connection by deadline, set up for pg_exec; NULL with the reason in why. */
PGconn *pgs_connect(pg_store *s, double deadline, char *why, size_t cap)
{
    PGconn *c = PQconnectStartParams(s->keys, s->vals, 1);
    PostgresPollingStatusType ps = PGRES_POLLING_WRITING;
    const char *enc;
    PGresult *res = NULL;
    exec_fail fail;

    if (!c) {
        snprintf(why, cap, "out of memory");
        return NULL;
    }
    while (PQstatus(c) != CONNECTION_BAD && ps != PGRES_POLLING_OK && ps != PGRES_POLLING_FAILED) {
        int w = wait_socket(PQsocket(c), ps == PGRES_POLLING_READING ? POLLIN : POLLOUT, deadline);
        if (w == 0) {
            snprintf(why, cap, "no connection within %.0f s", OP_S);
            PQfinish(c);
            return NULL;
        }
        ps = w < 0 ? PGRES_POLLING_FAILED : PQconnectPoll(c);
    }
    if (PQstatus(c) != CONNECTION_OK) goto fail;
    PQsetNoticeProcessor(c, quiet, NULL);
    if (PQserverVersion(c) < 90500) {
        snprintf(why, cap, "the server is PostgreSQL %d.%d; ljgapd needs 9.5 or newer",
                 PQserverVersion(c) / 10000, PQserverVersion(c) / 100 % 100);
        PQfinish(c);
        return NULL;
    }
    enc = PQparameterStatus(c, "server_encoding");
    if (!enc || strcmp(enc, "UTF8") != 0) {
        snprintf(why, cap,
                 "the database's encoding is %s; ljgapd keeps UTF-8 text in it and needs a UTF8 "
                 "database (createdb -E UTF8 -T template0 ...)",
                 enc ? enc : "unknown");
        PQfinish(c);
        return NULL;
    }
    if (PQsetnonblocking(c, 1) != 0 ||
        !(res = pgs_exec(c, sql_session, -1, NULL, NULL, NULL, deadline, &fail)) ||
        PQresultStatus(res) != PGRES_COMMAND_OK) {
        if (res) {
            snprintf(why, cap, "%s", PQresultErrorMessage(res));
            PQclear(res);
            PQfinish(c);
            return NULL;
        }
        if (fail == X_TIMEOUT) {
            snprintf(why, cap, "no answer within %.0f s", OP_S);
            PQfinish(c);
            return NULL;
        }
        goto fail;
    }
    PQclear(res);
    return c;
fail:
    snprintf(why, cap, "%s", PQerrorMessage(c));
    PQfinish(c);
    return NULL;
}

/* Marks the store down for RETRY_S with reason why (lock held). */
static void mark_down(pg_store *s, const char *why)
{
    s->down = 1;
    s->retry_at = ljgap__clock_now() + RETRY_S;
    pgs_clean_msg(s, why, s->reason, sizeof s->reason);
    pthread_cond_broadcast(&s->freed);
}

/* Is idle connection c still usable? Readable while idle means the server said something
 * unasked, which is what it does before closing (a restart, an administrator's kill). */
static int idle_alive(PGconn *c)
{
    struct pollfd p = {PQsocket(c), POLLIN, 0};
    if (PQstatus(c) != CONNECTION_OK || p.fd < 0) return 0;
    return poll(&p, 1, 0) == 0;
}

/* Takes a connection for an operation ending by deadline: an idle one, or a new one while
 * fewer than max are open. LJGAP_JOBSTORE_OK, or ERROR with the reason set (at once while the
 * store is down). */
static int take(pg_store *s, double deadline, PGconn **out)
{
    char why[MSG_MAX];
    *out = NULL;
    pthread_mutex_lock(&s->lock);
    for (;;) {
        if (s->n_idle) {
            PGconn *c = s->idle[--s->n_idle];
            if (idle_alive(c)) {
                pthread_mutex_unlock(&s->lock);
                *out = c;
                return LJGAP_JOBSTORE_OK;
            }
            s->open--;
            pthread_mutex_unlock(&s->lock);
            PQfinish(c); /* dead: the server closed it */
            pthread_mutex_lock(&s->lock);
            continue;
        }
        if (s->down && (s->probing || ljgap__clock_now() < s->retry_at)) {
            snprintf(why, sizeof why, "%s", s->reason);
            pthread_mutex_unlock(&s->lock);
            ljgap__jobstore_set_errmsg("%s: the database is unreachable (%s); trying again every "
                                      "%.0f s",
                                      s->safe, why, RETRY_S);
            return LJGAP_JOBSTORE_ERROR;
        }
        if (s->open < s->max) {
            int probe = s->down;
            PGconn *c;
            s->open++;
            s->probing |= probe;
            pthread_mutex_unlock(&s->lock);
            c = pgs_connect(s, deadline, why, sizeof why);
            pthread_mutex_lock(&s->lock);
            if (probe) s->probing = 0;
            if (!c) {
                s->open--;
                mark_down(s, why);
                pthread_mutex_unlock(&s->lock);
                set_error(s, "cannot connect", why);
                return LJGAP_JOBSTORE_ERROR;
            }
            s->down = 0;
            pthread_mutex_unlock(&s->lock);
            *out = c;
            return LJGAP_JOBSTORE_OK;
        }
        { /* every connection is in use: wait for one, or for the store to go down */
            struct timespec t;
            double left = deadline - ljgap__clock_now();
            if (left <= 0) {
                pthread_mutex_unlock(&s->lock);
                ljgap__jobstore_set_errmsg("%s: all %u connections stayed busy for %.0f s", s->safe,
                                          s->max, OP_S);
                return LJGAP_JOBSTORE_ERROR;
            }
            t = ljgap__deadline_in(left);
            pthread_cond_timedwait(&s->freed, &s->lock, &t);
        }
    }
}

/* Gives c back to the pool; or, with fail set, closes it (X_TIMEOUT also marks the store
 * down: the database does not answer). */
void pgs_give(pg_store *s, PGconn *c, exec_fail fail)
{
    pthread_mutex_lock(&s->lock);
    if (fail == X_OK && s->n_idle < s->max) {
        s->idle[s->n_idle++] = c;
        c = NULL;
    } else {
        s->open--;
        if (fail == X_TIMEOUT) {
            char why[64];
            snprintf(why, sizeof why, "no answer within %.0f s", OP_S);
            mark_down(s, why);
        }
    }
    pthread_cond_broadcast(&s->freed);
    pthread_mutex_unlock(&s->lock);
    PQfinish(c); /* NULL is fine */
}

/* Runs one statement with text parameters (request, if not NULL, is parameter 3 in binary)
 * on a pooled connection. Returns its result when its status is want; otherwise NULL with *st
 * set (EXISTS for a unique violation, else ERROR or NOMEM, with the reason set for this
 * thread). With retry, a connection that broke is replaced once and the statement run again. */
PGresult *pgs_run(pg_store *s, const char *what, const char *sql, int n, const char *const *vals,
                  const char *request, size_t request_len, ExecStatusType want, int retry, int *st)
{
    double deadline = ljgap__clock_now() + OP_S;
    const char *v[8];
    int lens[8] = {0}, fmts[8] = {0};
    PGresult *res;
    PGconn *c;
    exec_fail fail;
    const char *state;

    for (int i = 0; i < n; i++)
        v[i] = vals[i];
    if (request) {
        v[2] = request;
        lens[2] = (int)request_len;
        fmts[2] = 1;
    }
    for (;;) {
        if ((*st = take(s, deadline, &c)) != LJGAP_JOBSTORE_OK) return NULL;
        res = pgs_exec(c, sql, n, v, lens, fmts, deadline, &fail);
        if (fail == X_OK) break;
        {
            char why[MSG_MAX];
            if (fail == X_TIMEOUT)
                snprintf(why, sizeof why, "no answer within %.0f s", OP_S);
            else
                snprintf(why, sizeof why, "%s", PQerrorMessage(c));
            pgs_give(s, c, fail);
            if (fail == X_BROKEN && retry-- > 0 && ljgap__clock_now() < deadline) continue;
            set_error(s, what, why);
            *st = LJGAP_JOBSTORE_ERROR;
            return NULL;
        }
    }
    pgs_give(s, c, X_OK);
    if (PQresultStatus(res) == want) return res;
    state = PQresultErrorField(res, PG_DIAG_SQLSTATE);
    *st = state && strcmp(state, "23505") == 0   ? LJGAP_JOBSTORE_EXISTS
          : state && strcmp(state, "53200") == 0 ? LJGAP_JOBSTORE_NOMEM
          : !state && PQresultStatus(res) == PGRES_FATAL_ERROR &&
                  !strcmp(PQresultErrorMessage(res), "out of memory\n")
              ? LJGAP_JOBSTORE_NOMEM
              : LJGAP_JOBSTORE_ERROR;
    set_error(s, what,
              PQresultStatus(res) == PGRES_FATAL_ERROR ? PQresultErrorMessage(res)
                                                       : "unexpected answer from the server");
    PQclear(res);
    return NULL;
}

/* The number of rows a command changed (0 if it says nothing). */
long pgs_changed(PGresult *res)
{
    return strtol(PQcmdTuples(res), NULL, 10);
}
