/* replay.c -- runs the fuzz target over files, without libFuzzer (make test's corpus replay).
 *
 *   replay FILE|DIR...    feed each file (each regular file of each DIR, in name order) to
 *                         LLVMFuzzerTestOneInput; print "ok - NAME" or "not ok - NAME"
 *
 * Built with the normal compiler (and the sanitizers of a SANITIZE= build), so plain
 * `make test` needs no fuzzer runtime. The target's contract checks count breaches here
 * instead of aborting; a sanitizer report still ends the process, which tests/fuzz/run.sh
 * reports. Exit status 1 when any input failed.
 */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
extern int ljgap__fuzz_noabort;
extern long ljgap__fuzz_failures;

/* Reads the whole file into a malloc'd buffer of exactly its size (1 byte when empty). */
static uint8_t *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    uint8_t *buf = NULL;
    long size;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (size = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (buf = malloc(size ? (size_t)size : 1)) && fread(buf, 1, (size_t)size, f) != (size_t)size) {
        free(buf);
        buf = NULL;
    }
    *n = buf ? (size_t)size : 0;
    fclose(f);
    return buf;
}

static int run_file(const char *path)
{
    size_t n;
    uint8_t *data = slurp(path, &n);
    long before = ljgap__fuzz_failures;
    if (!data) {
        printf("not ok - %s: cannot read\n", path);
        return 1;
    }
    LLVMFuzzerTestOneInput(data, n);
    free(data);
    printf("%s - fuzz input %s\n", ljgap__fuzz_failures == before ? "ok" : "not ok", path);
    fflush(stdout);
    return ljgap__fuzz_failures != before;
}

static int by_name(const struct dirent **a, const struct dirent **b)
{
    return strcmp((*a)->d_name, (*b)->d_name);
}

int main(int argc, char **argv)
{
    int failed = 0;
    ljgap__fuzz_noabort = 1;
    LLVMFuzzerInitialize(&argc, &argv);
    for (int i = 1; i < argc; i++) {
        struct stat sb;
        struct dirent **list;
        int n;
        if (stat(argv[i], &sb) != 0 || !S_ISDIR(sb.st_mode)) {
            failed |= run_file(argv[i]);
            continue;
        }
        if ((n = scandir(argv[i], &list, NULL, by_name)) < 0) {
            printf("not ok - %s: cannot list\n", argv[i]);
            failed = 1;
            continue;
        }
        for (int k = 0; k < n; k++) {
            char path[4096];
            snprintf(path, sizeof path, "%s/%s", argv[i], list[k]->d_name);
            if (stat(path, &sb) == 0 && S_ISREG(sb.st_mode)) failed |= run_file(path);
            free(list[k]);
        }
        free(list);
    }
    return failed;
}
