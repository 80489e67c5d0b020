/* march.c -- the steps in wavenumber of the PDE solver (pde.c: "Wavenumber", "Infinite k2").
 *
 * Steps are uniform in zeta(k) = ln(k - k0) + ZETA_BETA tau(k)/m0 from zeta(k1), tau the
 * cumulative variance: ln(k - k0) puts steps where f(g,k) changes fast (k1 near k0, the
 * near-wall switch-on at large k) and tau where the variance is. Each step carries the
 * coefficient s = dzeta * pi k P(k) dk/dzeta at both ends (the operator is s f^2 D2). Level
 * L halves every step of level L-1, so its nodes contain level L-1's; a request finds each
 * node once (zeta_nodes). For an infinite k2 the zeta march ends at kmax and the remaining
 * variance follows in steps uniform in tau.
 */
#include "ljgap.h"
#include "march.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define ZETA_BETA 10.0  /* weight of the variance in the marching variable zeta */
#define DZETA0_FWD 0.25 /* zeta step at level 0: forward solves (gap PDFs) */
#define DZETA0_BWD 0.5  /* zeta step at level 0: backward solves (traction curves) */
#define MAX_STEPS 4e6   /* steps of one march, at most */
#define TAIL_STEPS0 8   /* tau steps of the infinite tail at level 0 (per unit m0 share) */

typedef struct {
    const ljgap_psd *psd;
    double k0, m0;
} zeta_ctx;

static double zeta_of(const zeta_ctx *z, double k)
{
    return log(k - z->k0) + ZETA_BETA * ljgap_psd_cumvar(z->psd, k) / z->m0;
}

/* dk/dzeta at k */
static double dk_dzeta(const zeta_ctx *z, double k)
{
    double d = 1.0 / (k - z->k0) + ZETA_BETA * 2.0 * M_PI * k * ljgap_psd_eval(z->psd, k) / z->m0;
    return 1.0 / d;
}

/* The step coefficient per unit zeta at k: π k P(k) dk/dzeta (a = that times f^2). */
static double rate_of(const zeta_ctx *z, double k)
{
    return M_PI * k * ljgap_psd_eval(z->psd, k) * dk_dzeta(z, k);
}

/* The k in [ka,kb] with zeta(k) = target: safeguarded Newton in x = ln(k - k0), started at
 * x0 when that lies inside, else at ka (the march asks for the next node just above the
 * previous one, and zeta is concave in x for the usual spectra, so Newton from the left end
 * converges in a few steps). */
static double zeta_inv(const zeta_ctx *z, double target, double ka, double kb, double x0)
{
    double xa = log(ka - z->k0), xb = log(kb - z->k0);
    double x = x0 > xa && x0 < xb ? x0 : xa;
    for (int it = 0; it < 100; it++) {
        double k = z->k0 + exp(x);
        double r = zeta_of(z, k) - target;
        if (r == 0) return k; /* (else the bracket test below would bisect away from it) */
        if (r > 0)
            xb = x;
        else
            xa = x;
        double dkz = dk_dzeta(z, k);
        double dzdx = dkz > 0 ? (k - z->k0) / dkz : 1.0;
        double xn = x - r / dzdx;
        if (!(xn > xa && xn < xb)) xn = 0.5 * (xa + xb);
        if (fabs(xn - x) < 1e-14 * (1.0 + fabs(x)) || xb - xa < 1e-14 * (1.0 + fabs(x)))
            return z->k0 + exp(xn);
        x = xn;
    }
    return z->k0 + exp(x);
}

void ljgap__nodes_free(zeta_nodes *Z)
{
    free(Z->k);
    memset(Z, 0, sizeof *Z);
}

/* Make entry j exist for spacing dz = Z->dz 2^p, p >= 0, or refine the table to spacing dz.
 * Returns the entry's index, or -1 when out of memory (then the caller finds the node itself). */
