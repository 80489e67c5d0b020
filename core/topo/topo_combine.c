/* topo_combine.c -- several measured PSDs of one surface combined into one (ljgap_combine.h).
 *
 * The grid: k = 10^(i/g) (g points a decade, i integer), every such k that lies inside at least
 * one input's band [k[0], k[n-1]]. An input covers a grid point only inside its own band: it is
 * interpolated there log-log between its two neighbouring points, ln P = (1-t) ln P_j +
 * t ln P_{j+1} with t the position in ln k, and never extrapolated.
 *
 * Errors of an interpolated point. The inputs' points are independent (a periodogram's bins
 * share no modes), but two grid points interpolated from the same pair of bins are not, and a
 * fit that took them as independent would count those bins twice. So the interpolated error is
 * the interpolation of the neighbours' relative errors, σ = (1-t) σ_j + t σ_{j+1} (the bound for
 * fully correlated neighbours: no grid point claims more precision than the bins it comes
 * from), and when the grid is finer than the input's bins (g above the input's points per
 * decade d) it is scaled by √(g/d): each input's information then enters the combination and
 * the fit about once, not once per grid point. When the grid is coarser than an input, the
 * bins between grid points are not used (their information is lost, conservatively).
 *
 * Combining. Where several inputs cover a point, y_i = ln P_i with σ_i = P_err_i/P_i (floored at
 * SIGMA_FLOOR so that an input given with zero error weighs heavily but finitely) are averaged
 * with weights w_i = 1/σ_i²: ln P = Σ w y / Σ w, σ = 1/√Σw, and χ² = Σ w (y - ln P)² measures
 * the inputs' disagreement; with χ²_red = χ²/(inputs - 1) > 1 the point's σ is multiplied by
 * √χ²_red (the Birge ratio). The χ² summed over every overlapping point gives a p-value: below
 * DISAGREE_P the answer warns that the measurements disagree. P = exp(ln P), P_err = P σ.
 *
 * Gaps. A stretch of k no input covers is named in a warning and left without points (a table
 * PSD is interpolated log-log across it by whoever uses it).
 *
 * The fit: weighted least squares of ln P on ln k over every combined point, weights 1/σ²;
 * D = (slope + 8)/2, C = e^intercept; errors from the covariance, scaled by √χ²_red when it
 * exceeds 1 (as ljgap_topo's fit).
 */
#include "ljgap_combine.h"

#include <gsl/gsl_cdf.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SIGMA_FLOOR 1e-9 /* smallest σ of ln P an input point enters with */
#define DISAGREE_P 0.01  /* a combined χ² this improbable is a disagreement worth a warning */
#define EDGE 1e-9        /* relative tolerance of a band edge (in ln k) */

void ljgap_combine_opts_default(ljgap_combine_opts *o)
{
    o->per_decade = 10;
    o->cancel = NULL;
}

void ljgap_combine_result_free(ljgap_combine_result *r)
{
    if (!r) return;
    free(r->k);
    free(r->P);
    free(r->P_err);
    free(r->inputs);
    free(r->chi2);
    r->k = r->P = r->P_err = r->chi2 = NULL;
    r->inputs = NULL;
    r->n = 0;
}

/* Is in a valid table? The reason into w when not. */
static int table_ok(const ljgap_combine_input *in, size_t i, ljgap_warnings *w)
{
    if (in->n < 2 || !in->k || !in->P || !in->P_err) {
        ljgap_warn(w, "psds[%zu] has fewer than two points", i);
        return 0;
    }
    for (size_t j = 0; j < in->n; j++) {
        if (!(isfinite(in->k[j]) && in->k[j] > 0 && (j == 0 || in->k[j] > in->k[j - 1]) &&
              isfinite(in->P[j]) && in->P[j] > 0 && isfinite(in->P_err[j]) && in->P_err[j] >= 0)) {
            ljgap_warn(w, "psds[%zu] point %zu is not a valid (k, P, P_err)", i, j);
            return 0;
        }
    }
    return 1;
}

