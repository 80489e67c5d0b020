/* forwarded.c -- the client an X-Forwarded-For header names (forwarded.h). */
#include "forwarded.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <string.h>

#define TOKEN_MAX 64 /* longer than any numeric address (an IPv6 one is at most 45) */

int ljgapd_forwarded_client(const char *xff, char *out, size_t n)
{
    const char *last = strrchr(xff, ',');
    char tok[TOKEN_MAX];
    unsigned char buf[sizeof(struct in6_addr)];
    size_t len;

    if (n) out[0] = '\0';
    last = last ? last + 1 : xff;
    last += strspn(last, " \t");
    len = strcspn(last, " \t");
    if (len == 0 || len >= sizeof tok || len >= n || last[len + strspn(last + len, " \t")])
        return 0;
    memcpy(tok, last, len);
    tok[len] = '\0';
    if (inet_pton(AF_INET, tok, buf) != 1 && inet_pton(AF_INET6, tok, buf) != 1) return 0;
    memcpy(out, tok, len + 1);
    return 1;
}
