/* memest.c -- upper bounds of a request's working memory (memest.h). */
#include "memest.h"

#include <cjson/cJSON.h>

#define MIB ((size_t)1 << 20)

/* topo_text.c's separators: white space, line ends, commas; '#' starts a comment */
static const unsigned char sep[256] = {
    [' '] = 1, ['\t'] = 1, ['\r'] = 1, ['\n'] = 1, ['\v'] = 1, ['\f'] = 1, [','] = 1, ['#'] = 1};

void ljgap__token_feed(ljgap__token_count *tc, const char *data, size_t n)
{
    const unsigned char *p = (const unsigned char *)data;
    size_t t = tc->tokens;
    int in = tc->inside;
    for (size_t i = 0; i < n; i++) {
        int s = sep[p[i]];
        t += !s & !in;
        in = !s;
    }
    tc->tokens = t;
    tc->inside = in;
}

size_t ljgap__memest_psd_text(size_t values)
{
    return 40 * values + 4 * MIB;
}

size_t ljgap__json_values(const char *body, size_t len)
{
    size_t n = 1;
    for (size_t i = 0; i < len; i++)
        n += body[i] == '[' || body[i] == ',' || body[i] == ':';
    return n;
}

size_t ljgap__memest_json(size_t len, size_t values, unsigned threads)
{
    return 128 * values + 2 * len + 8 * MIB + 2 * MIB * (size_t)(threads ? threads : 1);
}

size_t ljgap__memest_sim(int n, unsigned threads)
{
    size_t N = (size_t)n * (size_t)n, nc = (size_t)n * (size_t)(n / 2 + 1);
    size_t ws = 14 * N * sizeof(double) + nc * sizeof(double) + 3 * nc * 2 * sizeof(double);
    return (size_t)(threads ? threads : 1) * ws + 4 * N * sizeof(double) + 4 * MIB;
}

size_t ljgap__memest_sim_request(const char *body, size_t len, unsigned threads)
{
    int n = 64, R = 4;
    cJSON *root = cJSON_ParseWithLength(body, len);
    const cJSON *it;
    if (root) {
        if ((it = cJSON_GetObjectItemCaseSensitive(root, "n")) && cJSON_IsNumber(it) &&
            it->valuedouble >= 8 && it->valuedouble <= 4096)
            n = (int)it->valuedouble;
        if ((it = cJSON_GetObjectItemCaseSensitive(root, "realizations")) && cJSON_IsNumber(it) &&
            it->valuedouble >= 1 && it->valuedouble <= 64)
            R = (int)it->valuedouble;
        cJSON_Delete(root);
    }
    if (threads > (unsigned)R) threads = (unsigned)R;
    return ljgap__memest_sim(n, threads);
}
