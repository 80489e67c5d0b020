/* psd.c -- isotropic power spectral densities in dimensionless form (theory.md §1).
 *
 * Convention (22): the height variance is m0 = 2π ∫ k P(k) dk, so h_rms = √m0. A power
 * law (6) is P = C k^(2D-8) on [k1,k2], 2 < D < 3, k2 finite or infinite (the variance
 * 2πC(k2^(2D-6) - k1^(2D-6))/(2D-6) stays finite because 2D-6 < 0). A table gives P at
 * increasing k with log-log interpolation (each segment a power law), zero outside
 * [k[0], k[n-1]] unless a power-law tail of exponent q < -2 continues it to infinity.
 *
 * Everything is stored as power-law segments, so the variance of any band and its
 * inverse are analytic: for a segment P = Pj (k/kj)^q,
 *   2π ∫_ka^kb s P ds = 2π Pj kj^2 [ (kb/kj)^e - (ka/kj)^e ]/e,  e = q + 2,
 * evaluated with expm1 so that thin bands keep full relative accuracy.
 */
#include "ljgap.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* 2π Pj kj^2 [(kb/kj)^e - (ka/kj)^e]/e, e = q + 2, for kj <= ka <= kb. */
static double seg_var(double Pj, double kj, double q, double ka, double kb)
{
    double e = q + 2.0;
    double xa = log(ka / kj), dx = log1p((kb - ka) / ka);
    double r;
    if (fabs(e * (xa + dx)) < 1e-12)
        r = dx;
    else
        r = exp(e * xa) * expm1(e * dx) / e;
    return 2.0 * M_PI * Pj * kj * kj * r;
}

/* The k >= ka in a segment with seg_var(Pj,kj,q,ka,k) = dtau. */
static double seg_inv(double Pj, double kj, double q, double ka, double dtau)
{
    double e = q + 2.0;
    double c = dtau / (2.0 * M_PI * Pj * kj * kj);
    double ra = ka / kj;
    if (fabs(e) < 1e-12) return ka * exp(c);
    /* (k/kj)^e = ra^e + e c */
    double rae = pow(ra, e);
    double t = rae + e * c;
    if (t <= 0) return INFINITY; /* beyond the end of an infinite tail */
    return ka * exp(log1p(e * c / rae) / e);
}

static void psd_zero(ljgap_psd *p)
{
    memset(p, 0, sizeof *p);
}

int ljgap_psd_power(ljgap_psd *psd, double D, double k1, double k2, ljgap_level lk, double level)
{
    if (!(D > 2 && D < 3) || !(k1 > 0) || !isfinite(k1) || !(k2 > k1) || !(level > 0) ||
        !isfinite(level) || isnan(k2))
        return LJGAP_EINVAL;
    ljgap_psd p;
    psd_zero(&p);
    p.kind = LJGAP_PSD_POWER;
    p.D = D;
    p.k1 = k1;
    p.k2 = k2;
    double q = 2.0 * D - 8.0;
    /* variance of C = 1 */
    double v1;
    if (isinf(k2))
        v1 = 2.0 * M_PI * pow(k1, q + 2.0) / -(q + 2.0);
    else
        v1 = seg_var(pow(k1, q), k1, q, k1, k2);
    double m0;
    switch (lk) {
    case LJGAP_LEVEL_C:
        p.C = level;
        m0 = level * v1;
        break;
    case LJGAP_LEVEL_M0:
        m0 = level;
        p.C = level / v1;
        break;
    case LJGAP_LEVEL_HRMS:
        m0 = level * level;
        p.C = m0 / v1;
        break;
    default:
        return LJGAP_EINVAL;
    }
    if (!(m0 > 0) || !isfinite(m0) || !(p.C > 0) || !isfinite(p.C)) return LJGAP_EINVAL;
    p.m0 = m0;
    *psd = p;
    return LJGAP_OK;
}

