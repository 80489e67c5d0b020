/* budget.h -- the daemon's memory budget (--max-memory): bytes reserved before they are used.
 *
 * One counter of the bytes the daemon holds for requests: request bodies while they arrive and
 * wait, the working memory of a computation while it runs (its estimate, memest.h), the answer
 * cache's bound (pinned at start) and a simulation job's working memory while it runs. Every
 * holder reserves before it allocates and releases what it reserved when it frees: a
 * reservation that would take the use past the limit fails, and the caller refuses (503 with
 * Retry-After), waits (a computation in the queue), or evicts. Nothing here allocates on the
 * way: budget_try and budget_release are a few atomic operations, safe from any thread.
 *
 *   budget *b = budget_new(limit);
 *   if (budget_try(b, n)) { ...use n bytes...; budget_release(b, n); } else refuse;
 *   budget_get(b, &st);   limit, use, high-water mark, refusals (for /healthz)
 *
 * A budget may have a parent: a reservation then takes from both (bodies have a share of half
 * the budget, so that they can never leave the computations without room).
 */
#ifndef LJGAPD_BUDGET_H
#define LJGAPD_BUDGET_H

#include <stddef.h>

typedef struct budget budget;

/* A budget of limit bytes, inside parent's (parent may be NULL); NULL if out of memory. */
budget *budget_new(size_t limit, budget *parent);
void budget_free(budget *b);

/* Reserves n bytes (and in the parent) if the use stays within every limit: 1, else 0 and
 * nothing is reserved. n = 0 always succeeds. */
int budget_try(budget *b, size_t n);
/* Gives back n bytes reserved with budget_try (in the parent too). */
void budget_release(budget *b, size_t n);

/* Bytes the limit allows at most (the limit). */
size_t budget_limit(const budget *b);

typedef struct {
    size_t limit;          /* bytes at most */
    size_t used;           /* bytes reserved now */
    size_t peak;           /* the most ever reserved at once */
    unsigned long refused; /* budget_try calls that failed */
} budget_stats;

void budget_get(const budget *b, budget_stats *st);

/* Parses SIZE: digits with an optional suffix K, M or G (powers of 1024; k, m, g too) and an
 * optional trailing B ("64M", "1G", "512MB", "1048576"); 0 on success, -1 if malformed, zero,
 * or beyond 2^50. */
int budget_parse_size(const char *s, size_t *out);

/* The default --max-memory: the smaller of 2 GiB and a quarter of the physical memory (2 GiB
 * when the memory cannot be read). */
size_t budget_default_limit(void);

/* "1.5 GiB", "64 MiB", "512 KiB" or "100 bytes" into out. */
void budget_format(size_t bytes, char *out, size_t n);

#endif
