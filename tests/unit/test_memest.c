/* test_memest.c -- the memory estimates (server/api/memest.c) bound what the computations really
 * use. Each case runs in a child process: it maps large blocks as ljgapd does (mallopt), resets
 * its peak resident size (writing 5 to /proc/self/clear_refs), runs the computation and reads
 * VmHWM; the growth over VmRSS before the run must be at most the estimate, and the estimate
 * at most FACTOR times the growth plus SLACK (an estimate that asks for far more than it needs
 * would refuse requests that fit). Cases: text PSDs of a map and of a profile, a JSON
 * computation, a height map in JSON near the body limit, simulations on 64² and 128² grids on one
 * and two threads. The token count of a body fed in pieces equals that of the whole. (Not measured
 * under the address sanitizer.) */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <malloc.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "handler.h"
#include "memest.h"

#define FACTOR 4                /* the estimate is within this factor of the peak... */
#define SLACK ((size_t)8 << 20) /* ...plus this (fixed allowances: plans, answers) */

static size_t status_kb(const char *key)
{
    char line[256];
    size_t kb = 0, n = strlen(key);
    FILE *f = fopen("/proc/self/status", "r");
    if (!f) return 0;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, key, n) == 0 && line[n] == ':') kb = strtoul(line + n + 1, NULL, 10);
    fclose(f);
    return kb;
}

typedef void (*work)(const void *arg);

/* Runs w(arg) in a child; the child exits 0 when the growth of its peak RSS is within est and
 * est within FACTOR x growth + SLACK, 1 and 2 otherwise; the figures are printed. */
