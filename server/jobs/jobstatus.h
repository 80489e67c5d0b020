/* jobstatus.h -- what a client sees of a job: its stored record as the API's status object.
 *
 * Records come back from a database, so they are input: a damaged or hand-edited row must
 * neither crash the daemon nor put invalid JSON on the wire. ljgap__job_status_json checks
 * every field it shows (a known state, finite times in range, progress in [0, 1], an answer
 * that is one JSON object in valid UTF-8 with finite numbers, and a problem document when it
 * is a problem) and shows a row that fails the
 * checks as a failed job whose problem (type job-damaged, 500) says what is wrong with it.
 * A sound row's answer is shown as stored: cJSON re-prints it, and the answers the handler
 * writes are cJSON's own unformatted print, which re-prints to the same bytes, so a finished
 * job reads the same before and after a restart.
 *
 *   {"id","status","progress","elapsed_ms","created"[,"started"][,"finished"]
 *    [,"result" when done][,"problem" when failed, or cancelled while running]}
 *
 * Times are RFC 3339 UTC with milliseconds ("2025-01-31T12:00:00.000Z"); elapsed_ms is the
 * running time (0 while queued; from start to now while running, to the end once finished).
 */
#ifndef LJGAP_JOBSTATUS_H
#define LJGAP_JOBSTATUS_H

#include "jobstore.h"
#include "problems.h"

#include <stddef.h>


/* The status object of rec as a malloc'd one-line JSON string; NULL if memory ran out. */
char *ljgap__job_status_json(const ljgap__job_record *rec);

/* Is answer[0..len) one JSON object, valid UTF-8 without NUL, every number finite, and when
 * problem is nonzero a problem document (type under LJGAP_PROBLEM_BASE, title, status 400 to
 * 599, detail, errors[] of {pointer, detail})? What the status object shows of a stored answer must pass this. */
int ljgap__job_answer_ok(const char *answer, size_t len, int problem);

/* An RFC 9457 problem object (type LJGAP_PROBLEM_BASE slug, title, status, detail, empty
 * errors) as a malloc'd JSON string; NULL if memory ran out. */
char *ljgap__job_problem(int status, const char *slug, const char *title, const char *detail);

/* Writes t (Unix seconds, >= 0) as RFC 3339 UTC with milliseconds into buf (>= 25 bytes). */
void ljgap__rfc3339(double t, char *buf, size_t size);

#endif
