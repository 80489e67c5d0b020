/* embed.c -- writes the page's files as a C table for ljgapd (webfiles.h).
 *
 *   embed OUT.c DIR NAME...   each DIR/NAME (an allowlisted name, ljgapd_web_type) becomes one
 *                             entry of const ljgapd_web_file ljgapd_web_files[], with its bytes,
 *                             its Content-Type and an ETag (FNV-1a, 64 bits, of the bytes)
 *
 * A build tool, run by the Makefile; it fails (status 1, OUT removed) on any name that is not
 * allowlisted or any file that cannot be read, so the daemon never lacks a file silently.
 */
#include "webfiles.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Writes DIR/name as "static const unsigned char fI[]"; its length and hash into *len, *h. */
static int put_bytes(FILE *out, const char *dir, const char *name, int i, size_t *len, uint64_t *h)
{
    char path[4096];
    FILE *f;
    int c;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    if (!(f = fopen(path, "rb"))) {
        fprintf(stderr, "embed: %s: %s\n", path, strerror(errno));
        return -1;
    }
    *len = 0;
    *h = 14695981039346656037ULL;
    fprintf(out, "static const unsigned char f%d[] = {", i);
    while ((c = getc(f)) != EOF) {
        fprintf(out, "%s%d,", *len % 24 ? "" : "\n    ", c);
        *h = (*h ^ (uint64_t)c) * 1099511628211ULL;
        (*len)++;
    }
    fprintf(out, "%s0};\n", *len % 24 ? "" : "\n    "); /* a NUL after the bytes (not counted) */
    if (ferror(f)) {
        fprintf(stderr, "embed: %s: read error\n", path);
        fclose(f);
        return -1;
    }
    fclose(f);
    return 0;
}

int main(int argc, char **argv)
{
    FILE *out;
    size_t *len;
    uint64_t *hash;
    int n = argc - 3, rc = 1;
    if (argc < 4) {
        fprintf(stderr, "usage: embed OUT.c DIR NAME...\n");
        return 2;
    }
    len = calloc((size_t)n, sizeof *len);
    hash = calloc((size_t)n, sizeof *hash);
    if (!len || !hash || !(out = fopen(argv[1], "w"))) {
        fprintf(stderr, "embed: cannot write %s\n", argv[1]);
        return 1;
    }
    fprintf(out,
            "/* The page's files for ljgapd, written by tools/embed.c from %s: do not edit. */\n"
            "#include \"webfiles.h\"\n\n",
            argv[2]);
    for (int i = 0; i < n; i++) {
        if (!ljgapd_web_type(argv[3 + i])) {
            fprintf(stderr, "embed: %s is not a name the page may serve (webfiles.h)\n",
                    argv[3 + i]);
            goto end;
        }
        if (put_bytes(out, argv[2], argv[3 + i], i, &len[i], &hash[i]) != 0) goto end;
    }
    fprintf(out, "\nconst ljgapd_web_file ljgapd_web_files[] = {\n");
    for (int i = 0; i < n; i++)
        fprintf(out, "    {\"%s\", \"%s\", f%d, %zu, \"\\\"%016llx\\\"\"},\n", argv[3 + i],
                ljgapd_web_type(argv[3 + i]), i, len[i], (unsigned long long)hash[i]);
    fprintf(out, "};\nconst size_t ljgapd_web_nfiles = %d;\n", n);
    rc = ferror(out) ? 1 : 0;
end:
    if (fclose(out) != 0) rc = 1;
    if (rc) remove(argv[1]);
    free(len);
    free(hash);
    return rc;
}