int ljgap_psd_table(ljgap_psd *psd, const double *k, const double *P, size_t n, int has_tail,
                    double tail_q)
{
    if (n < 2) return LJGAP_EINVAL;
    for (size_t i = 0; i < n; i++) {
        if (!(k[i] > 0) || !isfinite(k[i]) || !(P[i] > 0) || !isfinite(P[i])) return LJGAP_EINVAL;
        if (i > 0 && !(k[i] > k[i - 1])) return LJGAP_EINVAL;
    }
    if (has_tail && !(tail_q < -2.0)) return LJGAP_EINVAL;
    ljgap_psd p;
    psd_zero(&p);
    p.kind = LJGAP_PSD_TABLE;
    p.n = n;
    p.k = malloc(n * sizeof *p.k);
    p.P = malloc(n * sizeof *p.P);
    p.cum = malloc(n * sizeof *p.cum);
    p.q = malloc(n * sizeof *p.q);
    if (!p.k || !p.P || !p.cum || !p.q) {
        ljgap_psd_free(&p);
        return LJGAP_ENOMEM;
    }
    memcpy(p.k, k, n * sizeof *k);
    memcpy(p.P, P, n * sizeof *P);
    p.cum[0] = 0;
    for (size_t i = 0; i + 1 < n; i++) {
        p.q[i] = log(P[i + 1] / P[i]) / log(k[i + 1] / k[i]);
        p.cum[i + 1] = p.cum[i] + seg_var(P[i], k[i], p.q[i], k[i], k[i + 1]);
    }
    p.q[n - 1] = has_tail ? tail_q : 0.0;
    p.has_tail = has_tail != 0;
    p.tail_q = has_tail ? tail_q : 0.0;
    p.k1 = k[0];
    p.k2 = has_tail ? INFINITY : k[n - 1];
    p.m0 = p.cum[n - 1];
    if (has_tail) p.m0 += 2.0 * M_PI * P[n - 1] * k[n - 1] * k[n - 1] / -(tail_q + 2.0);
    if (!(p.m0 > 0) || !isfinite(p.m0)) {
        ljgap_psd_free(&p);
        return LJGAP_EINVAL;
    }
    *psd = p;
    return LJGAP_OK;
}

void ljgap_psd_free(ljgap_psd *psd)
{
    if (!psd) return;
    free(psd->k);
    free(psd->P);
    free(psd->cum);
    free(psd->q);
    psd->k = psd->P = psd->cum = psd->q = NULL;
    psd->n = 0;
}

int ljgap_psd_truncate(ljgap_psd *out, const ljgap_psd *psd, double kc)
{
    if (!(kc > psd->k1)) return LJGAP_EINVAL;
    if (psd->kind == LJGAP_PSD_POWER) {
        *out = *psd;
        if (kc < psd->k2) {
            out->k2 = kc;
            out->m0 = ljgap_psd_cumvar(psd, kc);
        }
        return LJGAP_OK;
    }
    /* table: keep the nodes below kc and add one at kc */
    size_t m = 0;
    while (m < psd->n && psd->k[m] < kc)
        m++;
    if (m == psd->n && !psd->has_tail) return ljgap_psd_table(out, psd->k, psd->P, psd->n, 0, 0.0);
    double *k = malloc((m + 1) * sizeof *k), *P = malloc((m + 1) * sizeof *P);
    if (!k || !P) {
        free(k);
        free(P);
        return LJGAP_ENOMEM;
    }
    memcpy(k, psd->k, m * sizeof *k);
    memcpy(P, psd->P, m * sizeof *P);
    size_t n = m;
    if (m < psd->n && psd->k[m] == kc)
        P[n] = psd->P[m], k[n++] = kc;
    else
        k[n] = kc, P[n] = ljgap_psd_eval(psd, kc), n++;
    int st = ljgap_psd_table(out, k, P, n, 0, 0.0);
    free(k);
    free(P);
    return st;
}

int ljgap_psd_above(ljgap_psd *out, const ljgap_psd *psd, double kc)
{
    if (!(kc > psd->k1) || !(kc < psd->k2)) return LJGAP_EINVAL;
    if (psd->kind == LJGAP_PSD_POWER)
        return ljgap_psd_power(out, psd->D, kc, psd->k2, LJGAP_LEVEL_C, psd->C);
    /* table: a node at kc, then the nodes above it (or, past the last node, one more node on
     * the tail); the tail stays */
    size_t m = 0;
    while (m < psd->n && psd->k[m] <= kc)
        m++;
    size_t n = m < psd->n ? psd->n - m + 1 : 2;
    double *k = malloc(n * sizeof *k), *P = malloc(n * sizeof *P);
    if (!k || !P) {
        free(k);
        free(P);
        return LJGAP_ENOMEM;
    }
    k[0] = kc;
    P[0] = ljgap_psd_eval(psd, kc);
    if (m < psd->n) {
        memcpy(k + 1, psd->k + m, (n - 1) * sizeof *k);
        memcpy(P + 1, psd->P + m, (n - 1) * sizeof *P);
    } else {
        k[1] = 2.0 * kc;
        P[1] = ljgap_psd_eval(psd, k[1]);
    }
    int st = ljgap_psd_table(out, k, P, n, psd->has_tail, psd->tail_q);
    free(k);
    free(P);
    return st;
}

