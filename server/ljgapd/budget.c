/* budget.c -- the memory budget (budget.h): a lock-free counter of reserved bytes. */
#include "budget.h"

#include <ctype.h>
#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

struct budget {
    size_t limit;
    budget *parent;
    atomic_size_t used;
    atomic_size_t peak;
    atomic_ulong refused;
};

budget *budget_new(size_t limit, budget *parent)
{
    budget *b = calloc(1, sizeof *b);
    if (!b) return NULL;
    b->limit = limit;
    b->parent = parent;
    atomic_init(&b->used, 0);
    atomic_init(&b->peak, 0);
    atomic_init(&b->refused, 0);
    return b;
}

void budget_free(budget *b)
{
    free(b);
}

/* Reserves n in b alone (compare-and-swap: never past the limit, even for a moment). */
static int take(budget *b, size_t n)
{
    size_t u = atomic_load(&b->used), p;
    do {
        if (n > b->limit || u > b->limit - n) {
            atomic_fetch_add(&b->refused, 1);
            return 0;
        }
    } while (!atomic_compare_exchange_weak(&b->used, &u, u + n));
    p = atomic_load(&b->peak);
    while (u + n > p && !atomic_compare_exchange_weak(&b->peak, &p, u + n))
        ;
    return 1;
}

int budget_try(budget *b, size_t n)
{
    if (!n) return 1;
    if (!take(b, n)) return 0;
    if (b->parent && !budget_try(b->parent, n)) {
        atomic_fetch_sub(&b->used, n);
        atomic_fetch_add(&b->refused, 1);
        return 0;
    }
    return 1;
}

void budget_release(budget *b, size_t n)
{
    if (!n) return;
    atomic_fetch_sub(&b->used, n);
    if (b->parent) budget_release(b->parent, n);
}

size_t budget_limit(const budget *b)
{
    return b->limit;
}

void budget_get(const budget *b, budget_stats *st)
{
    budget *m = (budget *)b; /* atomics are read-only here */
    st->limit = b->limit;
    st->used = atomic_load(&m->used);
    st->peak = atomic_load(&m->peak);
    st->refused = atomic_load(&m->refused);
}

int budget_parse_size(const char *s, size_t *out)
{
    char *end = NULL;
    unsigned long long v;
    unsigned shift = 0;
    if (!s || !isdigit((unsigned char)s[0])) return -1;
    errno = 0;
    v = strtoull(s, &end, 10);
    if (errno || end == s) return -1;
    switch (*end) {
    case 'k':
    case 'K':
        shift = 10, end++;
        break;
    case 'm':
    case 'M':
        shift = 20, end++;
        break;
    case 'g':
    case 'G':
        shift = 30, end++;
        break;
    default:
        break;
    }
    if (*end == 'B' || (*end == 'b' && shift)) end++;
    if (*end || v == 0 || v > (1ULL << (50 - shift))) return -1;
    *out = (size_t)(v << shift);
    return 0;
}

size_t budget_default_limit(void)
{
    const size_t cap = (size_t)2 << 30;
    long pages = sysconf(_SC_PHYS_PAGES), psize = sysconf(_SC_PAGESIZE);
    size_t quarter;
    if (pages <= 0 || psize <= 0) return cap;
    quarter = (size_t)pages / 4 * (size_t)psize;
    return quarter < cap ? quarter : cap;
}

void budget_format(size_t bytes, char *out, size_t n)
{
    static const char *const unit[] = {"KiB", "MiB", "GiB", "TiB"};
    double x = (double)bytes;
    int u = -1;
    if (bytes < 1024) {
        snprintf(out, n, "%zu bytes", bytes);
        return;
    }
    while (x >= 1024 && u < 3)
        x /= 1024, u++;
    if (x == (double)(long long)x)
        snprintf(out, n, "%.0f %s", x, unit[u]);
    else
        snprintf(out, n, "%.1f %s", x, unit[u]);
}
