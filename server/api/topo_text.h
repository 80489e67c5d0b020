/* topo_text.h -- the plain-text form of POST /v1/psd (topo_text.c): a height matrix as text and
 * its query parameters, read into what request.c validates.
 */
#ifndef LJGAP_TOPO_TEXT_H
#define LJGAP_TOPO_TEXT_H

#include "request.h"

/* Parses a matrix of heights (m): one row a line, values separated by white space or one comma,
 * '#' to the end of a line a comment, blank lines skipped, CR LF accepted. Every bad value is a
 * problem at /topography/heights/ROW/COL whose detail names the line and column (1-based), a
 * row of the wrong length one at /topography/heights/ROW. Stops after max_points values or
 * LJGAP_MAX_ERRORS problems. t->h, t->nx, t->ny receive the matrix (t->h may be NULL). */
void ljgap__topo_text_parse(const char *body, size_t len, size_t max_points, ljgap__topo_spec *t,
                           ljgap__verr *e);
/* The query parameters as a request root {"topography": {...}, "material": {...}}: dx, dy
 * (numbers), periodic (true/false/1/0, or no value: true) and the material's fields (numbers);
 * a value that is none of these goes in as a string (request.c refuses it at the field's
 * pointer). An unknown or repeated parameter is a problem at its pointer (/topography/dx,
 * /material/E_star; /NAME for an unknown one). NULL when out of memory. */
cJSON *ljgap__topo_params_json(const ljgap__param *p, size_t np, ljgap__verr *e);

#endif
