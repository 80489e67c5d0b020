/* jobstatus.c -- a job's stored record as the status object, checked on the way out
 * (jobstatus.h).
 *
 * The object is built with cJSON, so every string is escaped whatever the row holds; the one
 * piece taken from the row as JSON, the answer, is parsed, checked and re-printed. Any field
 * that fails its check is either dropped (a time out of range), clamped (progress) or, when
 * it matters to the client (state, answer), turns the job into a failed one carrying a
 * job-damaged problem that names the field.
 */
#include "jobstatus.h"
#include "request.h"
#include "textbuf.h" /* ljgap__utf8_span */

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Times before 1970 or past the year 5000 are not times a job was created at. */
#define TIME_MAX 95617584000.0

static int all_finite(const cJSON *v)
{
    if (cJSON_IsNumber(v)) return isfinite(v->valuedouble);
    for (const cJSON *c = v->child; c; c = c->next)
        if (!all_finite(c)) return 0;
    return 1;
}

/* The answer parsed, when it passes ljgap__job_answer_ok's checks; else NULL. */
static cJSON *answer_parse(const char *answer, size_t len)
{
    const char *end = NULL;
    cJSON *doc;
    if (!answer || len == 0 || strlen(answer) != len || ljgap__utf8_span(answer, len) != len)
        return NULL;
    doc = cJSON_ParseWithLengthOpts(answer, len, &end, 0);
    while (doc && end && end < answer + len && strchr(" \t\r\n", *end))
        end++;
    if (!cJSON_IsObject(doc) || end != answer + len || !all_finite(doc)) {
        cJSON_Delete(doc);
        return NULL;
    }
    return doc;
}

static cJSON *problem_object(int status, const char *slug, const char *title, const char *detail)
{
    cJSON *p = cJSON_CreateObject();
    char type[96];
    snprintf(type, sizeof type, LJGAP_PROBLEM_BASE "%s", slug);
    if (p && cJSON_AddStringToObject(p, "type", type) &&
        cJSON_AddStringToObject(p, "title", title) &&
        cJSON_AddNumberToObject(p, "status", status) &&
        cJSON_AddStringToObject(p, "detail", detail) && cJSON_AddArrayToObject(p, "errors"))
        return p;
    cJSON_Delete(p);
    return NULL;
}

char *ljgap__job_problem(int status, const char *slug, const char *title, const char *detail)
{
    cJSON *p = problem_object(status, slug, title, detail);
    char *s = p ? cJSON_PrintUnformatted(p) : NULL;
    cJSON_Delete(p);
    return s;
}

void ljgap__rfc3339(double t, char *buf, size_t size)
{
    long long ms = llround(t * 1e3);
    time_t sec = (time_t)(ms / 1000);
    struct tm tm;
    char day[32];
    if (!gmtime_r(&sec, &tm) || !strftime(day, sizeof day, "%Y-%m-%dT%H:%M:%S", &tm)) {
        snprintf(buf, size, "1970-01-01T00:00:00.000Z");
        return;
    }
    snprintf(buf, size, "%s.%03dZ", day, (int)(ms % 1000));
}

/* t when it is a plausible time, else 0 (not shown). */
static double sound_time(double t)
{
    return isfinite(t) && t > 0 && t < TIME_MAX ? t : 0;
}

static int add_time(cJSON *o, const char *key, double t)
{
    char buf[40];
    if (t <= 0) return 1; /* not (yet): not shown */
    ljgap__rfc3339(t, buf, sizeof buf);
    return cJSON_AddStringToObject(o, key, buf) != NULL;
}

/* Milliseconds from a to b, rounded to the microsecond; 0 unless both are times and b >= a. */
static double span_ms(double a, double b)
{
    return a > 0 && b > a ? round((b - a) * 1e6) / 1e3 : 0;
}

static int has_string(const cJSON *o, const char *key)
{
    return cJSON_IsString(cJSON_GetObjectItemCaseSensitive(o, key));
}

/* Is p a problem document: type (one of ours), title, status (an HTTP error status), detail
 * and errors[] of {pointer, detail}? */
static int is_problem(const cJSON *p)
{
    const cJSON *errors = cJSON_GetObjectItemCaseSensitive(p, "errors"), *e;
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(p, "type");
    const cJSON *status = cJSON_GetObjectItemCaseSensitive(p, "status");
    if (!cJSON_IsString(type) ||
        strncmp(type->valuestring, LJGAP_PROBLEM_BASE, strlen(LJGAP_PROBLEM_BASE)) != 0 ||
        !has_string(p, "title") || !has_string(p, "detail") || !cJSON_IsNumber(status) ||
        status->valuedouble != floor(status->valuedouble) || status->valuedouble < 400 ||
        status->valuedouble > 599 || !cJSON_IsArray(errors))
        return 0;
    for (e = errors->child; e; e = e->next)
        if (!has_string(e, "pointer") || !has_string(e, "detail")) return 0;
    return 1;
}