static long nodes_slot(zeta_nodes *Z, double dz, size_t j)
{
    /* a spacing that is not the table's times or over a power of two (not a level of the
     * same march) starts a new table */
    if (!Z->n || (dz != Z->dz &&
                  !(fabs(dz / Z->dz - exp2(round(log2(dz / Z->dz)))) <= 1e-9 * (dz / Z->dz)))) {
        ljgap__nodes_free(Z);
        Z->dz = dz;
    }
    while (dz < Z->dz * 0.75) { /* refine: the old entries become the even ones */
        size_t n = 2 * Z->n;
        double *b = malloc(2 * (n ? n : 1) * sizeof *b);
        if (!b) return -1;
        for (size_t i = 0; i < n; i++)
            b[i] = b[n + i] = NAN;
        for (size_t i = 0; i < Z->n; i++)
            b[2 * i] = Z->k[i], b[n + 2 * i] = Z->r[i];
        free(Z->k);
        Z->k = b, Z->r = b + n, Z->n = n, Z->dz *= 0.5;
    }
    size_t p = (size_t)lround(dz / Z->dz), i = j * p;
    if (i >= Z->n) { /* grow */
        size_t n = 2 * i + 16;
        double *b = malloc(2 * n * sizeof *b);
        if (!b) return -1;
        for (size_t q = 0; q < n; q++) {
            b[q] = q < Z->n ? Z->k[q] : NAN;
            b[n + q] = q < Z->n ? Z->r[q] : NAN;
        }
        free(Z->k);
        Z->k = b, Z->r = b + n, Z->n = n;
    }
    return (long)i;
}

/* Regular node j of spacing dz above z1 = zeta(k1), with its rate; kprev is node j-1 (the
 * march asks in order) and kc the end of the segment that holds the node. Z may be NULL. */
static double nodes_get(zeta_nodes *Z, const zeta_ctx *z, double z1, double dz, size_t j,
                        double kprev, double kc, double *rate)
{
    long i = Z ? nodes_slot(Z, dz, j) : -1;
    if (i >= 0 && !isnan(Z->k[i])) {
        *rate = Z->r[i];
        return Z->k[i];
    }
    double x0 = -INFINITY;                                       /* (from kprev) */
    if (i >= 0 && (size_t)i + 1 < Z->n && !isnan(Z->k[i + 1])) { /* bracketed */
        double kn = Z->k[i + 1];
        kc = fmin(kc, kn);
        x0 = 0.5 * (log(kprev - z->k0) + log(kn - z->k0));
    }
    double k = zeta_inv(z, z1 + (double)j * dz, kprev, kc, x0);
    *rate = rate_of(z, k);
    if (i >= 0) Z->k[i] = k, Z->r[i] = *rate;
    return k;
}

void ljgap__march_free(pde_march *M)
{
    free(M->s);
    M->s = NULL;
    M->m = 0;
}

/* Build the steps of level L from k1 through the sorted cut points cuts[0..nc-1] (the
 * last one is the end of the march; INFINITY means the whole PSD). A snapshot index is
 * recorded at each cut. For the infinite tail, kmax is where f(g_k, kmax) = 1/1.001 (g_k is
 * the grid's lower end, or a lower one).
 * Forward (gap PDFs): steps DZETA0_FWD / 2^L, the first two as four backward-Euler halves
 * that damp the delta start. Backward (traction): steps DZETA0_BWD / 2^L, all
 * Crank-Nicolson. The backward solve starts from the smooth sigma(g) at the far end and
 * needs no damping; backward-Euler steps at k1 would add an h^3 term to its error expansion
 * (measured: it made the Richardson values converge at order 3 instead of 3.5-4), and the
 * longer steps are what its error balance allows (its error is mostly from the gap grid). */
