/* files.c -- build/bench/files FILE [RUNS]: the time to read an instrument file (server/files/,
 * ljgap__files_read) and to answer POST /v1/psd with it (ljgap__handle_file: the read, the PSD,
 * the JSON), each the median and the extremes of RUNS runs (default 7). bench/files.sh makes a
 * 2048² 32-bit NanoScope file and runs it (issue 28 asks for under 1 s to the PSD).
 */
#include "files.h"
#include "handler.h"

#include <gsl/gsl_errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    int runs = argc > 2 ? atoi(argv[2]) : 7;
    FILE *f = argc > 1 ? fopen(argv[1], "rb") : NULL;
    double tr[64], th[64];
    if (!f || runs < 1 || runs > 64) {
        fprintf(stderr, "usage: files FILE [RUNS <= 64]\n");
        return 2;
    }
    fseek(f, 0, SEEK_END);
    size_t len = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc(len ? len : 1);
    if (!buf || fread(buf, 1, len, f) != len) return 2;
    fclose(f);
    gsl_set_error_handler_off();
    ljgap__files_map m;
    ljgap__files_err e;
    for (int i = 0; i < runs; i++) {
        double t0 = now();
        int st = ljgap__files_read(buf, len, NULL, NULL, &m, &e);
        tr[i] = now() - t0;
        if (st) {
            fprintf(stderr, "read: %d %s\n", st, e.msg);
            return 1;
        }
        if (i == 0)
            printf("file: %s, %zu bytes, %s, %zu x %zu points, channel %s\n",
                   strrchr(argv[1], '/') ? strrchr(argv[1], '/') + 1 : argv[1], len, m.format, m.nx,
                   m.ny, m.channel);
        ljgap__files_map_free(&m);
    }
    for (int i = 0; i < runs; i++) {
        ljgap__reply r;
        double t0 = now();
        ljgap__handle_file("psd", NULL, 0, buf, len, NULL, &r);
        th[i] = now() - t0;
        if (r.status != 200) {
            fprintf(stderr, "psd: %d %.300s\n", r.status, r.body);
            return 1;
        }
        ljgap__reply_free(&r);
    }
    qsort(tr, (size_t)runs, sizeof *tr, cmp);
    qsort(th, (size_t)runs, sizeof *th, cmp);
    printf("read (ljgap__files_read):             median %.3f s (%.3f ... %.3f), %d runs\n",
           tr[runs / 2], tr[0], tr[runs - 1], runs);
    printf("to the PSD (ljgap__handle_file, all): median %.3f s (%.3f ... %.3f), %d runs\n",
           th[runs / 2], th[0], th[runs - 1], runs);
    free(buf);
    return 0;
}
