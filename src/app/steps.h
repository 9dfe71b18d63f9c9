/* The steps of a run (steps.c): each adds its arrays and its part of the report to a c0_result. */
#pragma once
#include "app/result.h"
#include "app/pipeline_conf.h"
#include "io/frames.h"

/* A step's bookkeeping: its name for the out-of-memory message while it
 * runs (c0_mem_stage), then in the report its wall seconds (timings_s), the
 * peak resident memory so far (peak_rss_mb) and how much the step raised
 * that peak (rss_rise_mb; 0: it stayed below an earlier step's). */
struct c0_step_clock { const char *key; double t0, peak0; };
struct c0_step_clock c0_step_begin(const char *key);
void c0_step_end(struct c0_result *r, const struct c0_step_clock *k);
/* Drift over all n stacks of f (stages/drift.h), on clock's acquisition
 * order, gaps and interleaving (NULL: one stack after another as given);
 * the later steps undo it frame by frame. */
int c0_step_drift(struct c0_result *r, const struct c0_drift_conf *dc, const struct c0_bleach_conf *clock,
		  struct c0_frames *f, int n);
/* Support of stacks r->sup[0..nsup) (indices into f); sets the union mask.
 * pool (and several stacks): one support from their covariances pooled
 * (c0_support_stacks), listed in r->pool; nsup becomes 1. */
int c0_step_support(struct c0_result *r, const struct c0_support_conf *sc, struct c0_frames *f, int pool);
/* Bleaching across the stacks (stages/bleach.h) by bc: the fade estimated
 * from the frame sums and the fitted backgrounds (or the known factors, or
 * none) into r->bleach_factor and rep["bleaching"]. */
int c0_step_bleach(struct c0_result *r, const struct c0_bleach_conf *bc, struct c0_frames *f);
/* After the MA-TIRF step (the angles a, stack tirf[i] at a->deg[i]): the
 * common depth offset one sd of an estimated fade rate leaves, at the depth
 * map's median, as rep["bleaching"]["depth_offset_sd_nm"]; nothing where
 * the fade was not estimated from the stacks. */
struct c0_angles;
struct c0_tirf;
int c0_report_bleach_depth(struct c0_result *r, const struct c0_angles *a, const int *tirf, const struct c0_tirf *t);
