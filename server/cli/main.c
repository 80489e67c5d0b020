/* cli.c -- build/ljgap: the request handler on the command line.
 *
 *   ljgap NAME [FILE]     read the request for endpoint NAME from FILE (or stdin), print the
 *                         answer body (one line) on stdout
 *   ljgap psd --dx M [--dy M] [--periodic] [--E_star PA ...] [FILE]
 *                         the PSD of a height matrix in text (FILE or stdin: one row a line,
 *                         heights in m; POST /v1/psd with text/plain): the options are the
 *                         query parameters (--NAME VALUE or --NAME=VALUE; --periodic alone
 *                         means periodic=true), handed to ljgap__handle_text
 *   ljgap psd [--format NAME] [--channel C] [--NAME VALUE ...] FILE
 *                         the PSD of an instrument file (NanoScope, .gwy, .gsf, xyz columns,
 *                         ...: server/files/), its format recognised by content (POST /v1/psd
 *                         with application/octet-stream), handed to ljgap__handle_file
 *   ljgap simulations [FILE]   run one numerical-model job in the foreground (the body of
 *                         POST /v1/simulations); stdout gets the job's "result" object, stderr
 *                         a progress bar when it is a terminal (nothing otherwise, so logs and
 *                         pipes stay clean); Ctrl-C cancels the run (a 503 problem, exit 1)
 *   ljgap combine [--points-per-decade G] FILE FILE ...
 *                         one PSD from several measurements (POST /v1/psd/combine): each FILE
 *                         a /v1/psd answer or a psd object ('-' standard input, once);
 *                         ljgap__combine_body makes the request
 *   ljgap --csv NAME ...  the answer as CSV (traction, pdf, sweep, simulations), as
 *                         POST /v1/NAME with Accept: text/csv gives it
 *
 * The same contract as POST /v1/NAME (docs/api.md): exit status 0 for a 2xx answer, 1 for a
 * problem (whose body is still printed on stdout), 2 when the command line is wrong or the
 * request cannot be read. A thin shell: all the work is in ljgap__handle_call and
 * ljgap__handle_text. The manual page is man/ljgap.1.
 */
#include "csv.h"
#include "files.h" /* ljgap__files_detect: is the file an instrument's? */
#include "handler.h"
#include "ljgap.h"

#include <errno.h>
#include <fftw3.h>
#include <gsl/gsl_errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ljgap [--csv] NAME [FILE]\n"
            "       ljgap psd --dx M [--dy M] [--periodic] [--NAME VALUE ...] [FILE]\n"
            "       ljgap psd [--format NAME] [--channel C] [--NAME VALUE ...] FILE\n"
            "       ljgap combine [--points-per-decade G] [--request] FILE FILE ...\n"
            "       ljgap --help | --version\n"
            "Reads a JSON request for endpoint NAME (adhesion, traction, pdf, sweep, contact,\n"
            "psd) from FILE or standard input and prints the JSON answer on standard output.\n"
            "With options, psd reads a height matrix in text instead (one row a line, heights\n"
            "in m separated by spaces or commas, '#' comments); the options are the query\n"
            "parameters of POST /v1/psd: dx, dy (m, default dx), periodic, detrend (mean,\n"
            "plane, lines, curvature), tip_radius, resolution (m), fit_k_min, fit_k_max (1/m),\n"
            "and a material's E_star (or E1, nu1, E2, nu2), dgamma, epsilon.\n"
            "An instrument file (NanoScope, .gwy, .gsf, xyz columns, ...) is recognised by\n"
            "its content: its grid, size and unit come from it; --channel picks a channel\n"
            "(index or title; default the height channel), --format forces a format.\n"
            "combine makes one PSD of several measurements of one surface (POST\n"
            "/v1/psd/combine): each FILE is a /v1/psd answer or a psd object (k, P, P_err);\n"
            "the request is printed instead with --request.\n"
            "NAME simulations runs one numerical-model job in the foreground and prints its\n"
            "result; a progress bar goes to standard error when it is a terminal, and Ctrl-C\n"
            "cancels the run.\n"
            "  --csv      print the answer as CSV (traction, pdf, sweep, simulations); problems\n"
            "             stay JSON\n"
            "  --help     this text\n"
            "  --version  the program's version\n"
            "Exit status: 0 for a 2xx answer, 1 for a problem answer, 2 for a usage or\n"
            "read error. The fields are in ljgap(1) and docs/api.md.\n");
}

