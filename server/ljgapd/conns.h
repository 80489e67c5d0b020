/* conns.h -- the daemon's record of its open connections: slow senders and per-client counts.
 *
 * libmicrohttpd 0.9.75 closes a connection after --idle-timeout seconds without traffic, but
 * has no bound on the time a whole request may take to arrive: a client that sends its
 * headers one byte every few seconds is never idle. This module adds that bound. Each
 * connection is idle (waiting for its next request), receiving (headers in, body arriving) or
 * busy (its request is being answered); a sweeper thread shuts down the socket of every
 * connection that stayed idle or receiving for more than receive_s seconds since it opened or
 * since its previous answer, so libmicrohttpd sees the end of the stream and closes it. A
 * connection's next request therefore has to arrive whole within receive_s.
 *
 * It also counts requests in progress per client key, for the per-client limit when clients
 * are named by X-Forwarded-For (behind a trusted proxy every connection comes from the proxy,
 * so connections cannot be counted per client; libmicrohttpd's per-address limit does it
 * otherwise).
 *
 * Nothing here knows HTTP: records are keyed by socket descriptor, created and dropped by the
 * daemon's connection-notification callback, which runs before libmicrohttpd closes the socket;
 * the sweeper only touches sockets of records still registered, under the registry's lock.
 */
#ifndef LJGAPD_CONNS_H
#define LJGAPD_CONNS_H

typedef struct conns conns;
typedef struct conn_rec conn_rec;

/* Starts the sweeper (receive_s > 0 seconds per whole request); NULL if out of memory. */
conns *conns_start(double receive_s);

/* A connection opened on socket fd: its record, or NULL if out of memory (then the other calls
 * accept NULL and do nothing). Sets TCP keep-alive probes on fd, so a peer that vanished
 * without a word (a laptop closed) is noticed within a minute. */
conn_rec *conns_open(conns *cs, int fd);
/* The connection is about to be closed by libmicrohttpd: forget it (frees rec). */
void conns_close(conns *cs, conn_rec *rec);

/* Its request's headers arrived (receiving), the request is complete and being answered
 * (busy), the answer is done (idle again, the receive clock restarts). */
void conns_receiving(conns *cs, conn_rec *rec);
void conns_busy(conns *cs, conn_rec *rec);
void conns_idle(conns *cs, conn_rec *rec);

/* Per-client requests in progress: enter returns 1 and counts the request if client has
 * fewer than limit in progress, else 0 (not counted); leave undoes a successful enter. */
int conns_client_enter(conns *cs, const char *client, unsigned limit);
void conns_client_leave(conns *cs, const char *client);

typedef struct {
    unsigned open;     /* connections open now */
    unsigned long cut; /* connections shut down for not completing a request in time */
} conns_stats;
void conns_get_stats(conns *cs, conns_stats *st);

/* Stops the sweeper and frees everything (records still open included). NULL is fine. */
void conns_free(conns *cs);

#endif
