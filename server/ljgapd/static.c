/* static.c -- the page's files: the copy compiled into the daemon, or the directory --web DIR.
 *
 * Only allowlisted names are served (webfiles.h: index.html, and NAME.{js,css,png,svg,ico,json}
 * at the top or in vendor/). The compiled-in copy ($(BUILD)/gen/web.c) is answered from memory
 * with its ETag (304 to a matching If-None-Match); --web DIR, for working on the page, is opened
 * once at start-up and read with openat from its descriptor, so nothing can climb out of it.
 * Files are sent by libmicrohttpd on the I/O thread.
 */
#include "daemon.h"
#include "webfiles.h"

#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *static_rel(const char *rest)
{
    return rest[0] ? rest : "index.html";
}

int ljgapd_static_exists(const char *rest)
{
    return ljgapd_web_type(static_rel(rest)) != NULL;
}

enum MHD_Result ljgapd_route_static(struct MHD_Connection *c, request *r)
{
    const char *rel = static_rel(r->url + 1);
    const char *ctype = ljgapd_web_type(rel);
    const ljgapd_web_file *f;
    struct stat st;
    int fd = -1;

    if (ljgapd_srv.web_fd < 0) {
        if (!(f = ljgapd_web_find(ljgapd_web_files, ljgapd_web_nfiles, r->url)))
            return ljgapd_respond_problem(c, r, MHD_HTTP_NOT_FOUND, "no such page", NULL, NULL);
        return ljgapd_respond_static(
            c, r, f->data, f->len, f->type, f->etag,
            MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_IF_NONE_MATCH));
    }
    fd = openat(ljgapd_srv.web_fd, rel, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return ljgapd_respond_problem(c, r, MHD_HTTP_NOT_FOUND, "no such page", NULL, NULL);
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return ljgapd_respond_problem(c, r, MHD_HTTP_NOT_FOUND, "no such page", NULL, NULL);
    }
    return ljgapd_respond_file(c, r, fd, (size_t)st.st_size, ctype);
}
