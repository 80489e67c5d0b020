/* bench.h -- what the benchmark programs share: wall-clock medians of repeated runs.
 *
 *   double t = bench_median_ms(run, ctx, bench_repeats(first_ms), &n);
 *
 * Figures, never assertions: the programs print and write files, they do not fail on speed.
 */
#ifndef LJGAP_BENCH_H
#define LJGAP_BENCH_H

#include "ljgap.h"
#include "core.h" /* ljgap__now */

#include <stdlib.h>

static int bench_cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Median of v[0..n) (sorts v). */
static inline double bench_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, bench_cmp);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* How many runs a median takes, from the duration of a first one: 7 below 0.1 s, 5 below 1 s,
 * 3 below 8 s, else that single run (keeps `make bench` within minutes). */
static inline int bench_repeats(double first_ms)
{
    return first_ms < 100 ? 7 : first_ms < 1000 ? 5 : first_ms < 8000 ? 3 : 1;
}

/* One timed call: run(ctx, i) for repeat i returns a status; then, untimed, score(ctx, i)
 * (may be NULL) looks at what it produced. */
typedef int (*bench_fn)(void *ctx, int i);

/* Runs run(ctx, 0..) as many times as bench_repeats says after the first (at most 7); the
 * median wall time in *ms, the count in *reps. Stops at the first nonzero status. */
static inline int bench_median_ms(bench_fn run, bench_fn score, void *ctx, double *ms, int *reps)
{
    double t[7];
    int n = 1, st = 0;
    for (int i = 0; i < n; i++) {
        double t0 = ljgap__now();
        st = run(ctx, i);
        t[i] = 1e3 * (ljgap__now() - t0);
        if (!st && score) st = score(ctx, i);
        if (st) {
            n = i + 1;
            break;
        }
        if (i == 0) n = bench_repeats(t[0]);
    }
    *ms = bench_median(t, n);
    *reps = n;
    return st;
}

#endif
