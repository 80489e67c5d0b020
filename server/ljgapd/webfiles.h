/* webfiles.h -- the page's files: which names may be served, with which type, and the table
 * of files compiled into the daemon.
 *
 * The build turns web/ into a C table (tools/embed.c writes $(BUILD)/gen/web.c, the array
 * ljgapd_web_files), so an installed ljgapd serves its page with nothing beside it; with
 * --web DIR it reads the same names from DIR instead (for working on the page). Either way
 * only allowlisted names are served: index.html, and NAME.{js,css,png,svg,ico,json} at the top
 * or in vendor/, NAME being letters, digits, '.', '_' and '-' and not starting with '.'. So
 * nothing can climb out of the directory.
 */
#ifndef LJGAP_WEBFILES_H
#define LJGAP_WEBFILES_H

#include <stddef.h>

typedef struct {
    const char *name;          /* path below the page's root: "index.html", "vendor/x.js" */
    const char *type;          /* its Content-Type */
    const unsigned char *data; /* its bytes */
    size_t len;                /* how many */
    const char *etag;          /* a strong validator of the bytes, quoted: "\"0123abcd...\"" */
} ljgapd_web_file;

/* The table compiled into ljgapd: $(BUILD)/gen/web.c, written by tools/embed.c (only the
 * daemon links it). */
extern const ljgapd_web_file ljgapd_web_files[];
extern const size_t ljgapd_web_nfiles;

/* The Content-Type of rel (a name below the page's root), or NULL when it is not allowlisted. */
const char *ljgapd_web_type(const char *rel);

/* The name a request path asks for: path without its leading '/', index.html for "/";
 * NULL when path does not start with '/'. Points into path or at a constant. */
const char *ljgapd_web_name(const char *path);

/* The file of table (n entries) that the request path names, or NULL. */
const ljgapd_web_file *ljgapd_web_find(const ljgapd_web_file *table, size_t n, const char *path);

/* Does an If-None-Match header value (NULL when absent) match etag ("*", or the tag in a
 * comma-separated list, weak W/ tags compared weakly as RFC 9110 §13.1.2 asks)? */
int ljgapd_web_etag_match(const char *if_none_match, const char *etag);

#endif
