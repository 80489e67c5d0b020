/* config.c -- ljgapd's command-line flags: defaults, parsing, --help.
 *
 * Every limit the daemon enforces is a flag with a documented default, listed by --help (and in
 * the README and openapi.json). Values are checked here; a bad one is a usage error (exit 2).
 */
#include "daemon.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void usage(FILE *f)
{
    char here[32];
    budget_format(budget_default_limit(), here, sizeof here);
    fprintf(
        f,
        "usage: ljgapd [--port N] [--bind ADDR] [--web DIR] [--compute-slots N] [--queue N]\n"
        "              [--queue-wait S] [--max-seconds S] [--connections N]\n"
        "              [--client-connections N] [--trust-proxy]\n"
        "              [--state-dir DIR | --jobs-db postgresql://...] [--job-lease S]\n"
        "              [--max-memory SIZE]\n"
        "              [more: see below]\n"
        "Serves the ljgap calculations over HTTP (see /openapi.json).\n"
        "Listening\n"
        "  --port N              TCP port; 0 picks a free one (default 8080)\n"
        "  --bind ADDR           numeric IPv4/IPv6 address to listen on (default 127.0.0.1)\n"
        "  --web DIR             serve the page from DIR instead of the copy compiled in\n"
        "Computations\n"
        "  --compute-slots N     most computations at once (default: number of cores)\n"
        "  --queue N             most computations waiting for a slot (default 64); past it,\n"
        "                        503 + Retry-After at once. 0: none wait\n"
        "  --queue-wait S        longest wait for a slot, in seconds (default 10); then 503 +\n"
        "                        Retry-After. Slots go to the waiting client holding fewest\n"
        "  --max-seconds S       wall-time cap of one computation (default 20): it stops with\n"
        "                        its best answer and a warning, or a 422 cap-exceeded problem\n"
        "Connections (no thread each: epoll, waiting and computing requests are suspended)\n"
        "  --connections N       most open connections (default 1024, within the open-file\n"
        "                        limit, whose soft value is raised to the hard one)\n"
        "  --client-connections N  most connections of one client (default 32); past it, its\n"
        "                        new connections are refused (with --trust-proxy: its requests\n"
        "                        in progress, and the next gets 503)\n"
        "  --trust-proxy         name the client by the last X-Forwarded-For address (only\n"
        "                        behind a proxy that sets it, such as nginx)\n"
        "  --idle-timeout S      close a connection silent for S seconds (default 30)\n"
        "  --receive-timeout S   a whole request (headers and body) must arrive within S\n"
        "                        seconds of the connection opening or of its previous answer,\n"
        "                        or the connection is closed (default 60): slow senders\n"
        "  --io-threads N        threads serving connections, epoll each (default 1; the\n"
        "                        connection limit is split between them)\n"
        "  --max-body N          largest request body in bytes (default 1048576)\n"
        "Memory\n"
        "  --max-memory SIZE     the memory budget, suffixes K, M, G (default: the smaller of\n"
        "                        2G and a quarter of physical memory; here %s). It bounds\n"
        "                        request bodies (at most half of it at once), computations'\n"
        "                        working memory (estimated before they start), the answer\n"
        "                        cache (at most a sixteenth) and running simulations: what does\n"
        "                        not fit now waits or gets 503 + Retry-After, what could never\n"
        "                        fit gets 413 naming the limit. At least 32M\n"
        "Simulation jobs\n"
        "  --job-workers N       simulation jobs running at once, each on its own thread\n"
        "                        (default 1)\n"
        "  --job-queue N         simulation jobs waiting; more get 503 + Retry-After (default 8)\n"
        "  --job-keep N          finished jobs kept for polling, for at most an hour (default 64)\n"
        "  --job-seconds N       wall-time cap of one simulation (default 600)\n"
        "  --job-threads N       threads of one simulation, each running realizations (default\n"
        "                        1); give job-workers x job-threads the cores the compute slots\n"
        "                        leave\n"
        "  --state-dir DIR       keep the simulation jobs in DIR/jobs.sqlite, so that queued,\n"
        "                        running and finished jobs survive a restart or a crash; one\n"
        "                        ljgapd per DIR (default: $STATE_DIRECTORY as systemd sets it,\n"
        "                        else $XDG_STATE_HOME/ljgapd, else ~/.local/state/ljgapd); a\n"
        "                        DIR that cannot be used is exit status 2\n"
        "  --jobs-db URL         keep them in PostgreSQL instead: a postgresql:// URL (libpq's\n"
        "                        form: postgresql://USER@HOST:PORT/DBNAME; a password is better\n"
        "                        kept in ~/.pgpass or $PGPASSWORD than in the URL). Every ljgapd\n"
        "                        given the same database shares one queue: any of them answers\n"
        "                        for any job, and their workers take jobs from it. The schema is\n"
        "                        created or migrated at start; a database that cannot be used\n"
        "                        then is exit status 2; lost later, the job routes answer 503\n"
        "                        + Retry-After until it is back. Not with --state-dir\n"
        "  --job-lease S         a running job's lease in seconds, renewed every third of it\n"
        "                        (default 30); a job whose ljgapd died is run again from the\n"
        "                        start by another (or the next) ljgapd once its lease lapses\n"
        "The first line on stdout is 'listening on http://HOST:PORT/'; one log line per\n"
        "request goes to stderr. SIGINT/SIGTERM stop it within 10 s.\n",
        here);
}

