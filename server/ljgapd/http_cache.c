/* http_cache.c -- bounded LRU cache: a chained hash table plus a doubly linked recency list.
 *
 * Each entry is one allocation holding the key bytes followed by the value bytes and a NUL, so a
 * hit costs one hash, one memcmp and one copy, and eviction is one free. The bucket array is
 * sized once at allocation (a power of two, at least twice max_entries) so chains stay short
 * and the table never rehashes. The hash is 64-bit FNV-1a: keys are request bodies chosen by
 * clients, but a collision only lengthens a chain (keys are always compared in full), and the
 * entry bound caps the chain length anyway.
 *
 * One mutex guards everything; the critical sections are a lookup or an insertion plus copies
 * of at most a few MiB, far shorter than the computations the cache saves.
 */
#include "http_cache.h"

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct entry {
    struct entry *chain; /* next entry in the same bucket */
    struct entry *newer; /* recency list: towards the most recently used */
    struct entry *older; /* recency list: towards the least recently used */
    uint64_t hash;       /* FNV-1a of the key */
    int status;          /* HTTP status stored with the value */
    size_t klen;         /* key length in bytes */
    size_t vlen;         /* value length in bytes (without the trailing NUL) */
    char data[];         /* key bytes, then value bytes, then NUL */
} entry;

struct http_cache {
    pthread_mutex_t lock; /* guards every field below */
    entry **bucket;       /* nbucket chains */
    size_t nbucket;       /* a power of two */
    entry *newest;        /* head of the recency list */
    entry *oldest;        /* tail of the recency list: evicted first */
    size_t entries;       /* entries held */
    size_t bytes;         /* key + value bytes held */
    size_t max_entries;   /* bound on entries */
    size_t max_bytes;     /* bound on bytes */
};

static uint64_t cache__hash(const char *key, size_t klen)
{
    uint64_t h = 14695981039346656037ULL;
    for (size_t i = 0; i < klen; i++) {
        h ^= (unsigned char)key[i];
        h *= 1099511628211ULL;
    }
    return h;
}

http_cache *http_cache_alloc(size_t max_entries, size_t max_bytes)
{
    http_cache *c = NULL;
    size_t n = 16;

    if (max_entries == 0 || max_bytes == 0) return NULL;
    while (n < 2 * max_entries && n < ((size_t)1 << 30))
        n <<= 1;
    c = calloc(1, sizeof *c);
    if (!c) return NULL;
    c->bucket = calloc(n, sizeof *c->bucket);
    if (!c->bucket) {
        free(c);
        return NULL;
    }
    c->nbucket = n;
    c->max_entries = max_entries;
    c->max_bytes = max_bytes;
    pthread_mutex_init(&c->lock, NULL);
    return c;
}

void http_cache_free(http_cache *c)
{
    if (!c) return;
    for (entry *e = c->newest, *next; e; e = next) {
        next = e->older;
        free(e);
    }
    pthread_mutex_destroy(&c->lock);
    free(c->bucket);
    free(c);
}

/* The entry for key, or NULL; *link is set to the pointer that points at it (for unlinking). */
static entry *cache__find(http_cache *c, uint64_t h, const char *key, size_t klen, entry ***link)
{
    entry **p = &c->bucket[h & (c->nbucket - 1)];
    for (; *p; p = &(*p)->chain) {
        entry *e = *p;
        if (e->hash == h && e->klen == klen && memcmp(e->data, key, klen) == 0) {
            if (link) *link = p;
            return e;
        }
    }
    return NULL;
}

static void cache__list_unlink(http_cache *c, entry *e)
{
    if (e->newer)
        e->newer->older = e->older;
    else
        c->newest = e->older;
    if (e->older)
        e->older->newer = e->newer;
    else
        c->oldest = e->newer;
    e->newer = e->older = NULL;
}

static void cache__list_push(http_cache *c, entry *e)
{
    e->newer = NULL;
    e->older = c->newest;
    if (c->newest) c->newest->newer = e;
    c->newest = e;
    if (!c->oldest) c->oldest = e;
}

/* Remove e from the table and the list and free it. */
static void cache__drop(http_cache *c, entry *e)
{
    entry **link = NULL;
    cache__find(c, e->hash, e->data, e->klen, &link);
    *link = e->chain;
    cache__list_unlink(c, e);
    c->entries--;
    c->bytes -= e->klen + e->vlen;
    free(e);
}

int http_cache_get(http_cache *c, const char *key, size_t klen, int *status, char **val,
                   size_t *vlen)
{
    uint64_t h = cache__hash(key, klen);
    int rc = 0;

    pthread_mutex_lock(&c->lock);
    entry *e = cache__find(c, h, key, klen, NULL);
    if (e) {
        char *copy = malloc(e->vlen + 1);
        if (copy) {
            memcpy(copy, e->data + e->klen, e->vlen + 1);
            *val = copy;
            *vlen = e->vlen;
            *status = e->status;
            cache__list_unlink(c, e);
            cache__list_push(c, e);
            rc = 1;
        } else {
            rc = -1;
        }
    }
    pthread_mutex_unlock(&c->lock);
    return rc;
}

int http_cache_put(http_cache *c, const char *key, size_t klen, int status, const char *val,
                   size_t vlen)
{
    return http_cache_put2(c, key, klen, status, val, vlen, NULL, 0);
}

int http_cache_put2(http_cache *c, const char *key, size_t klen, int status, const char *head,
                    size_t hlen, const char *tail, size_t tlen)
{
    uint64_t h = cache__hash(key, klen);
    entry *e = NULL, *old = NULL;
    size_t vlen = hlen + tlen;

    if (klen + vlen > c->max_bytes) return -1;
    e = malloc(sizeof *e + klen + vlen + 1);
    if (!e) return -1;
    e->hash = h;
    e->status = status;
    e->klen = klen;
    e->vlen = vlen;
    memcpy(e->data, key, klen);
    if (hlen) memcpy(e->data + klen, head, hlen);
    if (tlen) memcpy(e->data + klen + hlen, tail, tlen);
    e->data[klen + vlen] = '\0';

    pthread_mutex_lock(&c->lock);
    old = cache__find(c, h, key, klen, NULL);
    if (old) cache__drop(c, old);
    while (c->oldest && (c->entries + 1 > c->max_entries || c->bytes + klen + vlen > c->max_bytes))
        cache__drop(c, c->oldest);
    e->chain = c->bucket[h & (c->nbucket - 1)];
    c->bucket[h & (c->nbucket - 1)] = e;
    cache__list_push(c, e);
    c->entries++;
    c->bytes += klen + vlen;
    pthread_mutex_unlock(&c->lock);
    return 0;
}

void http_cache_stats(http_cache *c, size_t *entries, size_t *bytes)
{
    pthread_mutex_lock(&c->lock);
    *entries = c->entries;
    *bytes = c->bytes;
    pthread_mutex_unlock(&c->lock);
}
