/* main.c -- ljgapd, the ljgap HTTP daemon: start-up and shutdown.
 *
 * The daemon is a thin shell over the request handler (handler.h): everything that knows
 * physics or JSON fields lives there, and the daemon only moves bytes between sockets and that
 * pure function, with what a server shared by a lab needs around it (daemon.h lists the files):
 *
 *   - connections cost no thread: libmicrohttpd runs --io-threads event loops (epoll), and a
 *     request that waits for a compute slot or computes is suspended, holding no thread. The
 *     connection limit (--connections, default 1024) is fitted to the open-file limit, whose
 *     soft value is raised to the hard one; each client may hold --client-connections.
 *   - compute slots (--compute-slots, default the cores) with a bounded, fair wait queue
 *     (--queue, --queue-wait): a request past those limits gets 503 with Retry-After; a
 *     request whose client hangs up leaves the queue, or has its computation cancelled.
 *   - a cache of identical requests' answers, served without a slot; /healthz, /version,
 *     /openapi.json and the page's files never wait.
 *   - simulation jobs are kept in SQLite in the state directory (--state-dir; jobstore.h), or
 *     in PostgreSQL (--jobs-db URL) shared by several daemons behind one proxy, so they survive
 *     a restart or a crash, and run in the background (jobs.h). A store that cannot be used
 *     stops the start with exit status 2: there is no job store in memory.
 *   - shutdown: SIGINT/SIGTERM are taken by sigwait() here. The daemon stops accepting
 *     (MHD_quiesce_daemon); running simulations stop and go back to the queue (the next start
 *     runs them); requests waiting for a slot get 503; computations may finish for a grace
 *     period, then their cancel flags are raised; everything has stopped within 10 s, and it
 *     exits 0.
 */
#include "daemon.h"
#include "ljgap.h"

#include <arpa/inet.h>
#include <errno.h>
#include <malloc.h>
#include <fcntl.h>
#include <fftw3.h>
#include <gsl/gsl_errno.h>
#include <netinet/in.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <sys/resource.h>
#include <unistd.h>

#define FD_RESERVE 64 /* descriptors kept free of connections: files, the store, the listener */
#define OPS_THREADS 2 /* threads for job-store calls */
#define OPS_QUEUE 256 /* job-store calls waiting at most */
#define CACHE_ENTRY_OVERHEAD 256 /* bytes an answer cache entry holds besides key and answer */

ljgapd_server ljgapd_srv = {.web_fd = -1};

/* Raises the soft open-file limit to the hard one and fits the connection limit inside it.
 * Writes what it did into note. */
static void fit_file_limit(char *note, size_t n)
{
    struct rlimit rl;
    rlim_t was;
    unsigned fit;

    if (getrlimit(RLIMIT_NOFILE, &rl) != 0) {
        snprintf(note, n, "open-file limit unknown");
        return;
    }
    was = rl.rlim_cur;
    if (rl.rlim_cur < rl.rlim_max) {
        rl.rlim_cur = rl.rlim_max;
        if (setrlimit(RLIMIT_NOFILE, &rl) != 0) rl.rlim_cur = was;
    }
    fit = rl.rlim_cur > FD_RESERVE + 4
              ? (unsigned)(rl.rlim_cur - FD_RESERVE > 1000000 ? 1000000 : rl.rlim_cur - FD_RESERVE)
              : 4;
    if (ljgapd_srv.cfg.connections > fit) ljgapd_srv.cfg.connections = fit;
    if (rl.rlim_cur == was)
        snprintf(note, n, "open-file limit %llu", (unsigned long long)rl.rlim_cur);
    else
        snprintf(note, n, "open-file limit %llu (raised from %llu)",
                 (unsigned long long)rl.rlim_cur, (unsigned long long)was);
}

/* The state directory when --state-dir is not given: systemd's StateDirectory= (the first of
 * $STATE_DIRECTORY), else the XDG state home ($XDG_STATE_HOME, or ~/.local/state), in ljgapd/:
 * never the current directory, so jobs do not depend on where the daemon was started from.
 * NULL when there is none (no usable $HOME either). */
static const char *default_state_dir(char *buf, size_t n)
{
    const char *sd = getenv("STATE_DIRECTORY"), *xdg = getenv("XDG_STATE_HOME");
    const char *home = getenv("HOME");
    int len = -1;
    if (sd && sd[0] == '/')
        len = snprintf(buf, n, "%.*s", (int)strcspn(sd, ":"), sd);
    else if (xdg && xdg[0] == '/') /* the XDG spec ignores relative paths */
        len = snprintf(buf, n, "%s/ljgapd", xdg);
    else if (home && home[0] == '/')
        len = snprintf(buf, n, "%s/.local/state/ljgapd", home);
    return len > 0 && (size_t)len < n ? buf : NULL;
}

