/* fuzz_files.c -- libFuzzer target on the instrument-file readers (server/files/, files.h) and
 * on POST /v1/psd with a file (ljgap__handle_file).
 *
 * An input is two bytes and a file: the first byte picks the format (0: recognised by content,
 * k: the registry's k-th, forced; past the end: a name no format has), the second the channel
 * (0xff or 0x7f: the default, else its low 5 bits as an index "N"), and its high bit sends the
 * file through ljgap__handle_file (the handler's answer, the PSD included) instead of
 * ljgap__files_read alone. The file is handed over in a buffer of exactly its length, so that
 * AddressSanitizer sees any read past it.
 *
 * Besides crashes, leaks and undefined behaviour, every result is checked, and a breach aborts
 * (in the replay, tests/fuzz/replay.c, it is counted):
 *   - ljgap__files_read returns one of files.h's statuses; on success the map has 1 to
 *     LJGAP_FILES_MAX_POINTS points, every height finite or NaN, missing equal to the NaN
 *     count and below the points, sizes finite and >= 0, the channel index within the
 *     channels, every text NUL-terminated within its field; on a failure the map holds no
 *     heights, and a bad file's error names its format;
 *   - the handler answers 200, 413, 415 or 422 with one JSON object; 422 bad-file carries the
 *     format; a 200 answer has "source" with the format read.
 */
#include "files.h"
#include "handler.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int ljgap__fuzz_noabort;
long ljgap__fuzz_failures;

static void breach(const char *what)
{
    fprintf(stderr, "fuzz_files: %s\n", what);
    ljgap__fuzz_failures++;
    if (!ljgap__fuzz_noabort) abort();
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    ljgap__limits l = LJGAP_LIMITS_INIT;
    l.max_seconds = 2;
    l.max_topo_points = 1 << 16;
    ljgap__handler_set_limits(&l);
    return 0;
}

static int terminated(const char *s, size_t n)
{
    return memchr(s, '\0', n) != NULL;
}

static void check_map(const ljgap__files_map *m)
{
    size_t N = m->nx * m->ny, nan = 0;
    if (!m->z || !m->nx || !m->ny || m->nx > LJGAP_FILES_MAX_POINTS / m->ny) {
        breach("a map read without heights, or too large");
        return;
    }
    for (size_t i = 0; i < N; i++) {
        if (isnan(m->z[i]))
            nan++;
        else if (!isfinite(m->z[i]))
            breach("an infinite height");
    }
    if (nan != m->missing || nan >= N) breach("missing is not the count of NaN, or all are");
    if (!(m->size_x >= 0 && m->size_y >= 0 && isfinite(m->size_x) && isfinite(m->size_y)))
        breach("a size that is no finite number >= 0");
    if (m->n_channels < 1 || m->n_channels > LJGAP_FILES_MAX_CHANNELS || m->channel_index < 0 ||
        m->channel_index >= m->n_channels)
        breach("the channel index is outside the channels");
    if (!terminated(m->channel, sizeof m->channel) || !terminated(m->z_unit, sizeof m->z_unit) ||
        !terminated(m->instrument, sizeof m->instrument) ||
        !terminated(m->acquired, sizeof m->acquired) || !m->format)
        breach("a text field is not terminated");
    for (int i = 0; i < m->n_channels && i < LJGAP_FILES_MAX_CHANNELS; i++)
        if (!terminated(m->channels[i], sizeof m->channels[i])) breach("a channel title runs on");
}

static void check_answer(const ljgap__reply *r)
{
    cJSON *a = r->body ? cJSON_ParseWithLength(r->body, r->len) : NULL;
    if (!a || !cJSON_IsObject(a)) {
        breach("the answer is no JSON object");
    } else if (r->status == 200) {
        const cJSON *s = cJSON_GetObjectItem(a, "source");
        if (!cJSON_IsString(cJSON_GetObjectItem(s, "format"))) breach("200 without source.format");
    } else if (r->status == 422 || r->status == 413 || r->status == 415) {
        const cJSON *t = cJSON_GetObjectItem(a, "type");
        if (!cJSON_IsString(t))
            breach("a problem without type");
        else if (!strcmp(t->valuestring, "/problems/bad-file") &&
                 !cJSON_IsString(cJSON_GetObjectItem(a, "format")))
            breach("bad-file without its format");
    } else {
        breach("a status that is not 200, 413, 415 or 422");
    }
    cJSON_Delete(a);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const ljgap__files_format *const *f = ljgap__files_formats();
    int nf = 0;
    char channel[8] = "";
    if (size < 2) return 0;
    while (f[nf])
        nf++;
    const char *format = data[0] == 0 ? NULL : data[0] <= nf ? f[data[0] - 1]->name : "none-such";
    int via_handler = data[1] & 0x80, c = data[1] & 0x7f;
    if (c != 0x7f) snprintf(channel, sizeof channel, "%d", c & 0x1f);
    size_t n = size - 2;
    unsigned char *file = malloc(n ? n : 1);
    if (!file) return 0;
    memcpy(file, data + 2, n);
    if (via_handler) {
        ljgap__param q[2];
        size_t nq = 0;
        if (format) q[nq++] = (ljgap__param){"format", format};
        if (channel[0]) q[nq++] = (ljgap__param){"channel", channel};
        ljgap__reply r;
        ljgap__handle_file("psd", q, nq, file, n, NULL, &r);
        check_answer(&r);
        ljgap__reply_free(&r);
    } else {
        ljgap__files_map m;
        ljgap__files_err e;
        int st = ljgap__files_read(file, n, format, channel[0] ? channel : NULL, &m, &e);
        if (st < 0 || st > LJGAP_FILES_TOOBIG) breach("an unknown status");
        if (st == 0) check_map(&m);
        if (st && m.z) breach("a failed read left heights");
        if (st == LJGAP_FILES_BAD && !e.format) breach("a bad file without its format");
        if (!terminated(e.msg, sizeof e.msg) || !terminated(e.member, sizeof e.member))
            breach("an error text runs on");
        ljgap__files_map_free(&m);
    }
    free(file);
    return 0;
}
