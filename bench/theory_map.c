/* theory_map.c -- where the statistical theory holds: the adhesion summary (g_eq, sigma_max,
 * g_at_max, dgamma_eff) of the discrete numerical model (core/sim/sim.c) against the theory's (PDE)
 * and the hybrid's (k_split), for one spectrum per call (bench/theory_map.sh runs the
 * map over D and m0).
 *
 *   theory_map --D D --m0 M0 [--k1 K1] [--k2 K2] [--n N] [--L L] [--R R] [--threads T]
 *              [--k_split K,K..] [--hyb-n N,N..] [--label NAME] [--no-full] [--header]
 *
 * One CSV row per model: the theory, the discrete model at n, L (R realizations) unless
 * --no-full, and the hybrid at each k_split (on hyb-n points, the same L). The discrete
 * summaries come from the mean curve over a sweep of mean gaps (dense near contact, out to
 * where the analytic tail of ljgap__curve_summary holds), and their errors are the jackknife
 * over realizations (the summary of each leave-one-out mean) plus the sweep's sampling error
 * (|summary(all gaps) - summary(every other gap)| / 15: the spline is fourth order) plus, for
 * the hybrid, the law's own error (in error.sigma). Timings are wall seconds of the run.
 */
#include "core.h" /* ljgap__curve_summary */
#include "ljgap_sim.h"

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GAPS_MAX LJGAP_SIM_GAPS_MAX

/* The mean gaps of a sweep for variance m0: 0.025 apart from 0.85 to 2, 0.05 to 3, 0.1 to 4,
 * 0.25 beyond, to 10.5 sqrt(m0) at least (the tail's series needs m0/g^2 <= 0.01) and 4.5. */
static size_t sweep(double m0, double *g)
{
    double end = fmax(4.5, 10.5 * sqrt(m0)), x = 0.85;
    size_t n = 0;
    while (x <= end + 1e-9 && n < GAPS_MAX) {
        g[n++] = x;
        x += x < 2 - 1e-9 ? 0.025 : x < 3 - 1e-9 ? 0.05 : x < 4 - 1e-9 ? 0.1 : 0.25;
    }
    return n;
}

/* Summary of a curve (values), every point or every other (stride 2). */
static int curve_sum(const double *g, const double *u, size_t n, int stride, double m0,
                     ljgap_summary *s)
{
    double gg[GAPS_MAX], uu[GAPS_MAX];
    size_t m = 0;
    for (size_t i = 0; i < n; i += (size_t)stride)
        gg[m] = g[i], uu[m++] = u[i];
    if (gg[m - 1] != g[n - 1]) gg[m] = g[n - 1], uu[m++] = u[n - 1];
    ljgap_warnings w = {0};
    return ljgap__curve_summary(gg, uu, m, m0, s, &w);
}

/* The discrete (or hybrid) model's summary with errors; *secs its run time. */
static int model(const ljgap_psd *p, const ljgap_sim_opts *o, const double *g, size_t n,
                 ljgap_summary *out, double *secs, int *jumps)
{
    ljgap_sim_result r;
    ljgap_warnings w = {0};
    double t = ljgap__now();
    int st = ljgap_sim_run(p, o, g, n, &r, &w);
    *secs = ljgap__now() - t;
    for (int i = 0; i < w.n; i++)
        if (!strstr(w.msg[i], "lattice of wavevectors")) fprintf(stderr, "sim: %s\n", w.msg[i]);
    if (st) {
        fprintf(stderr, "sim: %s\n", ljgap_strerror(st));
        return st;
    }
    const int R = r.realizations;
    *jumps = 0;
    double syst = 0.0; /* the solver's residual and (hybrid) the law: error.sigma less the
                        * standard error */
    for (size_t i = 0; i < n; i++) {
        *jumps += r.jump[i];
        syst = fmax(syst, r.sigma_err[i] - r.sigma_std[i] / sqrt((double)R));
    }
    ljgap_summary all, half, jk[LJGAP_SIM_REALIZATIONS_MAX];
    st = curve_sum(g, r.sigma, n, 1, p->m0, &all) || curve_sum(g, r.sigma, n, 2, p->m0, &half);
    double loo[GAPS_MAX];
    for (int k = 0; k < R && !st && R > 1; k++) {
        for (size_t i = 0; i < n; i++) {
            double s = 0.0;
            for (int q = 0; q < R; q++)
                if (q != k) s += r.sigma_each[(size_t)q * n + i];
            loo[i] = s / (R - 1);
        }
        st = curve_sum(g, loo, n, 1, p->m0, &jk[k]);
    }
    if (st) {
        fprintf(stderr, "summary: the curve has no root or no maximum on [%g, %g]\n", g[0],
                g[n - 1]);
        ljgap_sim_result_free(&r);
        return st;
    }
    *out = all;
    for (int q = 0; q < 4; q++) {
        double m = 0.0, v = 0.0;
        for (int k = 0; k < R; k++)
            m += (&jk[k].g_eq)[q].value / R;
        for (int k = 0; k < R; k++)
            v += pow((&jk[k].g_eq)[q].value - m, 2);
        double jack = R > 1 ? sqrt((R - 1.0) / R * v) : 0.0;
        double samp = fabs((&all.g_eq)[q].value - (&half.g_eq)[q].value) / 15.0;
        /* syst shifts sigma_max by at most itself (and the rest by far less than jack) */
        (&out->g_eq)[q].err = jack + samp + (q == 1 ? syst : 0.0);
    }
    ljgap_sim_result_free(&r);
    return LJGAP_OK;
}

