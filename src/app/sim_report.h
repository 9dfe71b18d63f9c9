/* The simulator's run as a library call: the acquisitions and their ground
 * truth (sim/sim.h) written to an output directory with sim.json, every
 * parameter and the estimates of what was simulated. */
#pragma once
#include "sim/sim.h"
#include "io/report.h"

struct c0_outdir;

/* sim.json's content for c and its result (parameters, estimates, timings) */
void c0_sim_report(const struct c0_sim_conf *c, const struct c0_sim_result *r, cJSON *rep);
/* c0_simulate into out, then out/sim.json (argc, argv: the command line it
 * records); the directory is left for the caller to finish. */
int c0_sim_write(const struct c0_sim_conf *c, struct c0_outdir *out, int argc, char **argv, struct c0_sim_result *res);