int ljgap__job_answer_ok(const char *answer, size_t len, int problem)
{
    cJSON *doc = answer_parse(answer, len);
    int ok = doc && (!problem || is_problem(doc));
    cJSON_Delete(doc);
    return ok;
}

/* Why rec cannot be shown as stored, or NULL when it can; *answer receives its answer parsed
 * (NULL when it has none to show). */
static const char *damage_of(const ljgap__job_record *rec, cJSON **answer)
{
    *answer = NULL;
    if (rec->state == LJGAP_JOB_BAD)
        return "its status is not one of queued, running, done, failed, cancelled";
    if (rec->state < LJGAP_JOB_DONE) return NULL; /* no answer yet: any stored one is ignored */
    if (rec->answer && !(*answer = answer_parse(rec->answer, rec->answer_len)))
        return rec->state == LJGAP_JOB_DONE ? "its result is not one JSON object in UTF-8"
                                            : "its problem is not one JSON object in UTF-8";
    if (*answer && rec->state != LJGAP_JOB_DONE && !is_problem(*answer))
        return "its problem lacks type, title, status, detail or errors";
    if (!rec->answer && rec->state == LJGAP_JOB_DONE) return "it is done but has no result";
    if (!rec->answer && rec->state == LJGAP_JOB_FAILED) return "it failed but has no problem";
    return NULL;
}

/* The status object; with damage not NULL, the record is shown as damaged for that reason. */
static char *status_json(const ljgap__job_record *rec, const char *damage)
{
    ljgap__job_state state = rec->state;
    double created = sound_time(rec->created), started = sound_time(rec->started);
    double finished = sound_time(rec->finished), now = sound_time(rec->now);
    double progress = isfinite(rec->progress) ? fmin(fmax(rec->progress, 0), 1) : 0;
    double elapsed = 0;
    cJSON *o = cJSON_CreateObject(), *answer = NULL;
    char *out = NULL, detail[200];

    if (!o) return NULL;
    if (!damage) damage = damage_of(rec, &answer);
    if (damage) {
        cJSON_Delete(answer);
        snprintf(detail, sizeof detail,
                 "the stored record of this job is damaged (%s); it cannot be shown or run "
                 "again: submit the request anew",
                 damage);
        if (!(answer = problem_object(500, "job-damaged", "Damaged job record", detail))) goto end;
        state = LJGAP_JOB_FAILED;
    }
    if (state == LJGAP_JOB_QUEUED)
        progress = 0;
    else if (state == LJGAP_JOB_DONE)
        progress = 1;
    if (state == LJGAP_JOB_RUNNING)
        elapsed = span_ms(started, now);
    else if (state != LJGAP_JOB_QUEUED)
        elapsed = span_ms(started, finished);

    if (!cJSON_AddStringToObject(o, "id", ljgap__job_id_valid(rec->id) ? rec->id : "") ||
        !cJSON_AddStringToObject(o, "status", ljgap__job_state_name(state)) ||
        !cJSON_AddNumberToObject(o, "progress", progress) ||
        !cJSON_AddNumberToObject(o, "elapsed_ms", elapsed) || !add_time(o, "created", created) ||
        (state != LJGAP_JOB_QUEUED && !add_time(o, "started", started)) ||
        (state >= LJGAP_JOB_DONE && !add_time(o, "finished", finished)))
        goto end;
    if (answer) {
        cJSON_AddItemToObject(o, state == LJGAP_JOB_DONE ? "result" : "problem", answer);
        answer = NULL;
    }
    out = cJSON_PrintUnformatted(o);
    /* cJSON turns \u escapes into bytes: a lone surrogate would come out as invalid UTF-8 */
    if (out && ljgap__utf8_span(out, strlen(out)) != strlen(out) && !damage) {
        cJSON_free(out);
        cJSON_Delete(o);
        return status_json(rec, "its answer is not valid UTF-8 once unescaped");
    }
end:
    cJSON_Delete(answer);
    cJSON_Delete(o);
    return out;
}

char *ljgap__job_status_json(const ljgap__job_record *rec)
{
    return status_json(rec, NULL);
}
