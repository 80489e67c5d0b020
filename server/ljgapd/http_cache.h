/* http_cache.h -- a bounded, thread-safe LRU cache of computed answers for the HTTP daemon.
 *
 * Keys and values are byte strings (the daemon uses endpoint + body as the key and the finished
 * JSON answer as the value). The cache is bounded both in entries and in bytes (keys + values);
 * inserting past either bound evicts the least recently used entries. A value larger than the
 * byte bound is simply not stored. Every function takes one mutex, so any thread may call it.
 *
 *     http_cache *c = http_cache_alloc(1024, 64 << 20);
 *     http_cache_put(c, key, klen, 200, val, vlen);
 *     if (http_cache_get(c, key, klen, &status, &copy, &copylen) == 1) { ...; free(copy); }
 *     http_cache_free(c);
 */
#ifndef LJGAP_HTTP_CACHE_H
#define LJGAP_HTTP_CACHE_H

#include <stddef.h>

typedef struct http_cache http_cache;

/* A cache holding at most max_entries entries and max_bytes bytes of keys and values.
 * NULL if memory runs out or a bound is 0. */
http_cache *http_cache_alloc(size_t max_entries, size_t max_bytes);
void http_cache_free(http_cache *c); /* NULL is a no-op */

/* Look key up. On a hit returns 1, marks the entry most recently used and writes its status and
 * a malloc'd, NUL-terminated copy of the value (caller frees). Returns 0 on a miss, -1 if the
 * copy could not be allocated. */
int http_cache_get(http_cache *c, const char *key, size_t klen, int *status, char **val,
                   size_t *vlen);

/* Store a copy of (key -> status, val), replacing an entry with the same key. Returns 0, or -1
 * if memory ran out or the entry alone exceeds the byte bound (nothing stored). */
int http_cache_put(http_cache *c, const char *key, size_t klen, int status, const char *val,
                   size_t vlen);

/* The same with the value given in two parts, stored as head then tail (an answer with its last
 * bytes replaced, without a copy of the whole answer first). */
int http_cache_put2(http_cache *c, const char *key, size_t klen, int status, const char *head,
                    size_t hlen, const char *tail, size_t tlen);

/* Entries and bytes held now (for tests and logs). */
void http_cache_stats(http_cache *c, size_t *entries, size_t *bytes);

#endif
