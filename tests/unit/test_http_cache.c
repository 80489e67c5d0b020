/* test_http_cache.c -- the daemon's LRU cache: hits copy, both bounds evict the least recently
 * used entry, replacing a key keeps one entry, oversize values are refused, a value given in
 * two parts is stored as one. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "http_cache.h"

/* Is key present with value want? (A hit also marks it most recently used.) */
static int has(http_cache *c, const char *key, const char *want)
{
    char *v = NULL;
    size_t n = 0;
    int status = 0;
    int rc = http_cache_get(c, key, strlen(key), &status, &v, &n);
    int ok = rc == 1 && status == 200 && n == strlen(want) && strcmp(v, want) == 0;
    free(v);
    return rc == 1 ? (ok ? 1 : -1) : 0;
}

static void put(http_cache *c, const char *key, const char *val)
{
    assert_int_equal(http_cache_put(c, key, strlen(key), 200, val, strlen(val)), 0);
}

static void test_hit_miss_replace(void **state)
{
    (void)state;
    http_cache *c = http_cache_alloc(4, 1000);
    size_t n, bytes;
    assert_non_null(c);
    assert_int_equal(has(c, "a", "x"), 0);
    put(c, "a", "one");
    assert_int_equal(has(c, "a", "one"), 1);
    put(c, "a", "two");
    assert_int_equal(has(c, "a", "two"), 1);
    http_cache_stats(c, &n, &bytes);
    assert_int_equal(n, 1);
    assert_int_equal(bytes, 4);
    /* keys are bytes: an embedded NUL separates endpoint from body */
    assert_int_equal(http_cache_put(c, "e\0{}", 4, 200, "v", 1), 0);
    char *v = NULL;
    size_t vlen = 0;
    int status = 0;
    assert_int_equal(http_cache_get(c, "e\0{ }", 5, &status, &v, &vlen), 0);
    assert_int_equal(http_cache_get(c, "e\0{}", 4, &status, &v, &vlen), 1);
    free(v);
    http_cache_free(c);
    http_cache_free(NULL);
}

static void test_entry_bound_evicts_lru(void **state)
{
    (void)state;
    http_cache *c = http_cache_alloc(3, 1000);
    put(c, "a", "1");
    put(c, "b", "2");
    put(c, "c", "3");
    assert_int_equal(has(c, "a", "1"), 1); /* a is now the most recent: b is the oldest */
    put(c, "d", "4");
    assert_int_equal(has(c, "b", "2"), 0);
    assert_int_equal(has(c, "a", "1"), 1);
    assert_int_equal(has(c, "c", "3"), 1);
    assert_int_equal(has(c, "d", "4"), 1);
    http_cache_free(c);
}

static void test_byte_bound(void **state)
{
    (void)state;
    http_cache *c = http_cache_alloc(100, 20);
    size_t n, bytes;
    put(c, "k1", "aaaaaaaa"); /* 10 bytes */
    put(c, "k2", "bbbbbbbb"); /* 20 */
    put(c, "k3", "cccccccc"); /* evicts k1 */
    assert_int_equal(has(c, "k1", "aaaaaaaa"), 0);
    assert_int_equal(has(c, "k3", "cccccccc"), 1);
    http_cache_stats(c, &n, &bytes);
    assert_int_equal(n, 2);
    assert_true(bytes <= 20);
    /* a value larger than the whole cache is refused and evicts nothing */
    assert_int_equal(http_cache_put(c, "big", 3, 200, "0123456789012345678", 19), -1);
    assert_int_equal(has(c, "k2", "bbbbbbbb"), 1);
    http_cache_free(c);
}

/* http_cache_put2: head then tail, counted whole against the byte bound. */
static void test_two_parts(void **state)
{
    (void)state;
    http_cache *c = http_cache_alloc(4, 24);
    size_t n, bytes;
    assert_non_null(c);
    assert_int_equal(http_cache_put2(c, "k", 1, 200, "{\"a\":1,", 7, "\"b\":2}", 6), 0);
    assert_int_equal(has(c, "k", "{\"a\":1,\"b\":2}"), 1);
    assert_int_equal(http_cache_put2(c, "h", 1, 200, "head", 4, NULL, 0), 0);
    assert_int_equal(has(c, "h", "head"), 1);
    http_cache_stats(c, &n, &bytes);
    assert_int_equal(n, 2);
    assert_int_equal(bytes, 1 + 13 + 1 + 4);
    /* the two parts together exceed the bound, though each alone would not */
    assert_int_equal(http_cache_put2(c, "x", 1, 200, "0123456789", 10, "0123456789abcd", 14), -1);
    assert_int_equal(has(c, "k", "{\"a\":1,\"b\":2}"), 1);
    http_cache_free(c);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hit_miss_replace),
        cmocka_unit_test(test_entry_bound_evicts_lru),
        cmocka_unit_test(test_byte_bound),
        cmocka_unit_test(test_two_parts),
    };
    return cmocka_run_group_tests_name("http_cache", tests, NULL, NULL);
}
