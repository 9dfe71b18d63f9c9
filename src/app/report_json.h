/* report.json's sections: one function per step, each filling its part of
 * report.json from the step's results (the steps themselves build no JSON);
 * the support's in report_json_support.h. */
#pragma once
#include "app/result.h"
#include "app/pipeline_conf.h"
#include "stages/bleach.h"
#include "stages/pattern.h"

/* "drift": the trajectory's blocks and noise, in nm at pixel_nm. */
int c0_report_drift(cJSON *rep, const struct c0_drift *d, double pixel_nm);
/* "render": the Gaussian and precision of the render step. */
void c0_report_render(cJSON *rep, double sd_nm, double precision_nm, double fine_nm);
/* "intensity" (each stack, frames[] and extra seconds tc[]; mu_own: each
 * stack's own discrepancy mu when the MA-TIRF stacks share one, else NULL)
 * and "intensity_parameters". */
void c0_report_intensity(cJSON *rep, const struct c0_result *r, const struct c0_intensity_conf *ic,
			 const int64_t *frames, const double *tc, const double *mu_own);
/* The MA-TIRF section key ("matirf" or "baseline_matirf") of res, and the run's "z_nm". */
cJSON *c0_report_matirf(cJSON *rep, const char *key, const struct c0_angles *a, const struct c0_matirf_conf *m,
			const struct c0_matirf_result *res);
/* The MA-TIRF section j's depth readout: the columns' intensity-weighted
 * mean (the camera-grid baseline) or their single-depth fit, and its seconds. */
void c0_report_depth_readout(cJSON *j, int mean, double seconds);
/* "common_pattern" (stages/pattern.h), when it was evaluated (2 or more stacks). */
void c0_report_pattern(cJSON *rep, const struct c0_pattern_stats *ps);
/* The matirf command's additions: offset, background, PSF. */
void c0_report_matirf_raw(cJSON *j, const struct c0_matirf_raw *raw, const struct c0_matirf_result *res);
/* "bleaching": the mode, order, rate and factors. */
void c0_report_bleach(cJSON *rep, const struct c0_bleach_conf *bc, const struct c0_bleach_result *br, int n);
/* The run's "parameters": mode, grid, pooling, support stacks, PSF image. */
void c0_report_run_params(cJSON *rep, const struct c0_run_conf *c, const struct c0_stage_confs *s,
			  const struct c0_result *r, const int *only, int three_d);
/* The depth pooling's windows (fine pixels; 0: off) in the MA-TIRF section j;
 * strip_px the guided window's half-width across the structure (0: the whole square). */
void c0_report_pool(cJSON *j, int window_px, double range_nm, double strip_px, int guide_window_px);
/* The depth fit's weights (stages/depthfit.h): the noise model ns (NULL:
 * none made), used or not; block: the frame halves' block length (0: none). */
struct c0_depth_noise;
void c0_report_depth_noise(cJSON *j, const struct c0_depth_noise *ns, int used, int block);
