/* files_dump.c -- build/tests/files/files_dump: what ljgap__files_read makes of a file, for the
 * tests (tests/files/run.sh compares it with the generators' values and with Gwyddion's).
 *
 *   files_dump FILE [FORMAT [CHANNEL]]   prints "key value" lines (format, channel, channels,
 *                                        nx, ny, size_x, size_y, z_unit, missing, instrument,
 *                                        acquired, tip_radius), then "z" and the heights in
 *                                        metres, one a line, row after row (nan: missing);
 *                                        exit 0, or 1 with "error STATUS ..." on a failure
 *   files_dump --truncate FILE           reads every prefix of the file (every byte up to
 *                                        64 KiB, else 4096 lengths spread over it) and prints
 *                                        "prefixes N ok K bad B unknown U other O"
 * FORMAT "" or "-" detects the format.
 */
#include "files.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static unsigned char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    unsigned char *b = NULL;
    size_t cap = 0, n = 0, r;
    if (!f) return NULL;
    do {
        if (n == cap) {
            unsigned char *c = realloc(b, cap = cap ? 2 * cap : 65536);
            if (!c) {
                free(b);
                fclose(f);
                return NULL;
            }
            b = c;
        }
        r = fread(b + n, 1, cap - n, f);
        n += r;
    } while (r > 0);
    fclose(f);
    *len = n;
    return b;
}

static int truncations(const unsigned char *buf, size_t len)
{
    size_t counts[6] = {0}, tried = 0;
    size_t step = len <= 65536 ? 1 : len / 4096;
    for (size_t n = 0; n < len; n += (n < 2048 ? 1 : step)) {
        /* a copy of exactly n bytes: the sanitizers see a read past it */
        unsigned char *c = malloc(n ? n : 1);
        ljgap__files_map m;
        ljgap__files_err e;
        if (!c) return 2;
        memcpy(c, buf, n);
        int st = ljgap__files_read(c, n, NULL, NULL, &m, &e);
        ljgap__files_map_free(&m);
        free(c);
        counts[st >= 0 && st <= 5 ? st : 5]++;
        tried++;
    }
    printf("prefixes %zu ok %zu bad %zu unknown %zu other %zu\n", tried, counts[0],
           counts[LJGAP_FILES_BAD], counts[LJGAP_FILES_UNKNOWN],
           counts[LJGAP_FILES_CHANNEL] + counts[LJGAP_FILES_NOMEM] + counts[LJGAP_FILES_TOOBIG]);
    return 0;
}

int main(int argc, char **argv)
{
    size_t len = 0;
    unsigned char *buf;
    ljgap__files_map m;
    ljgap__files_err e;
    if (argc >= 3 && strcmp(argv[1], "--truncate") == 0) {
        if (!(buf = slurp(argv[2], &len))) return perror(argv[2]), 2;
        int r = truncations(buf, len);
        free(buf);
        return r;
    }
    if (argc < 2) {
        fprintf(stderr, "usage: files_dump FILE [FORMAT [CHANNEL]] | --truncate FILE\n");
        return 2;
    }
    if (!(buf = slurp(argv[1], &len))) return perror(argv[1]), 2;
    const char *fmt = argc > 2 && strcmp(argv[2], "-") ? argv[2] : NULL;
    int st = ljgap__files_read(buf, len, fmt, argc > 3 ? argv[3] : NULL, &m, &e);
    free(buf);
    if (st) {
        printf("error %d format %s offset %ld member %s: %s\n", st, e.format ? e.format : "-",
               e.offset, e.member[0] ? e.member : "-", e.msg);
        ljgap__files_map_free(&m);
        return 1;
    }
    printf("format %s\nchannel %s\nchannel_index %d\nchannels", m.format, m.channel,
           m.channel_index);
    for (int i = 0; i < m.n_channels; i++)
        printf("%s%s", i ? "|" : " ", m.channels[i]);
    printf("\nnx %zu\nny %zu\nsize_x %.17g\nsize_y %.17g\nz_unit %s\nmissing %zu\n"
           "instrument %s\nacquired %s\ntip_radius %.17g\nperiodic %d\nz\n",
           m.nx, m.ny, m.size_x, m.size_y, m.z_unit, m.missing, m.instrument, m.acquired,
           m.tip_radius, m.periodic);
    for (size_t i = 0; i < m.nx * m.ny; i++)
        printf("%.17g\n", m.z[i]);
    ljgap__files_map_free(&m);
    return 0;
}
