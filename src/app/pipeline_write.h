/* Writing a result into an output directory (pipeline_write.c). */
#pragma once
#include "app/result.h"
#include "io/outdir.h"

/* Writes what r holds into an open output directory. */
int c0_result_write_to(const struct c0_result *r, struct c0_outdir *out);