/* Opens the job store: PostgreSQL at cfg.jobs_db, else SQLite in cfg.state_dir (or the
 * default); 0, or -1 with the reason said. */
static int store_open(char *buf, size_t n)
{
    char err[600];
    unsigned queued = 0, running = 0;
    if (ljgapd_srv.cfg.jobs_db) {
        /* a connection for each thread that uses the store: workers, keeper, ops, main */
        if (ljgap__jobstore_open_pg(ljgapd_srv.cfg.jobs_db,
                                   ljgapd_srv.cfg.jobs.workers + OPS_THREADS + 2, &ljgapd_srv.store,
                                   err, sizeof err) != LJGAP_JOBSTORE_OK) {
            fprintf(stderr, "ljgapd: %s\n", err);
            return -1;
        }
    } else {
        if (!ljgapd_srv.cfg.state_dir && !(ljgapd_srv.cfg.state_dir = default_state_dir(buf, n))) {
            fprintf(stderr, "ljgapd: no state directory: give --state-dir DIR (neither "
                            "$STATE_DIRECTORY, $XDG_STATE_HOME nor $HOME is set)\n");
            return -1;
        }
        if (ljgap__jobstore_open_sqlite(ljgapd_srv.cfg.state_dir, &ljgapd_srv.store, err,
                                       sizeof err) != LJGAP_JOBSTORE_OK) {
            fprintf(stderr, "ljgapd: cannot use the state directory: %s\n", err);
            return -1;
        }
    }
    ljgap__jobstore_counts(ljgapd_srv.store, &queued, &running);
    if (ljgapd_srv.cfg.jobs_db)
        fprintf(stderr, "ljgapd: jobs kept in %s, shared (%u queued, %u running), lease %g s\n",
                ljgapd_srv.store->where, queued, running, ljgapd_srv.cfg.jobs.lease_seconds);
    else
        fprintf(stderr, "ljgapd: jobs kept in %s (%u queued)\n", ljgapd_srv.store->where, queued);
    return 0;
}

static struct MHD_Daemon *daemon_start(char *host, size_t hostsz)
{
    struct sockaddr_in in4 = {0};
    struct sockaddr_in6 in6 = {0};
    struct sockaddr *sa = NULL;
    unsigned flags =
        MHD_USE_EPOLL_INTERNAL_THREAD | MHD_ALLOW_SUSPEND_RESUME | MHD_USE_ITC | MHD_USE_ERROR_LOG;
    /* Without --trust-proxy the remote address is the client, and libmicrohttpd refuses its
     * connections past the limit at accept; behind a proxy every connection is the proxy's. */
    unsigned per_ip = ljgapd_srv.cfg.trust_proxy ? 0 : ljgapd_srv.cfg.client_connections;
    struct MHD_Daemon *d;
    const union MHD_DaemonInfo *info;

    if (inet_pton(AF_INET, ljgapd_srv.cfg.bind, &in4.sin_addr) == 1) {
        in4.sin_family = AF_INET;
        in4.sin_port = htons((uint16_t)ljgapd_srv.cfg.port);
        sa = (struct sockaddr *)&in4;
        snprintf(host, hostsz, "%s",
                 in4.sin_addr.s_addr == htonl(INADDR_ANY) ? "127.0.0.1" : ljgapd_srv.cfg.bind);
    } else if (inet_pton(AF_INET6, ljgapd_srv.cfg.bind, &in6.sin6_addr) == 1) {
        in6.sin6_family = AF_INET6;
        in6.sin6_port = htons((uint16_t)ljgapd_srv.cfg.port);
        sa = (struct sockaddr *)&in6;
        flags |= MHD_USE_IPv6;
        if (IN6_IS_ADDR_UNSPECIFIED(&in6.sin6_addr))
            snprintf(host, hostsz, "[::1]");
        else
            snprintf(host, hostsz, "[%s]", ljgapd_srv.cfg.bind);
    } else {
        fprintf(stderr, "ljgapd: --bind wants a numeric IPv4 or IPv6 address, not '%s'\n",
                ljgapd_srv.cfg.bind);
        return NULL;
    }
    struct MHD_OptionItem opts[] = {
        {MHD_OPTION_EXTERNAL_LOGGER, (intptr_t)ljgapd_mhd_log, NULL}, /* first, as MHD asks */
        {MHD_OPTION_SOCK_ADDR, 0, sa},
        {MHD_OPTION_CONNECTION_LIMIT, (intptr_t)ljgapd_srv.cfg.connections, NULL},
        {MHD_OPTION_PER_IP_CONNECTION_LIMIT, (intptr_t)per_ip, NULL},
        {MHD_OPTION_CONNECTION_TIMEOUT, (intptr_t)ljgapd_srv.cfg.idle_s, NULL},
        {MHD_OPTION_NOTIFY_COMPLETED, (intptr_t)ljgapd_on_completed, NULL},
        {MHD_OPTION_NOTIFY_CONNECTION, (intptr_t)ljgapd_on_connection, NULL},
        /* last, so that one I/O thread (no pool) simply ends the list here */
        {ljgapd_srv.cfg.io_threads > 1 ? MHD_OPTION_THREAD_POOL_SIZE : MHD_OPTION_END,
         (intptr_t)ljgapd_srv.cfg.io_threads, NULL},
        {MHD_OPTION_END, 0, NULL},
    };
    d = MHD_start_daemon(flags, (uint16_t)ljgapd_srv.cfg.port, NULL, NULL, ljgapd_on_access, NULL,
                         MHD_OPTION_ARRAY, opts, MHD_OPTION_END);
    if (!d) {
        fprintf(stderr, "ljgapd: cannot listen on %s port %u\n", ljgapd_srv.cfg.bind,
                ljgapd_srv.cfg.port);
        return NULL;
    }
    info = MHD_get_daemon_info(d, MHD_DAEMON_INFO_BIND_PORT);
    if (info) ljgapd_srv.cfg.port = info->port;
    return d;
}

