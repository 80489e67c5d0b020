/* input_error.h -- the measurement's uncertainty in the answers (issue 29; input_error.c).
 *
 * One call per answer builder of handler.c, after the answer's own fields: each adds
 * "input_error" beside "error" (the same keys, 1 σ), the same in si.input_error, for a table
 * PSD "extrapolated" {m0_fraction, dgamma_eff_fraction}, and says how in meta.input_error.
 * Nothing is added (and nothing computed) when the request says "input_error": false or the PSD
 * carries no uncertainty (a table without P_err and tail.exponent_err, a power law without
 * D_err and a level error). A failure here (time, a perturbed PSD with no answer) leaves the
 * answer as it is, input_error null and a warning; only an allocation failure fails the answer
 * (j->oom).
 */
#ifndef LJGAP_INPUT_ERROR_H
#define LJGAP_INPUT_ERROR_H

#include "answer.h"

/* adhesion: input_error {g_eq, sigma_max, g_at_max, dgamma_eff}, extrapolated, si */
void ljgap__ie_adhesion(job *j, const ljgap_summary *sum);
/* traction: input_error {sigma[], summary {...}}, extrapolated, si {sigma_Pa[], summary} */
void ljgap__ie_traction(job *j, const ljgap_summary *sum);
/* pdf: input_error {pdfs [{sigma}]}, si {pdfs [{sigma_Pa}]} */
void ljgap__ie_pdf(job *j);
/* contact: the adhesion's and {pull_off_N {...}, tabor {effective}, maugis_lambda} */
void ljgap__ie_contact(job *j, const ljgap_summary *sum);
/* sweep: results[i].input_error (and si.results[i]) for each value computed (st[i] == 0) */
void ljgap__ie_sweep(job *j, const ljgap_summary *sum, const int *st);

#endif
