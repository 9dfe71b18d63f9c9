/* The single-step commands on files (single.c). */
#pragma once
#include "app/result.h"

/* The intensity step alone on the stacks, on the support mask in the TIFF
 * support (fine grid), with c's noise variances when given (one per stack). */
int c0_run_intensity_files(const struct c0_run_conf *c, const struct c0_stack *stacks, int n, const char *support,
			   struct c0_result **out);
/* The standard MA-TIRF path on one 2D TIFF image per angle (paths[0..n)). */
int c0_run_matirf_files(const struct c0_run_conf *c, char *const *paths, int n, struct c0_result **out);
