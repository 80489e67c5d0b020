/* csv.h -- answers as CSV (text/csv), for spreadsheets and data frames.
 *
 * traction, pdf, sweep and the result of a simulation have a CSV form: the same numbers as
 * their JSON answer, written from it, laid out as
 *
 *   # ljgap traction: ...                               one line saying what this is
 *   # summary.g_eq [eps] = 2.60279853 ± 9.4e-07          every other field of the answer, one a
 *   # meta.method = pde                                 line: its JSON path, its unit, its value
 *   # meta.warnings[0] = ...                            and, where it has one, its error
 *   g_ave [eps],sigma [sigma0],sigma_err [sigma0]       the header: column names and units
 *   1.5,-0.01849,1.2e-08                                one row per point
 *
 * Column names are the JSON field names (an error column, NAME_err, stands beside the value it
 * belongs to); units are in brackets, in the dimensionless scales of the theory (eps: gaps,
 * 1/chi: wavenumbers, sigma0: tractions, dgamma: energies) or SI (m, Pa, J/m^2, 1/m). A null
 * in JSON is an empty cell, an infinite cut-off k2 is "inf", a boolean is true or false.
 * Numbers are printed with the fewest digits (15 to 17) that read back to the same double.
 * Lines end in LF; lines starting with # are comments (pandas: comment="#").
 */
#ifndef LJGAP_CSV_H
#define LJGAP_CSV_H

#include "reply.h"

#include <cjson/cJSON.h>

#define LJGAP_CT_CSV "text/csv; charset=utf-8; header=present"

/* Does endpoint ("traction", "pdf", "sweep", "simulations") have a CSV form? */
int ljgap__csv_offers(const char *endpoint);

/* Writes the CSV form of ans, the JSON object of a 2xx answer of endpoint, into *out (status
 * 200, LJGAP_CT_CSV). si_psd: the request gave its psd in SI units (the unit of a sweep's
 * values). Returns 0, or -1 when memory runs out or the endpoint has no CSV form (*out is
 * then empty). */
int ljgap__csv_render(const char *endpoint, const cJSON *ans, int si_psd, ljgap__reply *out);

/* Turns *r, a 2xx JSON reply of endpoint, into its CSV form in place (r is left as it was
 * when it is not a 2xx JSON reply); -1 when memory runs out (r then holds the out-of-memory
 * problem). The command line's --csv for simulations, whose answer is built as JSON. */
int ljgap__csv_reply(const char *endpoint, ljgap__reply *r);

#endif
