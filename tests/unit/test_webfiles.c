/* test_webfiles.c -- the page compiled into ljgapd (server/ljgapd/webfiles.c, tools/embed.c).
 *
 * Linked with the daemon's table ($(BUILD)/gen/web.o): every file the page loads (each local
 * src= and href= of its index.html) is in it, and so are the icons; every entry holds exactly
 * the bytes of its file in web/ with the allowlist's type and a distinct ETag; every file of web/
 * the page could serve is in it; the lookup refuses what the allowlist refuses (no climbing
 * out of the directory); If-None-Match matching. Run from the repository root (tests/run.sh).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "webfiles.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const ljgapd_web_file *find_name(const char *name)
{
    for (size_t i = 0; i < ljgapd_web_nfiles; i++)
        if (strcmp(ljgapd_web_files[i].name, name) == 0) return &ljgapd_web_files[i];
    return NULL;
}

static void test_page_has_what_it_loads(void **state)
{
    const ljgapd_web_file *index = find_name("index.html");
    char *html;
    int refs = 0;
    (void)state;
    assert_non_null(index);
    html = strndup((const char *)index->data, index->len);
    for (const char *p = html; (p = strpbrk(p, "sh"));) {
        const char *q;
        char ref[200];
        size_t n;
        if (strncmp(p, "src=\"", 5) == 0)
            q = p + 5;
        else if (strncmp(p, "href=\"", 6) == 0)
            q = p + 6;
        else {
            p++;
            continue;
        }
        n = strcspn(q, "\"");
        p = q + n;
        if (n == 0 || n >= sizeof ref || q[0] == '#' || strncmp(q, "/openapi.json", 13) == 0)
            continue;
        memcpy(ref, q, n);
        ref[n] = '\0';
        if (strstr(ref, "://") || strncmp(ref, "mailto:", 7) == 0)
            fail_msg("index.html loads %s from elsewhere", ref);
        if (!find_name(ref[0] == '/' ? ref + 1 : ref))
            fail_msg("index.html loads %s, which is not compiled in", ref);
        refs++;
    }
    assert_true(refs >= 7); /* uPlot's two files, three scripts, the style sheet, the icon */
    assert_non_null(strstr(html, "rel=\"icon\""));
    assert_non_null(find_name("favicon.svg"));
    assert_non_null(find_name("favicon.ico"));
    free(html);
}

static void test_entries_are_the_files(void **state)
{
    (void)state;
    assert_true(ljgapd_web_nfiles > 0);
    for (size_t i = 0; i < ljgapd_web_nfiles; i++) {
        const ljgapd_web_file *f = &ljgapd_web_files[i];
        char path[300];
        FILE *in;
        unsigned char *buf = malloc(f->len + 1);
        size_t got;
        snprintf(path, sizeof path, "web/%s", f->name);
        in = fopen(path, "rb");
        if (!in) fail_msg("%s is compiled in but not in web/", f->name);
        got = fread(buf, 1, f->len + 1, in);
        fclose(in);
        if (got != f->len || memcmp(buf, f->data, f->len) != 0)
            fail_msg("%s: the compiled-in bytes differ from web/%s", f->name, f->name);
        free(buf);
        assert_string_equal(f->type, ljgapd_web_type(f->name));
        assert_int_equal(strlen(f->etag), 18);
        assert_true(f->etag[0] == '"' && f->etag[17] == '"');
        assert_int_equal(strspn(f->etag + 1, "0123456789abcdef"), 16);
        for (size_t k = 0; k < i; k++)
            assert_string_not_equal(f->etag, ljgapd_web_files[k].etag);
    }
}

/* Every file of web/ (and web/vendor/) the allowlist would serve is compiled in, but for the
 * npm files (package.json and its lock are not part of the page). */
static void test_no_file_left_out(void **state)
{
    static const char *const dirs[] = {"web", "web/vendor"};
    (void)state;
    for (size_t d = 0; d < 2; d++) {
        DIR *dir = opendir(dirs[d]);
        struct dirent *e;
        assert_non_null(dir);
        while ((e = readdir(dir))) {
            char rel[300];
            snprintf(rel, sizeof rel, "%s%s", d ? "vendor/" : "", e->d_name);
            if (!ljgapd_web_type(rel) || strncmp(e->d_name, "package", 7) == 0) continue;
            if (!find_name(rel)) fail_msg("web/%s could be served but is not compiled in", rel);
        }
        closedir(dir);
    }
}

static void test_lookup(void **state)
{
    static const char *const refused[] = {
        "",
        "index.html",
        "/..",
        "/../web/app.js",
        "/vendor/../app.js",
        "/.x.js",
        "/secret.txt",
        "/vendor/a/b.js",
        "/app.js/",
        "/APP.JS",
        "//app.js",
        "/vendor/",
        "/package.json",
    };
    (void)state;
    assert_string_equal(ljgapd_web_find(ljgapd_web_files, ljgapd_web_nfiles, "/")->name,
                        "index.html");
    assert_string_equal(ljgapd_web_find(ljgapd_web_files, ljgapd_web_nfiles, "/index.html")->name,
                        "index.html");
    assert_string_equal(
        ljgapd_web_find(ljgapd_web_files, ljgapd_web_nfiles, "/vendor/uPlot.min.css")->type,
        "text/css; charset=utf-8");
    assert_string_equal(ljgapd_web_find(ljgapd_web_files, ljgapd_web_nfiles, "/favicon.ico")->type,
                        "image/x-icon");
    for (size_t i = 0; i < sizeof refused / sizeof refused[0]; i++)
        if (ljgapd_web_find(ljgapd_web_files, ljgapd_web_nfiles, refused[i]))
            fail_msg("\"%s\" was served", refused[i]);
    assert_null(ljgapd_web_type("vendor/../app.js"));
    assert_null(ljgapd_web_type("index.htm"));
}

static void test_etag_match(void **state)
{
    const char *tag = "\"0123456789abcdef\"";
    (void)state;
    assert_false(ljgapd_web_etag_match(NULL, tag));
    assert_true(ljgapd_web_etag_match("\"0123456789abcdef\"", tag));
    assert_true(ljgapd_web_etag_match("*", tag));
    assert_true(ljgapd_web_etag_match("\"x\", W/\"0123456789abcdef\" ", tag));
    assert_true(ljgapd_web_etag_match(" \"a\",\"0123456789abcdef\"", tag));
    assert_false(ljgapd_web_etag_match("\"0123456789abcdee\"", tag));
    assert_false(ljgapd_web_etag_match("0123456789abcdef", tag));
    assert_false(ljgapd_web_etag_match("", tag));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_page_has_what_it_loads),
        cmocka_unit_test(test_entries_are_the_files),
        cmocka_unit_test(test_no_file_left_out),
        cmocka_unit_test(test_lookup),
        cmocka_unit_test(test_etag_match),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
