/* request_sim.c -- validation of a simulation request, POST /v1/simulations (request.h).
 *
 * The discrete model's grid (n even, L from 2π/k1), realizations, seed, the mean gaps (as
 * traction's g_ave) and, for the hybrid, k_split between k1 and the grid's reach and above k0;
 * the psd must have a finite top the grid can carry (a power law's k2, a table's last knot) or
 * a k2 given for the simulated surface. The walk and its validators are request.c's (ljgap__v_*).
 */
#include "request.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* The band [k1, k2] of a parsed psd into k (NAN where unknown, k2 INFINITY for a power law
 * without one or a table with a tail). */
static void sim_band(const ljgap__psd_spec *s, double k[2])
{
    k[0] = k[1] = NAN;
    if (s->kind == LJGAP_PSD_POWER) {
        k[0] = s->k1;
        k[1] = s->k2;
    } else if (s->kind == LJGAP_PSD_TABLE && s->k && s->n > 1) {
        k[0] = s->k[0];
        k[1] = s->has_tail ? INFINITY : s->k[s->n - 1];
    }
    if (!isfinite(k[0])) k[0] = NAN;
}

/* The hybrid's k_split: k1 <= k_split <= LJGAP_K_MAX and above k0 (its band's law is the
 * theory's). Returns the top wavenumber the grid must carry, *name its name: k_split when it is
 * below k2, else k2, which must then be finite (the plain model), NAN when unknown. */
static double sim_top(ljgap__verr *e, const cJSON *root, const ljgap__psd_spec *s, const double k[2],
                      ljgap_sim_opts *o, const char **name)
{
    const cJSON *it = ljgap__v_member(root, "k_split");
    double x;
    int bad = e->n;
    *name = "k2";
    if (it && ljgap__v_num_pos(e, it, "/k_split", &x)) {
        if (!isnan(k[0]) && !(x >= k[0]))
            ljgap__verr_add(e, "/k_split",
                           "k_split = %g is below k1 = %g: the grid carries [k1, k_split] "
                           "(k_split = k1 is the theory alone)",
                           x, k[0]);
        else if (!(x > ljgap_k0()))
            ljgap__verr_add(e, "/k_split",
                           "k_split = %g is at or below k0 = %.5f: the fine band's law (the "
                           "theory) needs k_split > k0 (19)",
                           x, ljgap_k0());
        else if (ljgap__v_in_core_range(e, "/k_split", "k_split", x, 0, LJGAP_K_MAX))
            o->k_split = x;
    }
    if (it && e->n > bad) return NAN; /* a bad k_split: the grid is checked once it is fixed */
    if (o->k_split > 0 && !(o->k_split >= k[1])) {
        *name = "k_split";
        return o->k_split;
    }
    if (s->kind == LJGAP_PSD_POWER && isinf(k[1]))
        ljgap__verr_add(e, "/psd/k2",
                       "the numerical model needs a band-limited PSD: give a finite k2 (the grid "
                       "carries wavenumbers up to πn/L), or k_split for the hybrid");
    else if (s->kind == LJGAP_PSD_TABLE && s->has_tail)
        ljgap__verr_add(e, "/psd/tail",
                       "the numerical model needs a band-limited PSD: drop the tail (the table "
                       "then ends at its last k), or give k_split for the hybrid");
    return isfinite(k[1]) ? k[1] : NAN;
}

/* The grid of a simulation: n even in [8, LJGAP_SIM_N_MAX], L in [2π/k1, 1e4·2π/k1] (0: 2π/k1),
 * and the Nyquist wavenumber πn/L at or above top (k2, or k_split for the hybrid: the rules of
 * ljgap_sim_run; a grid that misses it is reported at /n with the n that would do, or at
 * /psd/k2 or /k_split when none would). */
