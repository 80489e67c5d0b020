/* jobstore.c -- how long the SQLite job store's calls take (server/jobs/jobstore_sqlite.c), on a
 * temporary directory under /tmp: the calls an HTTP thread makes (create = a committed,
 * fsync'ed insert; get of a finished job with a 20 kB result plus its status JSON, which is what
 * GET /v1/simulations/ID does; cancel of a queued job) and those a worker makes (claim, renew,
 * finish). Prints one line per call: median and 99th percentile in ms over N calls.
 *
 *   build/bench/jobstore [N]      (default 400)
 */
#include "bench.h"
#include "core.h" /* ljgap__now */
#include "jobstatus.h"
#include "jobstore.h"

#include <sqlite3.h>

#include <ftw.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

static int rm1(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb, (void)ftw;
    return flag == FTW_DP ? rmdir(path) : unlink(path);
}

static void report(const char *what, double *ms, int n)
{
    double med = bench_median(ms, n); /* sorts */
    printf("%-34s median %.3f ms  p99 %.3f ms  (%d calls)\n", what, med, ms[(n * 99) / 100], n);
}

int main(int argc, char **argv)
{
    int n = argc > 1 ? atoi(argv[1]) : 400;
    char dir[] = "/tmp/ljgap-bench-XXXXXX", err[600], (*ids)[LJGAP_JOB_ID_LEN + 1];
    double *t[6];
    long *runs;
    char *answer;
    ljgap__jobstore *st = NULL;
    ljgap__job_record rec;
    int cancel;
    if (n < 10) n = 10;
    ids = malloc((size_t)n * sizeof *ids);
    runs = malloc((size_t)n * sizeof *runs);
    answer = malloc(20001);
    for (int k = 0; k < 6; k++)
        t[k] = malloc((size_t)n * sizeof *t[k]);
    if (!ids || !runs || !answer || !t[5] || !mkdtemp(dir)) return 1;
    /* a result of 20 kB: {"sigma":[0.123456789012,...]} */
    strcpy(answer, "{\"sigma\":[");
    while (strlen(answer) < 19970)
        strcat(answer, "0.123456789012,");
    strcat(answer, "0]}");
    if (ljgap__jobstore_open_sqlite(dir, &st, err, sizeof err) != LJGAP_JOBSTORE_OK) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    for (int i = 0; i < n; i++) {
        double t0 = ljgap__now();
        ljgap__job_id_new(ids[i]);
        if (ljgap__jobstore_create(st, ids[i], "simulation", "{\"n\":64}", 8, 0) != 0) return 1;
        t[0][i] = 1e3 * (ljgap__now() - t0);
    }
    for (int i = 0; i < n; i++) {
        double t0 = ljgap__now();
        if (ljgap__jobstore_claim(st, "bench", 30, &rec) != 0) return 1;
        t[1][i] = 1e3 * (ljgap__now() - t0);
        runs[i] = rec.run;
        ljgap__job_record_clear(&rec);
        t0 = ljgap__now();
        ljgap__jobstore_renew(st, ids[i], runs[i], 0.5, 30, &cancel);
        t[2][i] = 1e3 * (ljgap__now() - t0);
        t0 = ljgap__now();
        ljgap__jobstore_finish(st, ids[i], runs[i], LJGAP_JOB_DONE, answer, strlen(answer));
        t[3][i] = 1e3 * (ljgap__now() - t0);
    }
    for (int i = 0; i < n; i++) {
        double t0 = ljgap__now();
        char *json;
        if (ljgap__jobstore_get(st, ids[i], &rec) != 0 || !(json = ljgap__job_status_json(&rec)))
            return 1;
        t[4][i] = 1e3 * (ljgap__now() - t0);
        free(json);
        ljgap__job_record_clear(&rec);
    }
    for (int i = 0; i < n; i++) {
        char id[LJGAP_JOB_ID_LEN + 1];
        double t0;
        ljgap__job_id_new(id);
        ljgap__jobstore_create(st, id, "simulation", "{}", 2, 0);
        t0 = ljgap__now();
        ljgap__jobstore_cancel(st, id, &rec);
        t[5][i] = 1e3 * (ljgap__now() - t0);
        ljgap__job_record_clear(&rec);
    }
    printf("# job store: SQLite %s, WAL, FULL commits for create/cancel/finish, on a temporary "
           "directory\n",
           sqlite3_libversion());
    report("create (committed)", t[0], n);
    report("get + status JSON (20 kB result)", t[4], n);
    report("cancel (a queued job)", t[5], n);
    report("claim", t[1], n);
    report("renew (progress, lease, cancel?)", t[2], n);
    report("finish (20 kB result)", t[3], n);
    ljgap__jobstore_close(st);
    nftw(dir, rm1, 8, FTW_DEPTH | FTW_PHYS);
    for (int k = 0; k < 6; k++)
        free(t[k]);
    free(ids);
    free(runs);
    free(answer);
    return 0;
}
