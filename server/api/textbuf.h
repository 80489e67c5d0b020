/* textbuf.h -- a growing, NUL-terminated text buffer for answers built piece by piece (the CSV
 * writer, the problem pages).
 *
 *   ljgap__textbuf b = {0};
 *   ljgap__textbuf_printf(&b, "%s,%d\n", name, n);   ... as often as needed
 *   if (b.oom) ... else use b.s (b.len bytes), then free(b.s)
 *
 * After an allocation fails, b.oom is set, further appends do nothing, and b.s is freed.
 */
#ifndef LJGAP_TEXTBUF_H
#define LJGAP_TEXTBUF_H

#include <stddef.h>

typedef struct {
    char *s;    /* the text (malloc'd, NUL-terminated), NULL until the first append */
    size_t len; /* bytes in s, without the NUL */
    size_t cap; /* bytes allocated */
    int oom;    /* an allocation failed: s is NULL and stays so */
} ljgap__textbuf;

void ljgap__textbuf_printf(ljgap__textbuf *b, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
/* Appends n bytes of s. */
void ljgap__textbuf_put(ljgap__textbuf *b, const char *s, size_t n);

/* Length of the longest prefix of s[0..n) made of whole, well-formed UTF-8 characters (no
 * overlong forms, surrogates or code points past U+10FFFF): n when all of it is. */
size_t ljgap__utf8_span(const char *s, size_t n);

#endif
