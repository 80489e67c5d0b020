/* uncert.c -- the cost of input_error (issue 29: at most 20 times the answer without it; the
 * Fig. 4 adhesion within 30 ms).
 *
 *   uncert [RUNS]   each request through the whole handler (JSON parse, validation, solves,
 *                   answer) RUNS times (default 21) with its errors and with "input_error":
 *                   false: the medians in ms and their ratio.
 *
 * The requests: Fig. 4's power law (D 2.5, k1 1, C 1/(4π)) with D_err and C_err (linear
 * propagation: 4 more solves); the same law as a table of 16 knots over k 1 ... 1000 with 10 %
 * P_err, the neighbours' correlation -0.37 and a tail with exponent_err (12 draws and the
 * extrapolated solve). Figures, never assertions (bench.h).
 */
#include "bench.h"
#include "core.h" /* ljgap__now */
#include "handler.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double median_ms(const char *endpoint, const char *body, int runs, int *status)
{
    double *t = malloc((size_t)runs * sizeof *t), m;
    for (int i = 0; i < runs; i++) {
        ljgap__reply r;
        double t0 = ljgap__now();
        ljgap__handle(endpoint, body, strlen(body), &r);
        t[i] = (ljgap__now() - t0) * 1e3;
        *status = r.status;
        ljgap__reply_free(&r);
    }
    m = bench_median(t, runs);
    free(t);
    return m;
}

int main(int argc, char **argv)
{
    int runs = argc > 1 ? atoi(argv[1]) : 21, st1, st0;
    char table[4000], *o = table;
    const double C = 1 / (4 * M_PI);
    if (runs < 1 || runs > 10000) return 2;
    o += sprintf(o, "\"psd\":{\"kind\":\"table\",\"k\":[");
    for (int i = 0; i < 16; i++)
        o += sprintf(o, "%s%.17g", i ? "," : "", pow(10, i * 0.2));
    o += sprintf(o, "],\"P\":[");
    for (int i = 0; i < 16; i++)
        o += sprintf(o, "%s%.17g", i ? "," : "", C * pow(10, i * 0.2 * -3));
    o += sprintf(o, "],\"P_err\":[");
    for (int i = 0; i < 16; i++)
        o += sprintf(o, "%s%.17g", i ? "," : "", 0.1 * C * pow(10, i * 0.2 * -3));
    o += sprintf(o, "],\"P_corr\":[");
    for (int i = 0; i < 15; i++)
        o += sprintf(o, "%s-0.37", i ? "," : "");
    o += sprintf(o, "],\"tail\":{\"exponent\":-3,\"exponent_err\":0.05}}");
    const struct {
        const char *name, *endpoint;
        char body[4200];
    } cases[] = {
        {"Fig. 4 adhesion, power law with D_err 0.03, C_err 0.008", "adhesion",
         "\"psd\":{\"kind\":\"power\",\"D\":2.5,\"k1\":1,\"C\":0.0795774715459477,"
         "\"D_err\":0.03,\"C_err\":0.008}"},
        {"Fig. 4's law as a 16-knot table, 10 % P_err, P_corr, tail", "adhesion", ""},
        {"the same table, traction at 100 gaps", "traction", ""},
    };
    snprintf((char *)cases[1].body, sizeof cases[1].body, "%s", table);
    snprintf((char *)cases[2].body, sizeof cases[2].body,
             "%s,\"g_ave\":{\"min\":2,\"max\":6,\"n\":100}", table);
    ljgap_init();
    printf("# median wall time of the whole handler over %d runs (ms): with input_error, without "
           "(\"input_error\": false), ratio\n",
           runs);
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        char with[4400], without[4400];
        snprintf(with, sizeof with, "{%s}", cases[c].body);
        snprintf(without, sizeof without, "{%s,\"input_error\":false}", cases[c].body);
        double t1 = median_ms(cases[c].endpoint, with, runs, &st1);
        double t0 = median_ms(cases[c].endpoint, without, runs, &st0);
        printf("%-62s %8.2f %8.2f %6.1fx%s\n", cases[c].name, t1, t0, t1 / t0,
               st1 == 200 && st0 == 200 ? "" : "  (not 200!)");
    }
    return 0;
}
