/* dump_b.c -- prints what one of the readers of server/files/{x3p,sur,metropro,netcdf}.c makes
 * of a file, as one JSON object (grid, size in m, unit, metadata, the heights row by row in m,
 * null where missing), for the cross-checks of tests/files/check_b.sh. Built by that script
 * straight from the readers' sources (no registry needed).
 *
 *   dump_b FORMAT FILE [CHANNEL]     FORMAT: x3p, sur, metropro or netcdf
 * Exit status 0, or the reader's code (1-5) with the error on stderr.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "files.h"

static void jstr(const char *s)
{
    putchar('"');
    for (; *s; s++) {
        if (*s == '"' || *s == '\\')
            printf("\\%c", *s);
        else if ((unsigned char)*s < 0x20)
            printf("\\u%04x", *s);
        else
            putchar(*s);
    }
    putchar('"');
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: dump_b FORMAT FILE [CHANNEL]\n");
        return 64;
    }
    const ljgap__files_format *fmts[] = {&ljgap__files_x3p, &ljgap__files_sur, &ljgap__files_metropro,
                                        &ljgap__files_netcdf};
    const ljgap__files_format *f = NULL;
    for (size_t i = 0; i < 4; i++)
        if (!strcmp(fmts[i]->name, argv[1])) f = fmts[i];
    FILE *in = fopen(argv[2], "rb");
    if (!f || !in) {
        fprintf(stderr, "dump_b: unknown format or unreadable file\n");
        return 64;
    }
    size_t cap = 1 << 16, len = 0, got;
    unsigned char *buf = malloc(cap);
    while (buf && (got = fread(buf + len, 1, cap - len, in)) > 0)
        if ((len += got) == cap) buf = realloc(buf, cap *= 2);
    fclose(in);
    if (!buf) return 4;
    ljgap__files_map map;
    ljgap__files_err err;
    memset(&err, 0, sizeof err);
    int probe = f->probe(buf, len);
    int rc = f->read(buf, len, argc > 3 ? argv[3] : NULL, &map, &err);
    free(buf);
    if (rc) {
        fprintf(stderr, "dump_b: %d %s at %ld [%s]: %s\n", rc, err.format ? err.format : "?",
                err.offset, err.member, err.msg);
        free(map.z);
        return rc;
    }
    printf("{\"probe\": %d, \"format\": ", probe);
    jstr(map.format);
    printf(", \"nx\": %zu, \"ny\": %zu, \"size_x\": %.17g, \"size_y\": %.17g, \"missing\": %zu, "
           "\"periodic\": %d, \"tip_radius\": %.17g, \"channel\": ",
           map.nx, map.ny, map.size_x, map.size_y, map.missing, map.periodic, map.tip_radius);
    jstr(map.channel);
    printf(", \"channel_index\": %d, \"channels\": [", map.channel_index);
    for (int c = 0; c < map.n_channels; c++) {
        if (c) printf(", ");
        jstr(map.channels[c]);
    }
    printf("], \"z_unit\": ");
    jstr(map.z_unit);
    printf(", \"instrument\": ");
    jstr(map.instrument);
    printf(", \"acquired\": ");
    jstr(map.acquired);
    printf(", \"z\": [");
    for (size_t k = 0; k < map.nx * map.ny; k++) {
        if (k) putchar(',');
        if (map.z[k] != map.z[k])
            printf("null");
        else
            printf("%.17g", map.z[k]);
    }
    printf("]}\n");
    free(map.z);
    return 0;
}
