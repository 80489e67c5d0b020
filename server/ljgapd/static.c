/* static.c -- the page's files, from the directory given by --web.
 *
 * Only allowlisted names are served: index.html, and NAME.{js,css,png,svg,json} at the top or
 * in vendor/, where NAME is letters, digits, '.', '_' and '-' not starting with '.'. So nothing
 * can climb out of the directory, which is opened once at start-up (openat from its
 * descriptor). Files are sent from their descriptor by libmicrohttpd, on the I/O thread.
 */
#include "daemon.h"

#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define FILE_NAME_MAX 128 /* longest static file name */

/* The Content-Type of an allowlisted file name (relative to the web directory), or NULL. */
static const char *static_type(const char *rel)
{
    static const struct {
        const char *ext;
        const char *type;
    } types[] = {
        {".js", "text/javascript; charset=utf-8"},
        {".css", "text/css; charset=utf-8"},
        {".png", "image/png"},
        {".svg", "image/svg+xml"},
        {".json", "application/json"},
    };
    const char *name = rel;
    size_t n;

    if (strcmp(rel, "index.html") == 0) return "text/html; charset=utf-8";
    if (strncmp(name, "vendor/", 7) == 0) name += 7;
    n = strlen(name);
    if (n == 0 || n > FILE_NAME_MAX || name[0] == '.') return NULL;
    if (strspn(name, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-") != n)
        return NULL;
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++) {
        size_t e = strlen(types[i].ext);
        if (n > e && strcmp(name + n - e, types[i].ext) == 0) return types[i].type;
    }
    return NULL;
}

static const char *static_rel(const char *rest)
{
    return rest[0] ? rest : "index.html";
}

int static_exists(const char *rest)
{
    return static_type(static_rel(rest)) != NULL;
}

enum MHD_Result route_static(struct MHD_Connection *c, request *r)
{
    const char *rel = static_rel(r->url + 1);
    const char *ctype = static_type(rel);
    struct stat st;
    int fd = -1;

    if (srv.web_fd >= 0) fd = openat(srv.web_fd, rel, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return respond_problem(c, r, MHD_HTTP_NOT_FOUND, "no such page", NULL, NULL);
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return respond_problem(c, r, MHD_HTTP_NOT_FOUND, "no such page", NULL, NULL);
    }
    return respond_file(c, r, fd, (size_t)st.st_size, ctype);
}
