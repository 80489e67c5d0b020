/* memest.h -- upper bounds of the memory a request needs, before it runs (issue 26).
 *
 * ljgapd reserves a computation's estimate from its memory budget (--max-memory) before the
 * computation gets a slot, and refuses a request whose estimate could never fit. Every figure
 * here is an upper bound of the bytes the computation allocates at its peak (the request body
 * is counted apart: the daemon reserves it while it arrives), checked against measured peaks
 * in tests/unit/test_memest.c. Each follows the allocations of the code it bounds:
 *
 *   text PSD of N heights  topo_text.c parses into a doubling array (at most 2 x 8N bytes; it
 *                          grows in place: ljgapd maps large blocks, so realloc moves pages),
 *                          the request keeps it, core/topo/topo.c copies the heights once (8N),
 *                          transforms them into a complex array ((nx/2+1) x ny x 16 <= 8N +
 *                          16 ny) and keeps a bin index (2 bytes a point): 33 bytes a height
 *                          and FFTW's scratch are bounded by 40, plus 4 MiB for the plan, the
 *                          bins and the answer.
 *   a JSON request         cJSON holds every value of the body in a node (64 bytes and the
 *                          allocator's 16), the request copies arrays as doubles (8), a height
 *                          map in JSON is then computed as the text PSD above (40): 128 bytes a
 *                          value, plus twice the body (strings, the cache's key), 8 MiB for the
 *                          solvers' work arrays (at most --max-points values each) and 2 MiB for
 *                          each thread of a sweep.
 *   a simulation           each of its threads has a workspace of 14 real n x n arrays, one
 *                          real and three complex n x (n/2+1) arrays (core/sim/simsolve.c); the run
 *                          shares four more n x n arrays (plans, the PSD's weights), plus 4 MiB.
 */
#ifndef LJGAP_MEMEST_H
#define LJGAP_MEMEST_H

#include <stddef.h>

/* The values of a text height matrix, counted as its chunks arrive: an upper bound of the
 * heights topo_text.c reads (every run of bytes between separators counts, comments too). */
typedef struct {
    size_t tokens; /* runs counted so far */
    int inside;    /* the last byte seen was inside a run */
} ljgap__token_count;

void ljgap__token_feed(ljgap__token_count *tc, const char *data, size_t n);

/* Bytes a text PSD of `values` heights needs at most. */
size_t ljgap__memest_psd_text(size_t values);
/* An upper bound of the values in a JSON body (cJSON's nodes): every value but the root follows
 * a '[', ',' or ':' (those inside strings only add to the bound). */
size_t ljgap__json_values(const char *body, size_t len);
/* Bytes a JSON computation with a body of len bytes and at most `values` values needs at most
 * (threads: of a sweep). */
size_t ljgap__memest_json(size_t len, size_t values, unsigned threads);
/* Bytes a simulation on an n x n grid with `threads` threads needs at most. */
size_t ljgap__memest_sim(int n, unsigned threads);
/* A simulation request's n and realizations from its JSON body (the defaults 64 and 4 when
 * absent or unreadable: the request is validated elsewhere); threads at most realizations. */
size_t ljgap__memest_sim_request(const char *body, size_t len, unsigned threads);

#endif