static void row(const char *label, double D, double m0, const char *what, double ks,
                const ljgap_sim_opts *o, double L, double secs, const ljgap_summary *s, size_t ng,
                int jumps)
{
    printf("%s,%g,%g,%s,%g,%d,%.6g,%d,%.3f", label, D, m0, what, ks, o ? o->n : 0, L,
           o ? o->realizations : 0, secs);
    for (int q = 0; q < 4; q++) {
        const ljgap_est *e = &s->g_eq + q;
        printf(",%.6f,%.2g", e->value, e->err);
    }
    printf(",%zu,%d\n", ng, jumps);
    fflush(stdout);
}

static int parse_list(const char *s, double *v, int max)
{
    int n = 0;
    char *end;
    while (n < max && *s) {
        v[n++] = strtod(s, &end);
        if (*end != ',') break;
        s = end + 1;
    }
    return n;
}

int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    double D = 2.2, m0 = 0.1, k1 = 1.0, k2 = 8.0, ks[8], hn[8];
    int nks = 0, nhn = 0, header = 0, full = 1;
    const char *label = "map";
    ljgap_sim_opts o;
    ljgap_sim_opts_default(&o);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--header")) {
            header = 1;
            continue;
        }
        if (!strcmp(a, "--no-full")) {
            full = 0;
            continue;
        }
        if (!v) goto usage;
        i++;
        if (!strcmp(a, "--D"))
            D = atof(v);
        else if (!strcmp(a, "--m0"))
            m0 = atof(v);
        else if (!strcmp(a, "--k1"))
            k1 = atof(v);
        else if (!strcmp(a, "--k2"))
            k2 = atof(v);
        else if (!strcmp(a, "--n"))
            o.n = atoi(v);
        else if (!strcmp(a, "--L"))
            o.L = atof(v);
        else if (!strcmp(a, "--R"))
            o.realizations = atoi(v);
        else if (!strcmp(a, "--threads"))
            o.threads = atoi(v);
        else if (!strcmp(a, "--k_split"))
            nks = parse_list(v, ks, 8);
        else if (!strcmp(a, "--hyb-n"))
            nhn = parse_list(v, hn, 8);
        else if (!strcmp(a, "--label"))
            label = v;
        else
            goto usage;
    }
    if (nhn != nks) goto usage;
    o.max_seconds = 3600;
    if (header)
        printf("label,D,m0,model,k_split,n,L,R,seconds,g_eq,g_eq_err,sigma_max,sigma_max_err,"
               "g_at_max,g_at_max_err,dgamma_eff,dgamma_eff_err,n_gaps,jumps\n");
    ljgap_psd p;
    if (ljgap_psd_power(&p, D, k1, k2, LJGAP_LEVEL_M0, m0)) goto usage;
    double g[GAPS_MAX];
    size_t ng = sweep(m0, g);
    double L = o.L > 0 ? o.L : 2 * M_PI / k1, secs;
    int jumps;
    ljgap_summary s;
    ljgap_opts to;
    ljgap_opts_default(&to);
    ljgap_warnings w = {0};
    double t = ljgap__now();
    if (ljgap_traction(&p, &to, NULL, 0, NULL, &s, &w)) {
        fprintf(stderr, "theory failed\n");
        return 1;
    }
    row(label, D, m0, "theory", 0, NULL, 0, ljgap__now() - t, &s, 0, 0);
    if (full) {
        if (model(&p, &o, g, ng, &s, &secs, &jumps)) return 1;
        row(label, D, m0, "discrete", 0, &o, L, secs, &s, ng, jumps);
    }
    for (int k = 0; k < nks; k++) {
        ljgap_sim_opts h = o;
        h.k_split = ks[k];
        h.n = (int)hn[k];
        if (model(&p, &h, g, ng, &s, &secs, &jumps)) return 1;
        row(label, D, m0, "hybrid", ks[k], &h, L, secs, &s, ng, jumps);
    }
    return 0;
usage:
    fprintf(stderr, "usage: theory_map --D D --m0 M0 [--k1 K1] [--k2 K2] [--n N] [--L L] [--R R] "
                    "[--threads T] [--k_split K,..] [--hyb-n N,..] [--label NAME] [--no-full] "
                    "[--header]\n");
    return 2;
}
