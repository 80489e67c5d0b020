/* util.c -- status strings, warnings, clocks and defaults shared by the core. */
#define _POSIX_C_SOURCE 200809L
#include "ljgap.h"
#include "core.h" /* the core's internals */

#include <gsl/gsl_errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

const char *ljgap_strerror(int status)
{
    switch (status) {
    case LJGAP_OK:
        return "success";
    case LJGAP_EINVAL:
        return "input outside the model's domain";
    case LJGAP_ENOMEM:
        return "out of memory";
    case LJGAP_ECAP:
        return "the request needs more work than the server's caps allow";
    case LJGAP_EFAIL:
        return "numerical failure";
    case LJGAP_ECANCEL:
        return "cancelled";
    default:
        return "unknown status";
    }
}

void ljgap_init(void)
{
    gsl_set_error_handler_off();
}

void ljgap_warn(ljgap_warnings *w, const char *fmt, ...)
{
    if (!w || w->n >= LJGAP_MAX_WARN) return;
    char buf[LJGAP_WARN_LEN];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    for (int i = 0; i < w->n; i++)
        if (strcmp(w->msg[i], buf) == 0) return;
    memcpy(w->msg[w->n++], buf, sizeof buf);
}

void ljgap_opts_default(ljgap_opts *o)
{
    o->method = LJGAP_METHOD_PDE;
    o->tol = 1e-6;
    o->vmax = 1.0 / 400.0;
    o->fixed_vmax = 0;
    o->samples = 100000;
    o->seed = 1;
    o->max_seconds = 20.0;
    o->max_work = 400000000L;
    o->cancel = NULL;
}

double ljgap__now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int ljgap__should_stop(const ljgap_opts *o, double deadline)
{
    if (o && o->cancel && *o->cancel) return 1;
    return ljgap__now() > deadline;
}

/* The methods (pde.c, paper.c, mc.c) free their partial results with it, and the caller of
 * ljgap_pdf_compute its answer: it lives here, below them all, not in solve.c above them. */
void ljgap_pdf_release(ljgap_pdf *p, size_t n)
{
    if (!p) return;
    for (size_t i = 0; i < n; i++) {
        free(p[i].g);
        free(p[i].phi);
        p[i].g = p[i].phi = NULL;
        p[i].n = 0;
    }
}