static int parse_uint(const char *s, unsigned lo, unsigned hi, unsigned *out)
{
    char *end = NULL;
    unsigned long v;
    errno = 0;
    v = strtoul(s, &end, 10);
    if (errno || end == s || *end || s[0] == '-' || v < lo || v > hi) return -1;
    *out = (unsigned)v;
    return 0;
}

/* Seconds in (0, hi]. */
static int parse_seconds(const char *s, double hi, double *out)
{
    char *end = NULL;
    double v;
    errno = 0;
    v = strtod(s, &end);
    if (errno || end == s || *end || !isfinite(v) || !(v > 0) || v > hi) return -1;
    *out = v;
    return 0;
}

static void defaults(ljgapd_config *c)
{
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    memset(c, 0, sizeof *c);
    c->port = 8080;
    c->bind = "127.0.0.1";
    c->connections = 1024;
    c->client_connections = 32;
    c->io_threads = 1;
    c->slots = cores > 0 ? (unsigned)cores : 1;
    c->queue = 64;
    c->queue_wait = 10;
    c->max_seconds = 20;
    c->retry_after = 5;
    c->idle_s = 30;
    c->receive_s = 60;
    c->max_body = (size_t)1 << 20;
    c->cache_entries = 1024;
    c->cache_bytes = (size_t)64 << 20;
    c->max_memory = budget_default_limit();
    c->grace_s = 7.0;
    c->stop_s = 9.5;
    ljgap__jobs_config_default(&c->jobs);
    c->job_seconds = 600;
    c->job_threads = 1;
    c->job_retry = 10;
    c->cancel_wait_s = 2.0;
}

