/* The MA-TIRF steps (steps_matirf.c). */
#pragma once
#include "app/result.h"
#include "app/pipeline_conf.h"

/* MA-TIRF volume from nq images (ny x nx at pixel_nm) into r->vol, or
 * r->base with baseline; pool (or NULL): the pixels' own and pooled
 * intensities when img are pooled (stages/depthpool.h). */
struct c0_pooled;
int c0_step_matirf(struct c0_result *r, const struct c0_angles *a, const struct c0_matirf_conf *m,
		   const float *const *img, const struct c0_pooled *pool, int ny, int nx, double pixel_nm, int baseline);
/* The standard MA-TIRF path on raw images (the matirf command): raw's offset
 * and constant background subtracted (from copies; refused at or above an
 * image's mean), m's joint background estimation and deconvolution (from
 * c0_run_conf_matirf_raw), then c0_step_matirf into r->vol. */
int c0_step_matirf_raw(struct c0_result *r, const struct c0_matirf_raw *raw, const struct c0_matirf_conf *m,
		       const float *const *img, int ny, int nx, double pixel_nm);
