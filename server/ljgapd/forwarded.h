/* forwarded.h -- the client an X-Forwarded-For header names, for a daemon behind a proxy.
 *
 * A proxy such as nginx ($proxy_add_x_forwarded_for) appends the address it saw to the header,
 * so the LAST entry is the one the trusted proxy vouches for; the entries before it are whatever
 * the client claimed. Only the last entry is taken, and only if it is a numeric IPv4 or IPv6
 * address (no port, no brackets, no names). Pure and thread-safe; the fuzz harness feeds it
 * arbitrary bytes.
 */
#ifndef LJGAP_FORWARDED_H
#define LJGAP_FORWARDED_H

#include <stddef.h>

/* Writes the last entry of the header value xff into out (size n) and returns 1 when it is an
 * IP address that fits; returns 0 (out is "") otherwise. */
int ljgapd_forwarded_client(const char *xff, char *out, size_t n);

#endif