/* Reads all of f into a malloc'd, NUL-terminated buffer; NULL on error (errno set). */
static char *read_all(FILE *f, size_t *len)
{
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap), *bigger;
    while (buf) {
        n += fread(buf + n, 1, cap - n - 1, f);
        if (n < cap - 1) break;
        if (!(bigger = realloc(buf, cap *= 2))) {
            free(buf);
            return NULL;
        }
        buf = bigger;
    }
    if (!buf) return NULL;
    if (ferror(f)) {
        free(buf);
        return NULL;
    }
    buf[n] = '\0';
    *len = n;
    return buf;
}

/* ---- simulations in the foreground ---- */

static volatile sig_atomic_t interrupted; /* Ctrl-C: the run's cancel flag */

static void on_sigint(int sig)
{
    (void)sig;
    interrupted = 1;
}

#define BAR_WIDTH 40

/* The progress bar on a terminal: redrawn in place when the whole percent changes. */
typedef struct {
    int last; /* percent drawn last, -1 before the first */
} bar;

static void bar_draw(void *ctx, double fraction)
{
    static const char full[BAR_WIDTH + 1] = "########################################";
    bar *b = ctx;
    int pct = (int)(100 * (fraction > 0 ? (fraction < 1 ? fraction : 1) : 0));
    if (pct == b->last) return;
    b->last = pct;
    fprintf(stderr, "\r[%-*.*s] %3d%%", BAR_WIDTH, pct * BAR_WIDTH / 100, full, pct);
    fflush(stderr);
}

/* Validates and runs one simulation, the answer into *rep (as ljgap__handle would). */
static void run_simulation(const char *body, size_t len, ljgap__reply *rep)
{
    bar b = {-1};
    int tty = isatty(STDERR_FILENO);
    ljgap__sim_control ctl = {0, &interrupted, tty ? bar_draw : NULL, &b};
    struct sigaction sa, old;
    ljgap__sim_request *rq = ljgap__sim_request_parse(body, len, rep);
    if (!rq) return;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old);
    ljgap__sim_request_run(rq, &ctl, rep);
    sigaction(SIGINT, &old, NULL);
    if (b.last >= 0) fputc('\n', stderr);
    ljgap__sim_request_free(rq);
    fftw_cleanup(); /* the run's FFTW planner state is global */
}

/* The options after NAME as query parameters (params has room for argc entries); *file gets
 * the one argument that is not an option, if any. Returns the number of parameters, or -1
 * (after a message) when the command line is wrong. */
static int text_options(int argc, char **argv, ljgap__param *params, const char **file)
{
    int n = 0;
    for (int i = 2; i < argc; i++) {
        char *a = argv[i], *eq;
        if (strncmp(a, "--", 2) != 0 || !a[2]) {
            if (*file) {
                fprintf(stderr, "ljgap: more than one file: '%s' and '%s'\n", *file, a);
                return -1;
            }
            *file = a;
            continue;
        }
        params[n].name = a + 2;
        if ((eq = strchr(a + 2, '='))) { /* --name=value */
            *eq = '\0';
            params[n].value = eq + 1;
        } else if (strcmp(a + 2, "periodic") == 0) {
            params[n].value = "true";
        } else if (i + 1 < argc) {
            params[n].value = argv[++i];
        } else {
            fprintf(stderr, "ljgap: option --%s needs a value\n", a + 2);
            return -1;
        }
        n++;
    }
    return n;
}

/* Is body an instrument file for psd (rather than a JSON request or a text matrix)? With
 * --format or --channel, always; else when a reader recognises it, except that xyz columns
 * beside a --dx are a text matrix of three columns, and a JSON object stays a request. */
static int is_instrument_file(const char *body, size_t len, const ljgap__param *p, int np)
{
    const ljgap__files_format *f;
    int dx = 0;
    for (int i = 0; i < np; i++) {
        if (!strcmp(p[i].name, "format") || !strcmp(p[i].name, "channel")) return 1;
        dx |= !strcmp(p[i].name, "dx");
    }
    size_t k = strspn(body, " \t\r\n");
    if (np < 0 && k < len && body[k] == '{') return 0;
    f = ljgap__files_detect((const unsigned char *)body, len);
    return f && !(dx && !strcmp(f->name, "xyz"));
}

/* ljgap combine [--points-per-decade G] [--request] FILE FILE ...: the answer (or with
 * --request the request) into *rep; 2 when the command line or a file is wrong. */