int ljgapd_parse_args(ljgapd_config *c, int argc, char **argv)
{
    static const struct option opts[] = {
        {"port", required_argument, NULL, 'p'},
        {"bind", required_argument, NULL, 'b'},
        {"web", required_argument, NULL, 'w'},
        {"compute-slots", required_argument, NULL, 's'},
        {"queue", required_argument, NULL, 'q'},
        {"queue-wait", required_argument, NULL, 'a'},
        {"max-seconds", required_argument, NULL, 'm'},
        {"connections", required_argument, NULL, 'c'},
        {"client-connections", required_argument, NULL, 'C'},
        {"trust-proxy", no_argument, NULL, 'x'},
        {"idle-timeout", required_argument, NULL, 'i'},
        {"receive-timeout", required_argument, NULL, 'r'},
        {"io-threads", required_argument, NULL, 'o'},
        {"max-body", required_argument, NULL, 'B'},
        {"job-workers", required_argument, NULL, 'W'},
        {"job-queue", required_argument, NULL, 'Q'},
        {"job-keep", required_argument, NULL, 'K'},
        {"job-seconds", required_argument, NULL, 'S'},
        {"job-threads", required_argument, NULL, 'T'},
        {"state-dir", required_argument, NULL, 'D'},
        {"jobs-db", required_argument, NULL, 'J'},
        {"job-lease", required_argument, NULL, 'L'},
        {"max-memory", required_argument, NULL, 'M'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    unsigned u;
    int o;

    defaults(c);
    optind = 1;
    while ((o = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
        int bad = 0;
        switch (o) {
        case 'p':
            bad = parse_uint(optarg, 0, 65535, &c->port);
            break;
        case 'b':
            c->bind = optarg;
            break;
        case 'w':
            c->web = optarg;
            break;
        case 's':
            bad = parse_uint(optarg, 1, 1024, &c->slots);
            break;
        case 'q':
            bad = parse_uint(optarg, 0, 100000, &c->queue);
            break;
        case 'a':
            bad = parse_seconds(optarg, 3600, &c->queue_wait);
            break;
        case 'm':
            bad = parse_seconds(optarg, 86400, &c->max_seconds);
            break;
        case 'c':
            bad = parse_uint(optarg, 4, 1000000, &c->connections);
            break;
        case 'C':
            bad = parse_uint(optarg, 1, 1000000, &c->client_connections);
            break;
        case 'x':
            c->trust_proxy = 1;
            break;
        case 'i':
            bad = parse_uint(optarg, 1, 86400, &c->idle_s);
            break;
        case 'r':
            bad = parse_uint(optarg, 1, 86400, &c->receive_s);
            break;
        case 'o':
            bad = parse_uint(optarg, 1, 64, &c->io_threads);
            break;
        case 'B':
            bad = parse_uint(optarg, 1024, 1u << 30, &u);
            c->max_body = u;
            break;
        case 'W':
            bad = parse_uint(optarg, 1, 64, &c->jobs.workers);
            break;
        case 'Q':
            bad = parse_uint(optarg, 1, 10000, &c->jobs.queue_cap);
            break;
        case 'K':
            bad = parse_uint(optarg, 1, 100000, &c->jobs.keep_done);
            break;
        case 'S':
            bad = parse_uint(optarg, 1, 86400, &c->job_seconds);
            break;
        case 'T':
            bad = parse_uint(optarg, 1, 64, &c->job_threads);
            break;
        case 'D':
            c->state_dir = optarg;
            bad = !optarg[0];
            break;
        case 'J':
            c->jobs_db = optarg;
            bad = strncmp(optarg, "postgresql://", 13) != 0 &&
                  strncmp(optarg, "postgres://", 11) != 0;
            break;
        case 'L':
            bad = parse_seconds(optarg, 3600, &c->jobs.lease_seconds) || c->jobs.lease_seconds < 1;
            break;
        case 'M':
            bad = budget_parse_size(optarg, &c->max_memory) || c->max_memory < ((size_t)32 << 20);
            break;
        case 'h':
            usage(stdout);
            return 1;
        default:
            usage(stderr);
            return -1;
        }
        if (bad) {
            const struct option *opt = opts;
            while (opt->val != o)
                opt++;
            if (o == 'J') /* never echoed: the URL may hold a password */
                fprintf(stderr, "ljgapd: --jobs-db wants a postgresql:// (or postgres://) URL\n");
            else
                fprintf(stderr, "ljgapd: bad value '%s' for --%s\n", optarg, opt->name);
            return -1;
        }
    }
    if (optind < argc) {
        usage(stderr);
        return -1;
    }
    if (c->jobs_db && c->state_dir) {
        fprintf(stderr, "ljgapd: --jobs-db and --state-dir exclude each other: the jobs are kept "
                        "in one place\n");
        return -1;
    }
    return 0;
}
