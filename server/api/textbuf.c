/* textbuf.c -- a growing text buffer (textbuf.h): doubling, one failure flag. */
#include "textbuf.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Makes room for n more bytes and the NUL; 0 on failure (then b->oom is set). */
static int reserve(ljgap_textbuf *b, size_t n)
{
    size_t cap = b->cap ? b->cap : 256;
    char *s;
    if (b->oom) return 0;
    if (b->len + n + 1 <= b->cap) return 1;
    while (cap < b->len + n + 1)
        cap *= 2;
    if (!(s = realloc(b->s, cap))) {
        free(b->s);
        b->s = NULL;
        b->len = b->cap = 0;
        b->oom = 1;
        return 0;
    }
    b->s = s;
    b->cap = cap;
    return 1;
}

void ljgap_textbuf_put(ljgap_textbuf *b, const char *s, size_t n)
{
    if (!reserve(b, n)) return;
    memcpy(b->s + b->len, s, n);
    b->len += n;
    b->s[b->len] = '\0';
}

void ljgap_textbuf_printf(ljgap_textbuf *b, const char *fmt, ...)
{
    va_list ap;
    int n;
    va_start(ap, fmt);
    n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0 || !reserve(b, (size_t)n)) return;
    va_start(ap, fmt);
    vsnprintf(b->s + b->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->len += (size_t)n;
}
