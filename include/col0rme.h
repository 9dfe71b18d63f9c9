/* col0rme public API: plain structs in, plain arrays out, status codes. */
#pragma once

#include "core/err.h"
#include "io/tiff.h"

/* The simulator of `col0rme simulate` in memory: blinking emitters on
 * filaments, one acquisition per angle, camera noise. Parameters by name
 * (sim.json's "parameters": "seed", "width", "height", "frames", "pixel_nm",
 * "fwhm_nm", "angles" (comma list, deg) or "nangles" (a default set),
 * "snr_db", "background", ...); the stacks are the values the CLI writes. */
struct c0_simulation;
int c0_simulation_new(struct c0_simulation **out);
int c0_simulation_set(struct c0_simulation *s, const char *name, const char *value);
double c0_simulation_get(const struct c0_simulation *s, const char *name);   /* NAN: no such parameter */
int c0_simulation_run(struct c0_simulation *s);
const float *c0_simulation_stack(const struct c0_simulation *s, int q, int *frames, int *h, int *w);  /* ADU, after run */
const double *c0_simulation_angles(const struct c0_simulation *s, int *n);
const double *c0_simulation_emitters(const struct c0_simulation *s, int *n);  /* n x (x, y, z nm, brightness) */
void c0_simulation_free(struct c0_simulation *s);