static void parse_sim_grid(ljgap__verr *e, const cJSON *root, double k1, double top,
                           const char *name, ljgap_sim_opts *o)
{
    const cJSON *it;
    double x, Lmin = 2 * M_PI / k1, L;
    int ok = 1;
    if ((it = ljgap__v_member(root, "n"))) {
        if (!ljgap__v_num_int(e, it, "/n", 8, LJGAP_SIM_N_MAX, &x)) {
            ok = 0;
        } else if (fmod(x, 2) != 0) {
            ljgap__verr_add(e, "/n", "n = %g must be even (the grid is n × n for the FFT)", x);
            ok = 0;
        } else {
            o->n = (int)x;
        }
    }
    if ((it = ljgap__v_member(root, "L"))) {
        if (!ljgap__v_num_pos(e, it, "/L", &o->L)) {
            ok = 0;
        } else if (!isnan(Lmin) && !(o->L >= Lmin * (1 - 1e-12) && o->L <= 1e4 * Lmin)) {
            ljgap__verr_add(e, "/L",
                           "L = %g is outside [2π/k1, 1e4·2π/k1] = [%.6g, %.6g]: the square "
                           "must carry the band's longest wave",
                           o->L, Lmin, 1e4 * Lmin);
            ok = 0;
        }
    }
    if (!ok || isnan(Lmin) || isnan(top)) return;
    L = o->L > 0 ? o->L : Lmin;
    if (top > M_PI * o->n / L * (1 + 1e-12)) {
        double need = ceil(top * L / M_PI);
        need += fmod(need, 2);
        if (need <= LJGAP_SIM_N_MAX)
            ljgap__verr_add(e, "/n",
                           "the grid does not resolve %s = %g: its highest wavenumber is "
                           "πn/L = %g (n = %d, L = %g); n >= %.0f would do",
                           name, top, M_PI * o->n / L, o->n, L, need);
        else
            ljgap__verr_add(e, strcmp(name, "k2") ? "/k_split" : "/psd/k2",
                           "no grid resolves %s = %g with L = %g: that needs n >= %.0f, over "
                           "the cap %d; lower %s or take a smaller L",
                           name, top, L, need, LJGAP_SIM_N_MAX, name);
    }
}

/* A simulation (ljgap_sim.h): k_split (the hybrid), grid, realizations, seed, tol and the mean
 * gaps, which are a list or a range as for traction, at most LJGAP_SIM_GAPS_MAX of them. */
void ljgap__request_parse_simulation(ljgap__verr *e, const cJSON *root, const ljgap__limits *lim,
                                    ljgap__request *rq)
{
    ljgap_sim_opts *o = &rq->sim;
    ljgap__limits gaps = *lim;
    const cJSON *it;
    double x, k[2];
    const char *top_name;
    ljgap_sim_opts_default(o);
    sim_band(&rq->psd, k);
    double top = sim_top(e, root, &rq->psd, k, o, &top_name);
    parse_sim_grid(e, root, k[0], top, top_name, o);
    if ((it = ljgap__v_member(root, "realizations")) &&
        ljgap__v_num_int(e, it, "/realizations", 1, LJGAP_SIM_REALIZATIONS_MAX, &x))
        o->realizations = (int)x;
    if ((it = ljgap__v_member(root, "seed")) &&
        ljgap__v_num_int(e, it, "/seed", 0, LJGAP_SEED_MAX, &x))
        o->seed = (unsigned long)x;
    if ((it = ljgap__v_member(root, "tol")) && ljgap__v_num(e, it, "/tol", &x)) {
        if (x >= 1e-14 && x <= 1e-2)
            o->tol = x;
        else
            ljgap__verr_add(e, "/tol",
                           "tol = %g is outside [1e-14, 1e-2] (the rms residual of the force "
                           "balance relative to σ0)",
                           x);
    }
    if (gaps.max_points > LJGAP_SIM_GAPS_MAX) gaps.max_points = LJGAP_SIM_GAPS_MAX;
    ljgap__v_traction(e, root, &gaps, rq);
}
