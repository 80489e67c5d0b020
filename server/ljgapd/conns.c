/* conns.c -- connection records, the slow-sender sweeper and per-client counts (conns.h).
 *
 * The records form one doubly-linked list under one mutex. State changes are a lock and a
 * store; the sweeper walks the list every SWEEP_MS. Shutting a socket down (not closing it)
 * leaves the descriptor to libmicrohttpd, which reads the end of stream and closes it through
 * its usual path; the record is dropped then, by conns_close, under the same lock the sweeper
 * holds while it calls shutdown(2), so the sweeper never touches a descriptor that was closed
 * and reused.
 *
 * Per-client counts live in a small chained hash table of CLIENT_BUCKETS buckets; an entry
 * exists only while its count is positive, so the table holds at most one entry per request
 * in progress.
 */
#include "clock.h"
#include "conns.h"
#include "ljgap.h"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>

#define SWEEP_MS 100
#define CLIENT_BUCKETS 256
#define KEEPALIVE_IDLE_S 20 /* TCP keep-alive: first probe after this much silence */
#define KEEPALIVE_INTVL_S 10
#define KEEPALIVE_COUNT 3

enum { C_IDLE, C_RECEIVING, C_BUSY };

struct conn_rec {
    conn_rec *prev, *next;
    int fd;       /* the socket (libmicrohttpd's) */
    int state;    /* C_IDLE, C_RECEIVING or C_BUSY */
    double since; /* ljgap__clock_now() when it last became idle (or opened) */
    int cut;      /* the sweeper shut it down already */
};

typedef struct client_count {
    struct client_count *next;
    unsigned n; /* requests in progress */
    char key[]; /* the client key */
} client_count;

struct conns {
    double receive_s;
    pthread_mutex_t lock;
    pthread_cond_t quit_cv;
    int quit;
    conn_rec *head;
    conns_stats stats;
    client_count *buckets[CLIENT_BUCKETS];
    pthread_t sweeper;
    int has_sweeper;
};

static void *sweep_main(void *arg)
{
    conns *cs = arg;
    pthread_mutex_lock(&cs->lock);
    while (!cs->quit) {
        struct timespec until;
        double now = ljgap__clock_now();
        for (conn_rec *r = cs->head; r; r = r->next) {
            if (r->state == C_BUSY || r->cut || now - r->since <= cs->receive_s) continue;
            shutdown(r->fd, SHUT_RDWR);
            r->cut = 1;
            cs->stats.cut++;
        }
        until = ljgap__deadline_in(SWEEP_MS / 1000.0);
        pthread_cond_timedwait(&cs->quit_cv, &cs->lock, &until);
    }
    pthread_mutex_unlock(&cs->lock);
    return NULL;
}

conns *conns_start(double receive_s)
{
    conns *cs;
    if (!(receive_s > 0) || !(cs = calloc(1, sizeof *cs))) return NULL;
    cs->receive_s = receive_s;
    pthread_mutex_init(&cs->lock, NULL);
    ljgap__cond_init_monotonic(&cs->quit_cv);
    if (pthread_create(&cs->sweeper, NULL, sweep_main, cs) != 0) {
        conns_free(cs);
        return NULL;
    }
    cs->has_sweeper = 1;
    return cs;
}

conn_rec *conns_open(conns *cs, int fd)
{
    static const int on = 1, idle = KEEPALIVE_IDLE_S, intvl = KEEPALIVE_INTVL_S,
                     count = KEEPALIVE_COUNT;
    conn_rec *r = calloc(1, sizeof *r);

    /* best effort: a socket that refuses these options is served all the same */
    setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &on, sizeof on);
    setsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &idle, sizeof idle);
    setsockopt(fd, IPPROTO_TCP, TCP_KEEPINTVL, &intvl, sizeof intvl);
    setsockopt(fd, IPPROTO_TCP, TCP_KEEPCNT, &count, sizeof count);
    if (!r) return NULL;
    r->fd = fd;
    r->state = C_IDLE;
    r->since = ljgap__clock_now();
    pthread_mutex_lock(&cs->lock);
    r->next = cs->head;
    if (cs->head) cs->head->prev = r;
    cs->head = r;
    cs->stats.open++;
    pthread_mutex_unlock(&cs->lock);
    return r;
}

void conns_close(conns *cs, conn_rec *r)
{
    if (!r) return;
    pthread_mutex_lock(&cs->lock);
    if (r->prev)
        r->prev->next = r->next;
    else
        cs->head = r->next;
    if (r->next) r->next->prev = r->prev;
    cs->stats.open--;
    pthread_mutex_unlock(&cs->lock);
    free(r);
}

static void set_state(conns *cs, conn_rec *r, int state)
{
    if (!r) return;
    pthread_mutex_lock(&cs->lock);
    if (state == C_IDLE) r->since = ljgap__clock_now();
    r->state = state;
    pthread_mutex_unlock(&cs->lock);
}

void conns_receiving(conns *cs, conn_rec *r)
{
    set_state(cs, r, C_RECEIVING);
}

void conns_busy(conns *cs, conn_rec *r)
{
    set_state(cs, r, C_BUSY);
}

void conns_idle(conns *cs, conn_rec *r)
{
    set_state(cs, r, C_IDLE);
}

/* FNV-1a of the key, reduced to a bucket. */
static unsigned bucket_of(const char *key)
{
    unsigned h = 2166136261u;
    for (const unsigned char *p = (const unsigned char *)key; *p; p++)
        h = (h ^ *p) * 16777619u;
    return h % CLIENT_BUCKETS;
}

int conns_client_enter(conns *cs, const char *client, unsigned limit)
{
    unsigned b = bucket_of(client);
    client_count *c;
    int ok = 0;
    pthread_mutex_lock(&cs->lock);
    for (c = cs->buckets[b]; c && strcmp(c->key, client) != 0; c = c->next)
        ;
    if (!c && limit > 0 && (c = malloc(sizeof *c + strlen(client) + 1))) {
        strcpy(c->key, client);
        c->n = 0;
        c->next = cs->buckets[b];
        cs->buckets[b] = c;
    }
    if (c && c->n < limit) {
        c->n++;
        ok = 1;
    }
    pthread_mutex_unlock(&cs->lock);
    return ok;
}

void conns_client_leave(conns *cs, const char *client)
{
    unsigned b = bucket_of(client);
    client_count **pp, *c;
    pthread_mutex_lock(&cs->lock);
    for (pp = &cs->buckets[b]; (c = *pp) && strcmp(c->key, client) != 0; pp = &c->next)
        ;
    if (c && --c->n == 0) {
        *pp = c->next;
        free(c);
    }
    pthread_mutex_unlock(&cs->lock);
}

void conns_get_stats(conns *cs, conns_stats *st)
{
    pthread_mutex_lock(&cs->lock);
    *st = cs->stats;
    pthread_mutex_unlock(&cs->lock);
}

void conns_free(conns *cs)
{
    if (!cs) return;
    pthread_mutex_lock(&cs->lock);
    cs->quit = 1;
    pthread_cond_broadcast(&cs->quit_cv);
    pthread_mutex_unlock(&cs->lock);
    if (cs->has_sweeper) pthread_join(cs->sweeper, NULL);
    for (conn_rec *r = cs->head, *next; r; r = next) {
        next = r->next;
        free(r);
    }
    for (unsigned b = 0; b < CLIENT_BUCKETS; b++)
        for (client_count *c = cs->buckets[b], *next; c; c = next) {
            next = c->next;
            free(c);
        }
    pthread_cond_destroy(&cs->quit_cv);
    pthread_mutex_destroy(&cs->lock);
    free(cs);
}