/* Wait until no request is in flight or `until` seconds have passed since t0. */
static void wait_inflight(const struct timespec *t0, double until)
{
    const struct timespec tick = {0, 20 * 1000 * 1000};
    while (atomic_load(&ljgapd_srv.inflight) > 0 && ljgap__clock_since(t0) < until)
        nanosleep(&tick, NULL);
}

int main(int argc, char **argv)
{
    struct MHD_Daemon *d = NULL;
    ljgap__limits limits;
    sigset_t sigs;
    char host[INET6_ADDRSTRLEN + 3], files[96], state_dir[4096], mem[32];
    struct timespec t_sig;
    MHD_socket lfd;
    ljgapd_config *cfg = &ljgapd_srv.cfg;
    pool_config slots_cfg, ops_cfg;
    int sig = 0, rc;

    gsl_set_error_handler_off();
    rc = ljgapd_parse_args(cfg, argc, argv);
    if (rc != 0) return rc < 0 ? 2 : 0;
    rc = 1;

    /* Signals go to main's sigwait only: block them before any thread starts. */
    sigemptyset(&sigs);
    sigaddset(&sigs, SIGINT);
    sigaddset(&sigs, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &sigs, NULL);
    signal(SIGPIPE, SIG_IGN);
    if (store_open(state_dir, sizeof state_dir) != 0) return 2; /* never a job store in memory */

    ljgap__limits_default(&limits);
    limits.max_seconds = cfg->max_seconds;
    limits.sim_threads = cfg->job_threads;
    ljgap__handler_set_limits(&limits);
    if (getrandom(&ljgapd_srv.id_seed, sizeof ljgapd_srv.id_seed, 0) != sizeof ljgapd_srv.id_seed)
        ljgapd_srv.id_seed = (unsigned)getpid() ^ (unsigned)time(NULL);
    fit_file_limit(files, sizeof files);

    /* The memory budget: the answer cache's bound (at most a sixteenth) is held for good;
     * request bodies may hold half of the rest; computations and simulations reserve their
     * estimates as they start, each at most the other half, so that one always fits beside a
     * full share of bodies (nothing can wait for memory that only waiting requests hold). */
    if (cfg->cache_bytes > cfg->max_memory / 16) cfg->cache_bytes = cfg->max_memory / 16;
    ljgapd_srv.pinned = cfg->cache_bytes + cfg->cache_entries * CACHE_ENTRY_OVERHEAD;
    if (ljgapd_srv.pinned > cfg->max_memory / 8) ljgapd_srv.pinned = cfg->max_memory / 8;
    ljgapd_srv.mem = budget_new(cfg->max_memory, NULL);
    ljgapd_srv.bodies = budget_new((cfg->max_memory - ljgapd_srv.pinned) / 2, ljgapd_srv.mem);
    if (ljgapd_srv.mem) budget_try(ljgapd_srv.mem, ljgapd_srv.pinned);
    /* Large blocks (bodies, heights, FFT arrays) are mapped and unmapped, never kept by malloc
     * after they are freed: what the budget gives back is given back to the system. */
    mallopt(M_MMAP_THRESHOLD, 256 * 1024);
    slots_cfg = (pool_config){cfg->slots, cfg->queue, cfg->queue_wait, ljgapd_srv.mem};
    ops_cfg = (pool_config){OPS_THREADS, OPS_QUEUE, cfg->queue_wait, NULL};
    ljgapd_srv.cache = http_cache_alloc(cfg->cache_entries, cfg->cache_bytes);
    ljgapd_srv.jobs =
        ljgap__jobs_alloc(&cfg->jobs, ljgapd_srv.store, ljgapd_job_kinds, ljgapd_job_nkinds);
    ljgapd_srv.slots = pool_start(&slots_cfg);
    ljgapd_srv.ops = pool_start(&ops_cfg);
    ljgapd_srv.conns = conns_start(cfg->receive_s);
    if (!ljgapd_srv.mem || !ljgapd_srv.bodies || !ljgapd_srv.cache || !ljgapd_srv.jobs ||
        !ljgapd_srv.slots || !ljgapd_srv.ops || !ljgapd_srv.conns) {
        fprintf(stderr, "ljgapd: out of memory or threads\n");
        goto end;
    }
    if (cfg->web) {
        ljgapd_srv.web_fd = open(cfg->web, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
        if (ljgapd_srv.web_fd < 0) {
            fprintf(stderr, "ljgapd: cannot open --web %s: %s\n", cfg->web, strerror(errno));
            goto end;
        }
    }
    d = daemon_start(host, sizeof host);
    if (!d) goto end;
    budget_format(cfg->max_memory, mem, sizeof mem);
    printf("listening on http://%s:%u/\n", host, cfg->port);
    fflush(stdout);
    fprintf(stderr,
            "ljgapd %s: %u compute slots (queue %u, wait %g s, cap %g s each), %u connections "
            "(%u per client%s), %s, %u I/O thread%s, %u job workers, web %s, memory %s\n",
            LJGAP_VERSION, cfg->slots, cfg->queue, cfg->queue_wait, cfg->max_seconds,
            cfg->connections, cfg->client_connections,
            cfg->trust_proxy ? ", by X-Forwarded-For" : "", files, cfg->io_threads,
            cfg->io_threads == 1 ? "" : "s", cfg->jobs.workers, cfg->web ? cfg->web : "compiled in",
            mem);

    while (sigwait(&sigs, &sig) != 0)
        ;
    clock_gettime(CLOCK_MONOTONIC, &t_sig);
    atomic_store(&ljgapd_srv.stopping, 1);
    fprintf(stderr, "ljgapd: %s, stopping (%u requests in flight)\n", strsignal(sig),
            atomic_load(&ljgapd_srv.inflight));
    lfd = MHD_quiesce_daemon(d);
    ljgap__jobs_shutdown(
        ljgapd_srv.jobs); /* no client waits for jobs: stop them now (they run again) */
    /* Waiting requests get 503 now; computations may finish for grace_s, then are cancelled.
     * Every suspended connection must be resumed before MHD_stop_daemon. */
    if (!pool_stop(ljgapd_srv.slots, cfg->grace_s, cfg->stop_s - cfg->grace_s) ||
        !pool_stop(ljgapd_srv.ops, 0, cfg->stop_s - ljgap__clock_since(&t_sig))) {
        fprintf(stderr, "ljgapd: a computation ignored its cancel flag; exiting without it\n");
        _exit(0);
    }
    wait_inflight(&t_sig, cfg->stop_s);
    if (atomic_load(&ljgapd_srv.inflight) > 0)
        fprintf(stderr, "ljgapd: %u requests did not finish; closing their connections\n",
                atomic_load(&ljgapd_srv.inflight));
    if (!ljgap__jobs_wait_idle(ljgapd_srv.jobs, cfg->stop_s - ljgap__clock_since(&t_sig))) {
        fprintf(stderr, "ljgapd: a simulation ignored its cancel flag; exiting without it\n");
        _exit(0);
    }
    MHD_stop_daemon(d);
    if (lfd != MHD_INVALID_SOCKET) close(lfd);
    fprintf(stderr, "ljgapd: stopped after %.1f s\n", ljgap__clock_since(&t_sig));
    rc = 0;
end:
    if (ljgapd_srv.web_fd >= 0) close(ljgapd_srv.web_fd);
    pool_free(ljgapd_srv.slots);
    pool_free(ljgapd_srv.ops);
    conns_free(ljgapd_srv.conns);
    ljgap__jobs_free(ljgapd_srv.jobs);
    ljgap__jobstore_close(ljgapd_srv.store);
    fftw_cleanup(); /* the simulations' FFTW planner state is global: freed once no job runs */
    http_cache_free(ljgapd_srv.cache);
    budget_free(ljgapd_srv.bodies);
    budget_free(ljgapd_srv.mem);
    return rc;
}