static int covers(const ljgap_combine_input *in, double lk)
{
    return lk >= log(in->k[0]) - EDGE && lk <= log(in->k[in->n - 1]) + EDGE;
}

/* ln P and its σ of input in at ln k = lk (inside its band); *j is a cursor that only moves up
 * (the grid is increasing). scale: the variance factor max(1, g/d). */
static void interpolate(const ljgap_combine_input *in, double lk, size_t *j, double scale,
                        double *y, double *s)
{
    while (*j + 2 < in->n && log(in->k[*j + 1]) < lk)
        (*j)++;
    size_t a = *j, b = a + 1;
    double la = log(in->k[a]), lb = log(in->k[b]);
    double t = (lk - la) / (lb - la);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    *y = (1 - t) * log(in->P[a]) + t * log(in->P[b]);
    *s = ((1 - t) * in->P_err[a] / in->P[a] + t * in->P_err[b] / in->P[b]) * sqrt(scale);
    if (!(*s >= SIGMA_FLOOR)) *s = SIGMA_FLOOR;
}

/* The stretches of k no input covers, into r->gap (warned). */
static void find_gaps(const ljgap_combine_input *in, size_t m, ljgap_combine_result *r,
                      ljgap_warnings *w)
{
    int used[LJGAP_COMBINE_MAX] = {0};
    double reach = 0;
    for (size_t done = 0; done < m; done++) {
        size_t b = m;
        for (size_t i = 0; i < m; i++) /* the next band by its start */
            if (!used[i] && (b == m || in[i].k[0] < in[b].k[0])) b = i;
        used[b] = 1;
        if (done && in[b].k[0] > reach * (1 + EDGE)) {
            if (r->ngaps < LJGAP_COMBINE_GAPS) {
                r->gap[r->ngaps][0] = reach;
                r->gap[r->ngaps][1] = in[b].k[0];
            }
            r->ngaps++;
            ljgap_warn(w,
                       "no measurement covers k = %g … %g 1/m: the combined table has no points "
                       "there (a table PSD is interpolated log-log across the gap)",
                       reach, in[b].k[0]);
        }
        reach = fmax(reach, in[b].k[in[b].n - 1]);
    }
    if (r->ngaps > LJGAP_COMBINE_GAPS) r->ngaps = LJGAP_COMBINE_GAPS;
}

/* Weighted least squares of ln P on ln k over the combined points (see the top). */
static int fit_combined(const ljgap_combine_result *r, ljgap_topo_fit *f)
{
    double S = 0, Sx = 0, Sy = 0, Sxx = 0, Sxy = 0, chi2 = 0;
    if (r->n < 3) return -1;
    for (size_t i = 0; i < r->n; i++) {
        double s = r->P_err[i] / r->P[i], wt = 1 / (s * s);
        S += wt, Sx += wt * log(r->k[i]), Sy += wt * log(r->P[i]);
    }
    double xm = Sx / S, ym = Sy / S;
    for (size_t i = 0; i < r->n; i++) {
        double s = r->P_err[i] / r->P[i], wt = 1 / (s * s), dx = log(r->k[i]) - xm;
        Sxx += wt * dx * dx;
        Sxy += wt * dx * (log(r->P[i]) - ym);
    }
    if (!(Sxx > 0) || !isfinite(Sxx)) return -1;
    double slope = Sxy / Sxx;
    for (size_t i = 0; i < r->n; i++) {
        double s = r->P_err[i] / r->P[i];
        double res = (log(r->P[i]) - ym - slope * (log(r->k[i]) - xm)) / s;
        chi2 += res * res;
    }
    double chi2_red = chi2 / (double)(r->n - 2), scale = chi2_red > 1 ? chi2_red : 1;
    double var_s = scale / Sxx, var_lnC = scale / S + xm * xm * var_s, lnC = ym - slope * xm;
    f->D.value = 0.5 * (slope + 8);
    f->D.err = 0.5 * sqrt(var_s);
    f->C.value = exp(lnC);
    f->C.err = f->C.value * sqrt(var_lnC);
    f->corr = var_lnC > 0 ? -xm * var_s / sqrt(var_lnC * var_s) : 0;
    if (!isfinite(f->C.value) || !isfinite(f->C.err) || !isfinite(f->D.err) || !isfinite(f->corr) ||
        !isfinite(chi2_red))
        return -1; /* beyond the range of a double: no fit */
    f->kmin = r->k[0];
    f->kmax = r->k[r->n - 1];
    f->bins = r->n;
    f->chi2_red = chi2_red;
    return 0;
}

