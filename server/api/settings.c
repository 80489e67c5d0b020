/* settings.c -- the request handler's limits (settings.h): defaults and the psd map's cap. */
#include "settings.h"

#include <unistd.h>

void ljgap__limits_default(ljgap__limits *l)
{
    static const ljgap__limits init = LJGAP_LIMITS_INIT;
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    *l = init;
    l->sweep_threads = n > 0 ? n : 1;
    l->sim_threads = 1;
}

size_t ljgap__limits_topo_cap(const ljgap__limits *l)
{
    return (size_t)(l->max_topo_points > 0 ? l->max_topo_points : LJGAP_TOPO_POINTS_DEFAULT);
}
