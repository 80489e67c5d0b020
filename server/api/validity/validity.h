/* validity.h -- where the theory holds, in the answers (validity.c): the "model" object of an
 * answer and its warning, and GET /v1/validity's answer. Used by handler.c and the daemon's
 * route table.
 */
#ifndef LJGAP_API_VALIDITY_H
#define LJGAP_API_VALIDITY_H

#include "answer.h"
#include "reply.h"

/* The map's verdict on spec as j->ans's "model" (and si's, when the answer has "si"), with a
 * warning in j->rq.warn when the theory differs from the discrete model by more than 5 %. */
void ljgap__ans_model(job *j, const ljgap__psd_spec *spec);
/* The same for each value of a sweep: results[i].model (and si.results[i].model), one warning
 * naming the values over 5 %. */
void ljgap__ans_model_sweep(job *j);
/* The map itself into j->ans: "map" (axes and rows) and "how". */
void ljgap__validity_answer(job *j);
/* GET /v1/validity: the map with meta, as a 200 JSON reply (or 500 out of memory). */
void ljgap__validity_reply(ljgap__reply *out);

#endif