/* The tail of the combination (see ljgap_combine_result.tail_from). */
static void pick_tail(const ljgap_combine_input *in, size_t m, ljgap_combine_result *r,
                      ljgap_warnings *w)
{
    size_t top = 0;
    for (size_t i = 1; i < m; i++)
        if (in[i].k[in[i].n - 1] > in[top].k[in[top].n - 1]) top = i;
    if (in[top].has_tail) {
        r->tail_from = (int)top;
        r->tail_q = in[top].tail_q;
        r->tail_q_err = in[top].tail_q_err;
    } else if (r->has_fit && 2 * r->fit.D.value - 8 < -2) {
        r->tail_from = -1;
        r->tail_q = 2 * r->fit.D.value - 8;
        r->tail_q_err = 2 * r->fit.D.err;
    } else {
        r->tail_from = -2;
        ljgap_warn(w,
                   "the combined psd has no tail: psds[%zu], which reaches the highest k, has "
                   "none and %s, so the table ends at k = %g 1/m",
                   top,
                   r->has_fit ? "the fitted exponent 2D - 8 is not below -2"
                              : "there is no power-law fit",
                   r->k[r->n - 1]);
    }
}

int ljgap_combine(const ljgap_combine_input *in, size_t m, const ljgap_combine_opts *o,
                  ljgap_combine_result *r, ljgap_warnings *w)
{
    ljgap_combine_opts def;
    double lo = INFINITY, hi = 0, scale[LJGAP_COMBINE_MAX];
    size_t cur[LJGAP_COMBINE_MAX] = {0};
    long i0, i1;
    memset(r, 0, sizeof *r);
    if (!o) {
        ljgap_combine_opts_default(&def);
        o = &def;
    }
    if (m < LJGAP_COMBINE_MIN || m > LJGAP_COMBINE_MAX || !in || !(o->per_decade >= 2) ||
        !(o->per_decade <= 100)) {
        ljgap_warn(w, "give %d to %d PSDs and 2 to 100 grid points a decade", LJGAP_COMBINE_MIN,
                   LJGAP_COMBINE_MAX);
        return LJGAP_EINVAL;
    }
    r->m = m;
    for (size_t i = 0; i < m; i++) {
        if (!table_ok(&in[i], i, w)) return LJGAP_EINVAL;
        double band = log10(in[i].k[in[i].n - 1] / in[i].k[0]);
        scale[i] = fmax(1, o->per_decade * band / (double)(in[i].n - 1));
        r->src[i].k_min = in[i].k[0];
        r->src[i].k_max = in[i].k[in[i].n - 1];
        lo = fmin(lo, in[i].k[0]);
        hi = fmax(hi, in[i].k[in[i].n - 1]);
    }
    find_gaps(in, m, r, w);
    i0 = (long)ceil(o->per_decade * log10(lo) - 1e-6);
    i1 = (long)floor(o->per_decade * log10(hi) + 1e-6);
    size_t cap = i1 >= i0 ? (size_t)(i1 - i0 + 1) : 0;
    if (cap > LJGAP_COMBINE_GRID_MAX) {
        ljgap_warn(w,
                   "the bands span k = %g … %g 1/m: %zu grid points at %g a decade, more than %d",
                   lo, hi, cap, o->per_decade, LJGAP_COMBINE_GRID_MAX);
        return LJGAP_EINVAL;
    }
    if (cap) {
        r->k = malloc(cap * sizeof *r->k);
        r->P = malloc(cap * sizeof *r->P);
        r->P_err = malloc(cap * sizeof *r->P_err);
        r->chi2 = malloc(cap * sizeof *r->chi2);
        r->inputs = malloc(cap * sizeof *r->inputs);
        if (!r->k || !r->P || !r->P_err || !r->chi2 || !r->inputs) return LJGAP_ENOMEM;
    }
    for (long g = i0; g <= i1; g++) {
        double k = pow(10, (double)g / o->per_decade), lk = log(k);
        double y[LJGAP_COMBINE_MAX], wt[LJGAP_COMBINE_MAX], S = 0, Sy = 0, chi2 = 0, s;
        int c = 0;
        if (o->cancel && *o->cancel) return LJGAP_ECANCEL;
        for (size_t i = 0; i < m; i++) {
            if (!covers(&in[i], lk)) continue;
            interpolate(&in[i], lk, &cur[i], scale[i], &y[c], &s);
            wt[c] = 1 / (s * s);
            S += wt[c], Sy += wt[c] * y[c];
            r->src[i].points++;
            c++;
        }
        if (!c) continue;
        double ym = Sy / S, sig = 1 / sqrt(S);
        for (int i = 0; i < c; i++)
            chi2 += wt[i] * (y[i] - ym) * (y[i] - ym);
        if (c > 1) {
            r->chi2_total += chi2;
            r->dof += (size_t)(c - 1);
            if (chi2 > c - 1) {
                sig *= sqrt(chi2 / (c - 1));
                r->inflated++;
            }
        }
        if (!isfinite(exp(ym) * sig) || !(exp(ym) > 0)) {
            ljgap_warn(w, "the combined P at k = %g 1/m is beyond the range of a double", k);
            return LJGAP_EINVAL;
        }
        r->k[r->n] = k;
        r->P[r->n] = exp(ym);
        r->P_err[r->n] = exp(ym) * sig;
        r->chi2[r->n] = c > 1 ? chi2 : 0;
        r->inputs[r->n] = c;
        r->n++;
    }
    for (size_t i = 0; i < m; i++)
        if (!r->src[i].points)
            ljgap_warn(w,
                       "psds[%zu] (k = %g … %g 1/m) contributes no point: its band holds no "
                       "point of the grid (%g a decade)",
                       i, r->src[i].k_min, r->src[i].k_max, o->per_decade);
    if (r->n < 2) {
        ljgap_warn(w,
                   "the measurements' bands hold %zu point%s of the grid (%g a decade, k = %g … "
                   "%g 1/m): no usable band",
                   r->n, r->n == 1 ? "" : "s", o->per_decade, lo, hi);
        return LJGAP_EINVAL;
    }
    r->p_value = r->dof ? gsl_cdf_chisq_Q(r->chi2_total, (double)r->dof) : 1;
    if (r->dof && r->p_value < DISAGREE_P)
        ljgap_warn(w,
                   "the measurements disagree beyond their errors where they overlap (χ² = %.3g "
                   "for %zu degrees of freedom, p = %.2g): the errors of the %zu points with "
                   "χ²_red > 1 are inflated by √χ²_red",
                   r->chi2_total, r->dof, r->p_value, r->inflated);
    r->has_fit = fit_combined(r, &r->fit) == 0;
    if (r->has_fit && !(r->fit.D.value > 2 && r->fit.D.value < 3))
        ljgap_warn(w,
                   "the fitted D = %.3g lies outside (2, 3): the combined spectrum is not a "
                   "self-affine surface's over this band",
                   r->fit.D.value);
    pick_tail(in, m, r, w);
    return LJGAP_OK;
}
