/* jobstore_pg_conn.h -- what the PostgreSQL job store's two files share (jobstore_pg.c: the
 * operations, rows, opening; jobstore_pg_conn.c: connections and messages). Private to them.
 */
#ifndef LJGAP_JOBSTORE_PG_CONN_H
#define LJGAP_JOBSTORE_PG_CONN_H

#include "jobstore.h"

#include <libpq-fe.h>
#include <pthread.h>

#define OP_S 5.0    /* the longest an operation waits for the database */
#define RETRY_S 1.0 /* while the database is down, a new connection is tried this often */
#define SECRETS 4   /* forms of the password scrubbed from messages */
#define MSG_MAX 400

typedef struct {
    ljgap__jobstore base;   /* the operations; first, so a ljgap__jobstore * points here */
    pthread_mutex_t lock;  /* guards the pool and the down state below */
    pthread_cond_t freed;  /* a connection was given back, or the store went down */
    PGconn **idle;         /* connections not in use (max of them at most) */
    unsigned n_idle;       /* entries in idle */
    unsigned open;         /* connections open or being opened, in use or idle */
    unsigned max;          /* most connections open at once */
    int down;              /* connecting failed or the database stopped answering */
    int probing;           /* a thread is trying to connect while down */
    double retry_at;       /* while down: when the next connection may be tried */
    char reason[MSG_MAX];  /* while down: why */
    const char *keys[12];  /* libpq connection keywords ... */
    const char *vals[12];  /* ... and values, the URL last but one */
    char *url;             /* the URL as given */
    char *safe;            /* postgresql://user@host:port/dbname: for messages */
    char *secret[SECRETS]; /* the password as given and decoded, or NULL */
} pg_store;

typedef enum { X_OK, X_BROKEN, X_TIMEOUT } exec_fail;

/* msg on one line, the password scrubbed, into out (cap bytes). */
void pgs_clean_msg(const pg_store *s, const char *msg, char *out, size_t cap);
/* The forms of url's password to scrub from messages, into s->secret. */
void pgs_find_secrets(pg_store *s, const char *url);
/* A hex digit's value, -1 for another character. */
int pgs_hexval(char c);
/* The value of key among libpq's parsed options, or NULL. */
const char *pgs_opt(const PQconninfoOption *o, const char *key);
/* One statement on c, waiting no longer than deadline; NULL with *fail on failure. */
PGresult *pgs_exec(PGconn *c, const char *sql, int nparams, const char *const *vals,
                   const int *lens, const int *fmts, double deadline, exec_fail *fail);
/* A new connection with the session settings, or NULL with why. */
PGconn *pgs_connect(pg_store *s, double deadline, char *why, size_t cap);
/* Gives c back to the pool (closed when fail says it broke). */
void pgs_give(pg_store *s, PGconn *c, exec_fail fail);
/* An operation (what, for messages): a connection from the pool, the statement, one retry on a
 * broken connection when retry; NULL with *st the store's status on failure. */
PGresult *pgs_run(pg_store *s, const char *what, const char *sql, int n, const char *const *vals,
                  const char *request, size_t request_len, ExecStatusType want, int retry, int *st);
/* The rows a statement changed. */
long pgs_changed(PGresult *res);

#endif
