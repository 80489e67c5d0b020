/* combine.c -- the speed of POST /v1/psd/combine (issue 25: a combine of 4 PSDs under 10 ms).
 *
 *   combine [RUNS]   four PSD tables of one power law as /v1/psd gives them (10 bins a decade
 *                    over 2.5 decades each, overlapping by one: 5.5 decades in all, 5 % noise),
 *                    combined RUNS times (default 2000) by the core (ljgap_combine) and by the
 *                    whole handler (JSON parse, validation, core, answer): the median and the
 *                    99th percentile of each, in ms.
 *
 * Figures, never assertions (bench.h).
 */
#include "bench.h"
#include "core.h" /* ljgap__now */
#include "handler.h"
#include "ljgap_combine.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define M 4
#define N 26 /* points a table: 2.5 decades at 10 a decade */

static double pct(double *t, int n, double q)
{
    qsort(t, (size_t)n, sizeof *t, bench_cmp);
    return t[(int)(q * (n - 1))];
}

int main(int argc, char **argv)
{
    static double k[M][N], P[M][N], E[M][N], t_core[100000], t_all[100000];
    int runs = argc > 1 ? atoi(argv[1]) : 2000;
    ljgap_combine_input in[M];
    char *body = malloc(M * N * 3 * 32 + 200), *o = body;
    unsigned long seed = 1;
    if (!body || runs < 1 || runs > 100000) return 2;
    o += sprintf(o, "{\"psds\":[");
    for (int m = 0; m < M; m++) {
        const char *col[3] = {"k", "P", "P_err"};
        for (int i = 0; i < N; i++) {
            double u;
            seed = seed * 6364136223846793005UL + 1442695040888963407UL;
            u = (double)(seed >> 11) / 9007199254740992.0 - 0.5; /* uniform, var 1/12 */
            k[m][i] = 1e5 * pow(10, 1.5 * m + i / 10.0) * 1.013;
            P[m][i] = 1e-30 * pow(k[m][i], -3.4) * (1 + 0.05 * sqrt(12) * u);
            E[m][i] = 0.05 * P[m][i];
        }
        in[m] = (ljgap_combine_input){N, k[m], P[m], E[m], 0, 0, 0};
        o += sprintf(o, "%s{\"kind\":\"table\"", m ? "," : "");
        for (int c = 0; c < 3; c++) {
            const double *x = c == 0 ? k[m] : c == 1 ? P[m] : E[m];
            o += sprintf(o, ",\"%s\":[", col[c]);
            for (int i = 0; i < N; i++)
                o += sprintf(o, "%s%.17g", i ? "," : "", x[i]);
            o += sprintf(o, "]");
        }
        o += sprintf(o, "}");
    }
    o += sprintf(o, "]}");
    for (int r = 0; r < runs; r++) {
        ljgap_combine_result res;
        ljgap__reply rep;
        double t0 = ljgap__now();
        int st = ljgap_combine(in, M, NULL, &res, NULL);
        t_core[r] = 1e3 * (ljgap__now() - t0);
        ljgap_combine_result_free(&res);
        t0 = ljgap__now();
        ljgap__handle("psd/combine", body, strlen(body), &rep);
        t_all[r] = 1e3 * (ljgap__now() - t0);
        if (st || rep.status != 200) {
            fprintf(stderr, "combine: status %d, %d: %.300s\n", st, rep.status, rep.body);
            return 1;
        }
        ljgap__reply_free(&rep);
    }
    printf("combine of %d PSDs of %d points (%zu bytes of JSON), %d runs\n", M, N, strlen(body),
           runs);
    printf("core_ms median %.4f p99 %.4f\n", pct(t_core, runs, 0.5), pct(t_core, runs, 0.99));
    printf("handler_ms median %.4f p99 %.4f (JSON parse, validation, core, answer)\n",
           pct(t_all, runs, 0.5), pct(t_all, runs, 0.99));
    free(body);
    return 0;
}