/* Index of the segment holding k (k1 <= k < k2): the last i with k[i] <= k. */
static size_t table_seg(const ljgap_psd *p, double k)
{
    size_t lo = 0, hi = p->n - 1;
    if (k >= p->k[hi]) return hi;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (p->k[mid] <= k)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

double ljgap_psd_eval(const ljgap_psd *p, double k)
{
    if (!(k >= p->k1) || k > p->k2) return 0.0;
    if (p->kind == LJGAP_PSD_POWER) return p->C * pow(k, 2.0 * p->D - 8.0);
    size_t i = table_seg(p, k);
    if (i == p->n - 1 && !p->has_tail) return p->P[i];
    return p->P[i] * pow(k / p->k[i], p->q[i]);
}

double ljgap_psd_cumvar(const ljgap_psd *p, double k)
{
    if (!(k > p->k1)) return 0.0;
    if (k >= p->k2) return p->m0;
    if (p->kind == LJGAP_PSD_POWER) {
        double q = 2.0 * p->D - 8.0;
        return seg_var(p->C * pow(p->k1, q), p->k1, q, p->k1, k);
    }
    size_t i = table_seg(p, k);
    return p->cum[i] + seg_var(p->P[i], p->k[i], p->q[i], p->k[i], k);
}

double ljgap_psd_var(const ljgap_psd *p, double ka, double kb)
{
    if (ka < p->k1) ka = p->k1;
    if (kb > p->k2) kb = p->k2;
    if (!(kb > ka)) return 0.0;
    if (p->kind == LJGAP_PSD_POWER) {
        double q = 2.0 * p->D - 8.0;
        return seg_var(p->C * pow(p->k1, q), p->k1, q, ka, kb);
    }
    size_t i = table_seg(p, ka), j = table_seg(p, kb);
    if (i == j) return seg_var(p->P[i], p->k[i], p->q[i], ka, kb);
    return ljgap_psd_cumvar(p, kb) - ljgap_psd_cumvar(p, ka);
}

double ljgap_psd_k_of_cumvar(const ljgap_psd *p, double tau)
{
    if (!(tau > 0)) return p->k1;
    if (tau >= p->m0) return p->k2;
    if (p->kind == LJGAP_PSD_POWER) {
        double q = 2.0 * p->D - 8.0;
        double k = seg_inv(p->C * pow(p->k1, q), p->k1, q, p->k1, tau);
        return k < p->k2 ? k : p->k2;
    }
    size_t lo = 0, hi = p->n - 1;
    if (tau >= p->cum[hi])
        lo = hi;
    else
        while (hi - lo > 1) {
            size_t mid = (lo + hi) / 2;
            if (p->cum[mid] <= tau)
                lo = mid;
            else
                hi = mid;
        }
    double k = seg_inv(p->P[lo], p->k[lo], p->q[lo], p->k[lo], tau - p->cum[lo]);
    if (lo + 1 < p->n && k > p->k[lo + 1]) k = p->k[lo + 1];
    return k;
}

/* 8-point Gauss-Legendre on [-1,1] */
static const double gl_x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                               0.9602898564975363};
static const double gl_w[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                               0.1012285362903763};

/* ∫ 2π s P(s) f(g0,s)^2 ds over [ka,kb] inside one smooth piece of P, integrated in
 * w = ln(s - k0), where the pole of f near k0 becomes a smooth function. */
static double packet_piece(const ljgap_psd *p, double g0, double ka, double kb)
{
    const double k0 = ljgap_k0();
    double wa = log(ka - k0), wb = log(kb - k0);
    int panels = (int)ceil((wb - wa) / 0.25);
    if (panels < 1) panels = 1;
    double hw = (wb - wa) / panels, sum = 0;
    for (int j = 0; j < panels; j++) {
        double c = wa + (j + 0.5) * hw;
        for (int i = 0; i < 8; i++) {
            double w = c + (i < 4 ? -gl_x[i] : gl_x[i - 4]) * 0.5 * hw;
            double s = k0 + exp(w);
            double f = ljgap_f(g0, s);
            sum +=
                gl_w[i & 3] * 0.5 * hw * 2.0 * M_PI * s * ljgap_psd_eval(p, s) * f * f * (s - k0);
        }
    }
    return sum;
}

double ljgap_packet_var(const ljgap_psd *p, double g0, double ka, double kb)
{
    if (ka < p->k1) ka = p->k1;
    if (kb > p->k2) kb = p->k2;
    if (!(kb > ka) || isinf(kb)) return isinf(kb) ? NAN : 0.0;
    if (p->kind == LJGAP_PSD_POWER) return packet_piece(p, g0, ka, kb);
    double sum = 0, a = ka;
    for (size_t i = table_seg(p, ka) + 1; i < p->n && p->k[i] < kb; i++) {
        sum += packet_piece(p, g0, a, p->k[i]);
        a = p->k[i];
    }
    return sum + packet_piece(p, g0, a, kb);
}
