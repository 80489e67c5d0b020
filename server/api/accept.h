/* accept.h -- content negotiation: which of the answer's media types an Accept header prefers.
 *
 * RFC 9110 §12.5.1. The header is a comma-separated list of media ranges (type/subtype,
 * type/ *, * / *), each with optional parameters, of which only q (a weight, 0 to 1, three
 * decimals at most) is read: other parameters, such as charset, do not restrict the match. For
 * each offered type the most specific range that matches it gives its weight (q = 0 refuses
 * it); the type with the largest weight wins; on a tie the client's order of the matching
 * ranges decides, then the server's order of the offered types. A missing or empty header
 * accepts everything. Malformed ranges are skipped; a header with nothing usable in it
 * accepts nothing (406).
 *
 * Pure and allocation-free: any bytes are safe to pass (it reads up to the NUL).
 */
#ifndef LJGAP_ACCEPT_H
#define LJGAP_ACCEPT_H

#include <stddef.h>

/* The index in offered[0..n) (type/subtype strings, lower case, most preferred first) of the
 * type the Accept header value prefers, or -1 when it accepts none of them. accept NULL or
 * empty: 0. */
int ljgap__accept_pick(const char *accept, const char *const *offered, size_t n);

#endif
