/* settings.h -- what one call of the request handler is given besides its body: the server-wide
 * limits (set once at start-up), the per-call settings (cancel flag, Accept header) and a text
 * upload's query parameters. Its own header so that validation (request.h) and the handler
 * (handler.h) both include it downward.
 */
#ifndef LJGAP_SETTINGS_H
#define LJGAP_SETTINGS_H

#include <stddef.h>

/* Server-wide limits the handler enforces (422 naming the cap when exceeded). */
typedef struct {
    double max_seconds;   /* wall-time cap of one computation (default 20) */
    long max_samples;     /* montecarlo samples cap (default 1e6) */
    long max_points;      /* cap on g_ave points / sweep values / pdf snapshots (default 10000) */
    long sweep_threads;   /* worker threads of one sweep (default, and when <= 0: the online
                           * cores; 1 computes sequentially); results do not depend on it */
    long max_topo_points; /* cap on the heights of one psd map (default, and when <= 0:
                           * LJGAP_TOPO_POINTS_DEFAULT) */
    long sim_threads;     /* threads of one simulation run, each computing realizations (<= 0:
                           * the online cores); results do not depend on it. The handler starts
                           * with 0 (the CLI's foreground run takes every core); ljgap__limits_default
                           * gives 1 (a daemon's jobs, --job-workers of them at once, leave the
                           * other cores to the synchronous endpoints) */
    const volatile int *cancel; /* set nonzero to abort computations (shutdown) */
} ljgap__limits;

/* The handler's limits before ljgap__handler_set_limits: sweeps and simulations on every core. A
 * macro, not a const object: C needs a constant expression to initialise a static. */
#define LJGAP_LIMITS_INIT                                                                          \
    {                                                                                              \
        .max_seconds = 20.0, .max_samples = 1000000, .max_points = 10000, .sweep_threads = 0,      \
        .sim_threads = 0, .cancel = NULL                                                           \
    }

/* The daemon's defaults: those, with the online cores for a sweep and 1 thread a simulation. */
void ljgap__limits_default(ljgap__limits *l);
/* The limits used by ljgap__handle (defaults until set). Not thread-safe: call at start-up. */
void ljgap__handler_set_limits(const ljgap__limits *l);

#define LJGAP_TOPO_POINTS_DEFAULT (1L << 23) /* 8 Mi heights: a 2896² map, 64 MiB of doubles */

/* The cap on the heights of one psd map: max_topo_points, or LJGAP_TOPO_POINTS_DEFAULT when that
 * is <= 0. */
size_t ljgap__limits_topo_cap(const ljgap__limits *l);

/* How one call is driven, beyond the server-wide limits. Everything may be zero. */
typedef struct {
    const volatile int *cancel; /* nonzero stops this computation (503 "unavailable" problem);
                                 * NULL: the limits' cancel flag */
    const char *accept;         /* the request's Accept header, NULL when it has none:
                                 * traction, pdf and sweep answer text/csv (csv.h) when it
                                 * prefers that to application/json (accept.h); one that allows
                                 * no form the endpoint has is a 406 problem, decided before the
                                 * body is read. Problems are always application/problem+json. */
} ljgap__call;

/* A text upload's query parameter (handler.h: ljgap__handle_text). Bodies up to
 * LJGAP_TEXT_MAX_BYTES are meant (the daemon enforces it). */
#define LJGAP_TEXT_MAX_BYTES ((size_t)64 << 20)

typedef struct {
    const char *name;  /* query parameter name, decoded */
    const char *value; /* its value, decoded; NULL or "" when given without one */
} ljgap__param;

#endif
