/* The drift's files: the trajectory as a table and as a small plot, from
 * the public view of stages/drift.h. */
#pragma once
#include "stages/drift.h"

#include <stddef.h>
#include <stdint.h>

/* drift.csv: one row per frame (stack, frame, dx_nm, dy_nm), allocated. */
int c0_drift_csv(const struct c0_drift *d, double pixel_nm, char **buf, size_t *len);
/* A small plot (RGB, allocated): x (red) and y (blue) shift against frame,
 * grey zero line, grey ticks every 10 nm, stack boundaries dotted. */
int c0_drift_plot(const struct c0_drift *d, double pixel_nm, uint8_t **rgb, int *w, int *h);
