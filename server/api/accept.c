/* accept.c -- the Accept header (accept.h): one pass over the ranges, per offered type. */
#include "accept.h"

#include <string.h>
#include <strings.h>

#define OWS " \t"

/* One media range of the header: [type, type + tlen) "/" [sub, sub + slen), weight in
 * thousandths. */
typedef struct {
    const char *type, *sub;
    size_t tlen, slen;
    int q; /* 0..1000 */
} range;

/* Parses a qvalue (RFC 9110 §12.4.2: "0" ["." up to 3 digits] or "1" ["." up to 3 zeros])
 * from [s, s + n) into thousandths; -1 when malformed. */
static int parse_q(const char *s, size_t n)
{
    int q, scale = 100;
    if (n == 0 || (s[0] != '0' && s[0] != '1')) return -1;
    q = (s[0] - '0') * 1000;
    if (n == 1) return q;
    if (s[1] != '.' || n > 5) return -1;
    for (size_t i = 2; i < n; i++, scale /= 10) {
        if (s[i] < '0' || s[i] > '9') return -1;
        q += (s[i] - '0') * scale;
    }
    return q > 1000 ? -1 : q;
}

/* A token character of RFC 9110 §5.6.2. */
static int tchar(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
           (c && strchr("!#$%&'*+-.^_`|~", c));
}

static size_t token(const char *s, size_t n)
{
    size_t i = 0;
    while (i < n && tchar(s[i]))
        i++;
    return i;
}

/* Parses one element [s, s + n) of the list; 0 when it is not a media range. */
static int parse_range(const char *s, size_t n, range *r)
{
    size_t i, t;
    while (n && s[0] && strchr(OWS, s[0]))
        s++, n--;
    t = token(s, n);
    if (t == 0 || t >= n || s[t] != '/') return 0;
    r->type = s;
    r->tlen = t;
    r->sub = s + t + 1;
    r->slen = token(r->sub, n - t - 1);
    if (r->slen == 0) return 0;
    if (r->tlen == 1 && r->type[0] == '*' && !(r->slen == 1 && r->sub[0] == '*')) return 0;
    r->q = 1000;
    i = t + 1 + r->slen;
    /* parameters: *( OWS ";" OWS [ name "=" value ] ); only q is read */
    while (i < n) {
        size_t name, vlen;
        const char *v;
        while (i < n && s[i] && strchr(OWS, s[i]))
            i++;
        if (i == n) break;
        if (s[i] != ';') return 0;
        i++;
        while (i < n && s[i] && strchr(OWS, s[i]))
            i++;
        name = token(s + i, n - i);
        if (name == 0) continue; /* an empty parameter ("text/csv;") */
        if (i + name >= n || s[i + name] != '=') return 0;
        v = s + i + name + 1;
        if (v < s + n && *v == '"') { /* quoted-string value */
            const char *e = v + 1;
            while (e < s + n && *e != '"')
                e += (*e == '\\' && e + 1 < s + n) ? 2 : 1;
            if (e >= s + n) return 0;
            vlen = (size_t)(e + 1 - v);
        } else {
            vlen = token(v, (size_t)(s + n - v));
        }
        if (name == 1 && (s[i] == 'q' || s[i] == 'Q') && (r->q = parse_q(v, vlen)) < 0) return 0;
        i = (size_t)(v + vlen - s);
    }
    return 1;
}

/* Length of the list element at s: up to the next comma outside a quoted string. */
static size_t element(const char *s)
{
    size_t i = 0;
    while (s[i] && s[i] != ',') {
        if (s[i] == '"') {
            for (i++; s[i] && s[i] != '"'; i++)
                if (s[i] == '\\' && s[i + 1]) i++;
            if (!s[i]) break;
        }
        i++;
    }
    return i;
}

/* How specifically r matches type/sub: 3 exact, 2 type/ *, 1 * / *, 0 not at all. */
static int match(const range *r, const char *type, size_t tlen, const char *sub)
{
    if (r->tlen == 1 && r->type[0] == '*') return 1;
    if (r->tlen != tlen || strncasecmp(r->type, type, tlen) != 0) return 0;
    if (r->slen == 1 && r->sub[0] == '*') return 2;
    return r->slen == strlen(sub) && strncasecmp(r->sub, sub, r->slen) == 0 ? 3 : 0;
}

int ljgap__accept_pick(const char *accept, const char *const *offered, size_t n)
{
    int best = -1, best_q = 0;
    size_t best_pos = 0;
    if (!accept || accept[strspn(accept, OWS)] == '\0') return n ? 0 : -1;
    for (size_t o = 0; o < n; o++) {
        const char *slash = strchr(offered[o], '/');
        size_t tlen = slash ? (size_t)(slash - offered[o]) : 0;
        int spec = 0, q = 0;
        size_t pos = 0, idx = 0;
        if (!slash) continue;
        /* the most specific matching range gives the weight (the first of equal ones) */
        for (const char *p = accept;; idx++) {
            size_t len = element(p);
            range r;
            int m;
            if (parse_range(p, len, &r) && (m = match(&r, offered[o], tlen, slash + 1)) > spec) {
                spec = m;
                q = r.q;
                pos = idx;
            }
            if (!p[len]) break;
            p += len + 1;
        }
        if (spec == 0 || q == 0) continue;
        if (best < 0 || q > best_q || (q == best_q && pos < best_pos)) {
            best = (int)o;
            best_q = q;
            best_pos = pos;
        }
    }
    return best;
}
