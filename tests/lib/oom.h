/* oom.h -- out of memory in the handler: a cJSON allocator that fails the n-th allocation from
 * now, and the sweep that fails every allocation of a request in turn (static functions:
 * include it once, after cmocka.h, handler.h and cJSON).
 *
 *   oom_sweep("adhesion", body, 400);
 */
#ifndef LJGAP_TEST_OOM_H
#define LJGAP_TEST_OOM_H

#include <stdlib.h>
#include <string.h>

static long oom_left = -1; /* allocations to let through; -1: all */

static void *oom_malloc(size_t n)
{
    if (oom_left == 0) return NULL;
    if (oom_left > 0) oom_left--;
    return malloc(n);
}

/* ljgap__handle(endpoint, body) with its n-th cJSON allocation failing, n = 0, 1, ... (at most
 * max) until it answers 200: every other answer must be the 500 out-of-memory problem, and
 * both kinds must be seen. */
static void oom_sweep(const char *endpoint, const char *body, long max)
{
    cJSON_Hooks hooks = {oom_malloc, free};
    int saw_oom = 0, saw_ok = 0;
    for (long n = 0; n < max && !saw_ok; n++) {
        ljgap__reply r;
        oom_left = n;
        cJSON_InitHooks(&hooks);
        ljgap__handle(endpoint, body, strlen(body), &r);
        cJSON_InitHooks(NULL);
        oom_left = -1;
        assert_non_null(r.body);
        if (r.status == 500) {
            cJSON *p = cJSON_Parse(r.body), *t = cJSON_GetObjectItemCaseSensitive(p, "type");
            assert_true(cJSON_IsString(t));
            assert_string_equal(t->valuestring, "/problems/out-of-memory");
            assert_string_equal(r.content_type, "application/problem+json");
            cJSON_Delete(p);
            saw_oom = 1;
        } else {
            if (r.status != 200)
                fail_msg("status %d after %ld allocations: %.300s", r.status, n, r.body);
            saw_ok = 1;
        }
        ljgap__reply_free(&r);
    }
    assert_true(saw_oom);
    assert_true(saw_ok);
}

#endif
