/* test_budget.c -- the memory budget (server/ljgapd/budget.c): reservations within the limit,
 * release, the high-water mark, a share inside a parent (bodies in the whole budget), many
 * threads reserving at once never passing the limit, and --max-memory's SIZE syntax. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <pthread.h>
#include <stdatomic.h>
#include <string.h>

#include "budget.h"

static void test_reserve_release(void **state)
{
    budget *b = budget_new(100, NULL);
    budget_stats st;
    assert_true(budget_try(b, 60));
    assert_false(budget_try(b, 41));
    assert_true(budget_try(b, 40));
    assert_false(budget_try(b, 1));
    assert_true(budget_try(b, 0));
    budget_release(b, 60);
    assert_true(budget_try(b, 10));
    budget_get(b, &st);
    assert_int_equal(st.limit, 100);
    assert_int_equal(st.used, 50);
    assert_int_equal(st.peak, 100);
    assert_int_equal(st.refused, 2);
    assert_false(budget_try(b, (size_t)-1)); /* no wrap-around */
    budget_free(b);
}

static void test_share(void **state)
{
    budget *all = budget_new(100, NULL), *bodies = budget_new(50, all);
    budget_stats st;
    assert_true(budget_try(bodies, 50));
    assert_false(budget_try(bodies, 1)); /* the share is full */
    assert_true(budget_try(all, 50));    /* the rest is the computations' */
    budget_release(bodies, 50);
    assert_true(budget_try(all, 30));
    assert_true(budget_try(bodies, 20));
    assert_false(budget_try(bodies, 1)); /* the parent is full: nothing stays reserved */
    budget_get(bodies, &st);
    assert_int_equal(st.used, 20);
    budget_get(all, &st);
    assert_int_equal(st.used, 100);
    budget_free(bodies);
    budget_free(all);
}

#define THREADS 8
#define ROUNDS 20000
static budget *shared;
static atomic_int over;

static void *hammer(void *arg)
{
    size_t n = 1 + (size_t)(intptr_t)arg * 7;
    for (int i = 0; i < ROUNDS; i++)
        if (budget_try(shared, n)) {
            budget_stats st;
            budget_get(shared, &st);
            if (st.used > st.limit) atomic_store(&over, 1);
            budget_release(shared, n);
        }
    return NULL;
}

static void test_threads(void **state)
{
    pthread_t th[THREADS];
    budget_stats st;
    shared = budget_new(64, NULL);
    for (intptr_t i = 0; i < THREADS; i++)
        assert_int_equal(pthread_create(&th[i], NULL, hammer, (void *)i), 0);
    for (int i = 0; i < THREADS; i++)
        pthread_join(th[i], NULL);
    budget_get(shared, &st);
    assert_int_equal(st.used, 0);
    assert_true(st.peak <= 64);
    assert_int_equal(atomic_load(&over), 0);
    budget_free(shared);
}

static void test_parse(void **state)
{
    size_t v;
    assert_int_equal(budget_parse_size("64M", &v), 0);
    assert_int_equal(v, (size_t)64 << 20);
    assert_int_equal(budget_parse_size("1G", &v), 0);
    assert_int_equal(v, (size_t)1 << 30);
    assert_int_equal(budget_parse_size("512k", &v), 0);
    assert_int_equal(v, (size_t)512 << 10);
    assert_int_equal(budget_parse_size("2GB", &v), 0);
    assert_int_equal(v, (size_t)2 << 30);
    assert_int_equal(budget_parse_size("1048576", &v), 0);
    assert_int_equal(v, (size_t)1 << 20);
    const char *bad[] = {"", "M", "-1G", "0", "1T", "1.5G", "1G ", " 1G", "1GiB", "99999999999G"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        assert_int_equal(budget_parse_size(bad[i], &v), -1);
    assert_true(budget_default_limit() > 0);
    assert_true(budget_default_limit() <= (size_t)2 << 30);
}

static void test_format(void **state)
{
    char s[32];
    budget_format((size_t)64 << 20, s, sizeof s);
    assert_string_equal(s, "64 MiB");
    budget_format((size_t)3 << 29, s, sizeof s);
    assert_string_equal(s, "1.5 GiB");
    budget_format(100, s, sizeof s);
    assert_string_equal(s, "100 bytes");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reserve_release), cmocka_unit_test(test_share),
        cmocka_unit_test(test_threads),         cmocka_unit_test(test_parse),
        cmocka_unit_test(test_format),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