static int run_combine(int argc, char **argv, const ljgap__call *call, ljgap__reply *rep)
{
    const char *docs[64];
    size_t lens[64], n = 0;
    double g = 0;
    int rc = 2, request = 0;
    char err[300], *body = NULL;
    for (int i = 2; i < argc; i++) {
        FILE *f;
        if (strcmp(argv[i], "--points-per-decade") == 0 && i + 1 < argc) {
            char *end;
            g = strtod(argv[++i], &end);
            if (*end || !(g > 0)) {
                fprintf(stderr, "ljgap: --points-per-decade needs a positive number\n");
                goto end;
            }
            continue;
        }
        if (strcmp(argv[i], "--request") == 0) {
            request = 1;
            continue;
        }
        if (strncmp(argv[i], "--", 2) == 0 || n == 64) {
            usage(stderr);
            goto end;
        }
        f = strcmp(argv[i], "-") == 0 ? stdin : fopen(argv[i], "rb");
        if (!f || !(docs[n] = read_all(f, &lens[n]))) {
            fprintf(stderr, "ljgap: %s: %s\n", argv[i], strerror(errno));
            if (f && f != stdin) fclose(f);
            goto end;
        }
        if (f != stdin) fclose(f);
        n++;
    }
    if (n < 2) {
        fprintf(stderr, "ljgap: combine takes two files or more\n");
        goto end;
    }
    if (!(body = ljgap__combine_body(docs, lens, n, g, err, sizeof err))) {
        fprintf(stderr, "ljgap: combine: %s\n", err);
        goto end;
    }
    if (request) {
        rep->status = 200;
        rep->body = body;
        rep->len = strlen(body);
        body = NULL;
    } else {
        ljgap__handle_call("psd/combine", body, strlen(body), call, rep);
    }
    rc = 0;
end:
    for (size_t i = 0; i < n; i++)
        free((char *)docs[i]);
    free(body);
    return rc;
}

int main(int argc, char **argv)
{
    FILE *in = stdin;
    char *body = NULL;
    const char *file = NULL;
    ljgap__param *params = NULL;
    size_t len = 0;
    ljgap__reply rep = {0};
    int rc = 2, nparams = -1, csv = 0;
    ljgap__call call = {0};
    gsl_set_error_handler_off();
    if (argc == 2 && strcmp(argv[1], "--help") == 0) {
        usage(stdout);
        return 0;
    }
    if (argc == 2 && strcmp(argv[1], "--version") == 0) {
        printf("ljgap %s\n", LJGAP_VERSION);
        return 0;
    }
    if (argc > 1 && strcmp(argv[1], "--csv") == 0) {
        csv = 1;
        call.accept = "text/csv";
        argv++;
        argc--;
    }
    if (argc < 2 || argv[1][0] == '-') {
        usage(stderr);
        return 2;
    }
    if (strcmp(argv[1], "combine") == 0) {
        if (run_combine(argc, argv, &call, &rep)) goto end;
        goto print;
    }
    for (int i = 2; i < argc; i++)
        if (strncmp(argv[i], "--", 2) == 0 && argv[i][2]) nparams = 0; /* a text upload */
    if (nparams == 0) {
        if (!ljgap__handler_has_text(argv[1])) {
            fprintf(stderr, "ljgap: options are for a text upload, which only psd takes\n");
            usage(stderr);
            return 2;
        }
        if (!(params = calloc((size_t)argc, sizeof *params))) goto end;
        if ((nparams = text_options(argc, argv, params, &file)) < 0) goto end;
    } else if (argc > 3) {
        usage(stderr);
        return 2;
    } else {
        file = argc == 3 ? argv[2] : NULL;
    }
    if (file && strcmp(file, "-") != 0 && !(in = fopen(file, "rb"))) {
        fprintf(stderr, "ljgap: %s: %s\n", file, strerror(errno));
        goto end;
    }
    if (!(body = read_all(in, &len))) {
        fprintf(stderr, "ljgap: cannot read the request: %s\n", strerror(errno));
        goto end;
    }
    if (strcmp(argv[1], "psd") == 0 && is_instrument_file(body, len, params, nparams)) {
        ljgap__handle_file(argv[1], params, nparams > 0 ? (size_t)nparams : 0,
                          (const unsigned char *)body, len, &call, &rep);
    } else if (nparams >= 0) {
        ljgap__handle_text(argv[1], params, (size_t)nparams, body, len, &call, &rep);
    } else if (strcmp(argv[1], "simulations") == 0) {
        run_simulation(body, len, &rep);
        if (csv) ljgap__csv_reply(argv[1], &rep);
    } else {
        ljgap__handle_call(argv[1], body, len, &call, &rep);
    }
print:
    /* a CSV body ends in its own newline; a JSON one gets one */
    if (fwrite(rep.body, 1, rep.len, stdout) != rep.len ||
        (!(rep.len && rep.body[rep.len - 1] == '\n') && putchar('\n') == EOF) ||
        fflush(stdout) != 0) {
        fprintf(stderr, "ljgap: cannot write the answer: %s\n", strerror(errno));
        goto end;
    }
    rc = rep.status >= 200 && rep.status < 300 ? 0 : 1;
end:
    ljgap__reply_free(&rep);
    free(params);
    free(body);
    if (in && in != stdin) fclose(in);
    return rc;
}