static int measured(const char *what, work w, const void *arg, size_t est)
{
    pid_t pid;
    int st = -1;
#if defined(__SANITIZE_ADDRESS__)
    /* the sanitizer's shadow and quarantine are resident too: the figures mean nothing */
    printf("# %s: not measured under the address sanitizer\n", what);
    return 0;
#endif
    pid = fork();
    if (pid == 0) {
        size_t before, peak, grew;
        FILE *f;
        mallopt(M_MMAP_THRESHOLD, 256 * 1024);
        if (!(f = fopen("/proc/self/clear_refs", "w"))) _exit(3);
        fputs("5", f);
        fclose(f);
        before = status_kb("VmRSS");
        w(arg);
        peak = status_kb("VmHWM");
        grew = peak > before ? (peak - before) * 1024 : 0;
        printf("# %s: peak grew %.1f MiB, estimate %.1f MiB\n", what, grew / 1048576.0,
               est / 1048576.0);
        fflush(stdout);
        _exit(grew > est ? 1 : est > FACTOR * grew + SLACK ? 2 : 0);
    }
    waitpid(pid, &st, 0);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

typedef struct {
    char *body;
    size_t len;
    ljgap__param p[2];
} text_case;

static void run_text(const void *arg)
{
    const text_case *t = arg;
    ljgap__reply rep;
    ljgap__handle_text("psd", t->p, 1, t->body, t->len, NULL, &rep);
    if (rep.status != 200) fprintf(stderr, "status %d: %.300s\n", rep.status, rep.body);
    ljgap__reply_free(&rep);
}

/* A ny x nx map of random heights as text, "%.9e" each: a random walk along each row (a
 * spectrum falling as k^-2, which the profile's conversion needs). */
static text_case text_map(size_t nx, size_t ny)
{
    text_case t = {0};
    size_t cap = nx * ny * 18 + 16, n = 0;
    t.body = malloc(cap);
    srand(26);
    for (size_t j = 0; j < ny; j++) {
        double h = 0;
        for (size_t i = 0; i < nx; i++) {
            h += 1e-8 * ((double)rand() / RAND_MAX - 0.5);
            n += (size_t)snprintf(t.body + n, cap - n, "%.9e%c", h, i + 1 < nx ? ' ' : '\n');
        }
    }
    t.len = n;
    t.p[0].name = "dx";
    t.p[0].value = "1e-6";
    return t;
}

static size_t text_estimate(const text_case *t)
{
    ljgap__token_count tc = {0};
    ljgap__token_feed(&tc, t->body, t->len);
    return ljgap__memest_psd_text(tc.tokens);
}

static void test_text_psd(void **state)
{
    const size_t dims[][2] = {{700, 700}, {512, 1024}, {200000, 1}};
    for (size_t i = 0; i < sizeof dims / sizeof dims[0]; i++) {
        text_case t = text_map(dims[i][0], dims[i][1]);
        char what[64];
        snprintf(what, sizeof what, "text PSD %zu x %zu", dims[i][0], dims[i][1]);
        assert_int_equal(measured(what, run_text, &t, text_estimate(&t)), 0);
        free(t.body);
    }
}

static void test_tokens_in_pieces(void **state)
{
    const char *s = "1 2,3\t4e5\n# note\n-6 ,7\r\n8";
    ljgap__token_count whole = {0}, parts = {0};
    ljgap__token_feed(&whole, s, strlen(s));
    for (size_t i = 0; s[i]; i++)
        ljgap__token_feed(&parts, s + i, 1);
    assert_int_equal(whole.tokens, 8); /* 7 values and the comment's word ("#" separates) */
    assert_int_equal(parts.tokens, whole.tokens);
}

typedef struct {
    const char *body;
    const char *endpoint;
} json_case;

static void run_json(const void *arg)
{
    const json_case *j = arg;
    ljgap__reply rep;
    ljgap__handle(j->endpoint, j->body, strlen(j->body), &rep);
    if (rep.status != 200) fprintf(stderr, "status %d: %.300s\n", rep.status, rep.body);
    ljgap__reply_free(&rep);
}

/* Height maps in JSON near the 1 MiB body limit, where the body's values dominate the estimate:
 * 256 x 256 heights as "%.6e", and 512 x 512 one-digit heights (the most values a body holds). */
static void test_json_map(void **state)
{
    const size_t n[] = {256, 512}, cap = 1 << 20;
    for (int c = 0; c < 2; c++) {
        json_case j = {NULL, "psd"};
        char *b = malloc(cap), what[64];
        size_t k = 0;
        double h = 0;
        srand(26);
        k += (size_t)snprintf(b + k, cap - k, "{\"topography\":{\"dx\":1e-6,\"heights\":[");
        for (size_t r = 0; r < n[c]; r++) {
            k += (size_t)snprintf(b + k, cap - k, "%s[", r ? "," : "");
            for (size_t i = 0; i < n[c]; i++) {
                h += 1e-8 * ((double)rand() / RAND_MAX - 0.5);
                if (c == 0)
                    k += (size_t)snprintf(b + k, cap - k, "%s%.6e", i ? "," : "", h);
                else
                    k += (size_t)snprintf(b + k, cap - k, "%s%d", i ? "," : "", rand() % 10);
            }
            k += (size_t)snprintf(b + k, cap - k, "]");
        }
        snprintf(b + k, cap - k, "]}}");
        j.body = b;
        assert_true(strlen(b) < cap - 1);
        snprintf(what, sizeof what, "JSON psd, %zu x %zu heights in %zu bytes", n[c], n[c],
                 strlen(b));
        assert_int_equal(measured(what, run_json, &j,
                                  ljgap__memest_json(strlen(b), ljgap__json_values(b, strlen(b)), 1)),
                         0);
        free(b);
    }
}

static void test_json(void **state)
{
    json_case j = {"{\"psd\":{\"kind\":\"power\",\"D\":2.5,\"k1\":1,\"m0\":0.5},\"method\":"
                   "\"montecarlo\",\"samples\":100000}",
                   "adhesion"};
    /* a small body: the fixed allowance is the whole estimate, so only the bound is checked */
    size_t est = ljgap__memest_json(strlen(j.body), ljgap__json_values(j.body, strlen(j.body)), 1);
    int r = measured("JSON adhesion (Monte Carlo)", run_json, &j, est);
    assert_true(r == 0 || r == 2);
}

typedef struct {
    char body[256];
} sim_case;

static void run_sim(const void *arg)
{
    const sim_case *s = arg;
    ljgap__reply rep;
    ljgap__sim_control ctl = {0};
    ljgap__sim_request *sr = ljgap__sim_request_parse(s->body, strlen(s->body), &rep);
    if (!sr) {
        fprintf(stderr, "sim: %.300s\n", rep.body);
        _exit(4);
    }
    ljgap__sim_request_run(sr, &ctl, &rep);
    ljgap__sim_request_free(sr);
    ljgap__reply_free(&rep);
}

static void test_sim(void **state)
{
    const int grid[] = {64, 128};
    for (unsigned threads = 1; threads <= 2; threads++)
        for (size_t i = 0; i < sizeof grid / sizeof grid[0]; i++) {
            sim_case s;
            ljgap__limits l;
            char what[64];
            ljgap__limits_default(&l);
            l.sim_threads = (int)threads;
            ljgap__handler_set_limits(&l);
            snprintf(s.body, sizeof s.body,
                     "{\"psd\":{\"kind\":\"power\",\"D\":2.2,\"k1\":1,\"k2\":8,\"m0\":0.1},"
                     "\"n\":%d,\"realizations\":2,\"g_ave\":[3]}",
                     grid[i]);
            snprintf(what, sizeof what, "simulation %d² on %u thread%s", grid[i], threads,
                     threads > 1 ? "s" : "");
            size_t est = ljgap__memest_sim_request(s.body, strlen(s.body), threads);
            int r = measured(what, run_sim, &s, est);
            assert_true(r == 0 || r == 2); /* small grids: the fixed allowance dominates */
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tokens_in_pieces),
        cmocka_unit_test(test_text_psd),
        cmocka_unit_test(test_json),
        cmocka_unit_test(test_json_map),
        cmocka_unit_test(test_sim),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