int ljgap__march_make(pde_march *M, const ljgap_psd *psd, const double *cuts, size_t nc, int L,
                      double g_k, int backward, zeta_nodes *Z)
{
    memset(M, 0, sizeof *M);
    zeta_ctx z = {psd, ljgap_k0(), psd->m0};
    double kend = cuts[nc - 1];
    int inf = isinf(kend);
    double kmax = kend;
    if (inf) {
        double kw = 1e3 * 9.0 * pow(g_k, -10.0);
        kmax = fmax(100.0 * psd->k1, kw);
        for (size_t c = 0; c + 1 < nc; c++)
            kmax = fmax(kmax, 10.0 * cuts[c]);
        if (isfinite(psd->k2)) kmax = psd->k2, inf = 0;
    }
    M->kmax = kmax;
    M->tau_rem = inf ? psd->m0 - ljgap_psd_cumvar(psd, kmax) : 0.0;
    double scale = ldexp(1.0, L);
    double dz = (backward ? DZETA0_BWD : DZETA0_FWD) / scale;
    /* Steps are uniform in zeta from zeta(k1), whatever the cuts: a cut ends a step early
     * (a remainder under 0.3 dz is merged into the step before). So the nodes do not move
     * when kmax moves (it follows g_k), and level L+1 holds every node of level L. */
    double z1 = zeta_of(&z, psd->k1);
    double zend = zeta_of(&z, kmax);
    if (!isfinite(z1) || !isfinite(zend) || !(zend > z1)) return LJGAP_EFAIL;
    /* A backward march to a finite k2 has one cut, its start: the steps end on it exactly at
     * every level. A remainder step there (its length a different fraction of dz at each
     * level) left an error that no extrapolation removes: for k2 = 8 the Richardson values
     * of g_eq were off by 8e-6 and 7e-6 at levels 1 and 2. */
    if (backward && !inf) dz = (zend - z1) / fmax(1.0, ceil((zend - z1) / DZETA0_BWD)) / scale;
    /* regular steps, a Rannacher split and a possible extra step per cut, the tail */
    double need = (zend - z1) / dz + 4.0 + 2.0 * (double)nc;
    size_t mtail = 0;
    if (inf && M->tau_rem > 1e-15 * psd->m0) {
        mtail = (size_t)((2 + ceil(TAIL_STEPS0 * 4.0 * M->tau_rem / psd->m0)) * scale);
        need += (double)mtail;
    }
    if (!(need < MAX_STEPS)) return LJGAP_ECAP;
    size_t cap = (size_t)need + 4;
    M->s = malloc(cap * sizeof *M->s);
    if (!M->s) return LJGAP_ENOMEM;
    size_t m = 0;
    double kprev = psd->k1, zprev = z1, rprev = rate_of(&z, psd->k1);
    long jn = 0;  /* regular nodes zeta(k1) + j dz passed so far */
    int nreg = 0; /* steps made */
    for (size_t c = 0; c < nc; c++) {
        double kc = isinf(cuts[c]) ? kmax : fmin(cuts[c], kmax);
        double zc = zeta_of(&z, kc);
        while (zprev < zc && m + 2 < cap) {
            double zn = z1 + (double)(jn + 1) * dz;
            double kb, rb;
            if (zn >= zc - 0.3 * dz) {
                zn = zc, kb = kc;
                rb = rate_of(&z, kb);
            } else {
                kb = nodes_get(Z, &z, z1, dz, (size_t)(jn + 1), kprev, kc, &rb);
            }
            while (z1 + (double)(jn + 1) * dz <= zn + 1e-12 * dz)
                jn++;
            double h = zn - zprev;
            if (!backward && nreg++ < 2) {
                /* Rannacher start: each of the first two steps as two backward-Euler halves */
                double km = zeta_inv(&z, zprev + 0.5 * h, kprev, kb, -INFINITY);
                double sm = 0.5 * h * rate_of(&z, km);
                M->s[m++] = (pde_step){kprev, km, 0.5 * h * rprev, sm, 1.0, -1};
                M->s[m++] = (pde_step){km, kb, sm, 0.5 * h * rb, 1.0, -1};
            } else {
                M->s[m++] = (pde_step){kprev, kb, h * rprev, h * rb, 0.5, -1};
            }
            rprev = rb;
            kprev = kb;
            zprev = zn;
            if (zn >= zc) break;
        }
        if (m > 0 && !isinf(cuts[c])) M->s[m - 1].snap = (int)c;
    }
    if (mtail && m + mtail <= cap) {
        double t0 = ljgap_psd_cumvar(psd, kmax), dt = M->tau_rem / (double)mtail;
        for (size_t j = 0; j < mtail; j++) {
            double ka = M->s[m - 1].kb;
            double kb =
                j + 1 == mtail ? INFINITY : ljgap_psd_k_of_cumvar(psd, t0 + (double)(j + 1) * dt);
            M->s[m++] = (pde_step){ka, kb, 0.5 * dt, 0.5 * dt, 0.5, -1};
        }
    }
    /* the final snapshot (the whole PSD, or the last cut) */
    if (isinf(cuts[nc - 1])) M->s[m - 1].snap = (int)(nc - 1);
    M->m = m;
    return LJGAP_OK;
}
