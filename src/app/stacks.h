/* The input stacks of a run and the start every run shares (stacks.c). */
#pragma once
#include "app/result.h"
#include "app/pipeline_conf.h"
#include "io/frames.h"

/* Opens the stacks as frame sources, all the same size. */
int c0_stacks_open(const struct c0_stack *s, int n, struct c0_frames *f);
void c0_stacks_close(struct c0_frames *f, int n);
/* How many of n stacks of bytes[i] bytes each, read again pass after pass,
 * the page cache is left to keep: the first ones whose sum fits in three
 * quarters of avail bytes (n when they all fit, or avail is unknown: 0). */
int c0_stacks_keep_cached(const double *bytes, int n, double avail);
/* The camera pixel size: c->pixel_nm (>= 0, finite), else the stacks'
 * calibration, which must be the same for all n. */
int c0_stacks_pixel(const struct c0_run_conf *c, const struct c0_frames *f, int n, double *pixel_nm);
/* Every stack against the support config (size against the PSF band, frames). */
int c0_stacks_check(const struct c0_support_conf *sc, const struct c0_frames *f, int n);
/* The start of every run: the stacks opened into f (close them with
 * c0_stacks_close), the stages' configs, an empty result for command. */
int c0_pipe_begin(const char *command, const struct c0_run_conf *c, const struct c0_stack *stacks, int n,
		  struct c0_frames *f, struct c0_stage_confs *sc, struct c0_result **out);

/* c0_pipe_begin, then body on the open stacks, then the stacks closed; the
 * result in *out, or freed when body fails. */
typedef int (*c0_pipe_body)(const struct c0_run_conf *c, const struct c0_stage_confs *sc, struct c0_frames *f, int n,
			    struct c0_result *r, const void *arg);
int c0_pipe_run(const char *command, const struct c0_run_conf *c, const struct c0_stack *stacks, int n,
		c0_pipe_body body, const void *arg, struct c0_result **out);
