/* webfiles.c -- the page's allowlist, the lookup in the compiled-in table, ETag matching. */
#include "webfiles.h"

#include <string.h>

#define NAME_MAX_LEN 128 /* longest file name served */

const char *ljgapd_web_type(const char *rel)
{
    static const struct {
        const char *ext;
        const char *type;
    } types[] = {
        {".js", "text/javascript; charset=utf-8"},
        {".css", "text/css; charset=utf-8"},
        {".png", "image/png"},
        {".svg", "image/svg+xml"},
        {".ico", "image/x-icon"},
        {".json", "application/json"},
    };
    const char *name = rel;
    size_t n;

    if (!rel) return NULL;
    if (strcmp(rel, "index.html") == 0) return "text/html; charset=utf-8";
    if (strncmp(name, "vendor/", 7) == 0) name += 7;
    n = strlen(name);
    if (n == 0 || n > NAME_MAX_LEN || name[0] == '.') return NULL;
    if (strspn(name, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-") != n)
        return NULL;
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++) {
        size_t e = strlen(types[i].ext);
        if (n > e && strcmp(name + n - e, types[i].ext) == 0) return types[i].type;
    }
    return NULL;
}

const char *ljgapd_web_name(const char *path)
{
    if (!path || path[0] != '/') return NULL;
    return path[1] ? path + 1 : "index.html";
}

const ljgapd_web_file *ljgapd_web_find(const ljgapd_web_file *table, size_t n, const char *path)
{
    const char *name = ljgapd_web_name(path);
    if (!name || !ljgapd_web_type(name)) return NULL;
    for (size_t i = 0; i < n; i++)
        if (strcmp(table[i].name, name) == 0) return &table[i];
    return NULL;
}

int ljgapd_web_etag_match(const char *inm, const char *etag)
{
    size_t el = strlen(etag);
    if (!inm) return 0;
    for (const char *p = inm; *p;) {
        size_t n;
        p += strspn(p, " \t,");
        if (*p == '*') return 1;
        if (strncmp(p, "W/", 2) == 0) p += 2; /* weak comparison: the opaque tags alone */
        n = strcspn(p, ",");
        while (n && (p[n - 1] == ' ' || p[n - 1] == '\t'))
            n--;
        if (n == el && strncmp(p, etag, el) == 0) return 1;
        p += strcspn(p, ",");
    }
    return 0;
}
