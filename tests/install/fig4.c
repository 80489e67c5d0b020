/* fig4.c -- a program outside the project, built against the installed library through
 * pkg-config by tests/install/run.sh (shared and static): the adhesion of the paper's Fig. 4
 * surface (D = 2.5, C = 1/(4π), k1 = 1, k2 = ∞; docs/theory.md §4). Prints the two numbers and
 * exits 0 when they match the reference values (Δγeff/Δγ = 0.20150, g_eq = 2.6028, to their
 * printed digits plus the returned error estimates).
 */
#include <ljgap.h>

#include <math.h>
#include <stdio.h>

int main(void)
{
    ljgap_psd psd;
    ljgap_opts o;
    ljgap_summary s;
    ljgap_warnings w = {0};
    int st;
    ljgap_init();
    if (ljgap_psd_power(&psd, 2.5, 1, INFINITY, LJGAP_LEVEL_C, 1 / (4 * M_PI)) != LJGAP_OK)
        return 2;
    ljgap_opts_default(&o);
    st = ljgap_traction(&psd, &o, NULL, 0, NULL, &s, &w);
    ljgap_psd_free(&psd);
    if (st != LJGAP_OK) {
        printf("ljgap_traction: %s\n", ljgap_strerror(st));
        return 1;
    }
    printf("dgamma_eff %.6f ± %.1e\ng_eq %.5f ± %.1e\n", s.dgamma_eff.value, s.dgamma_eff.err,
           s.g_eq.value, s.g_eq.err);
    return fabs(s.dgamma_eff.value - 0.20150) <= 0.5e-5 + s.dgamma_eff.err &&
                   fabs(s.g_eq.value - 2.6028) <= 0.5e-4 + s.g_eq.err
               ? 0
               : 1;
}
