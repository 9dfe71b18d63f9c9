/* The whole method as one call (include/col0rme.h), and the steps it is
 * made of, which the single-step commands use too: each step adds its
 * arrays and its part of the report to a c0_result, and c0_result_write
 * writes whatever the result holds. */
#pragma once
#include "col0rme.h"
#include "stages/support.h"
#include "stages/intensity.h"
#include "stages/matirf.h"
#include "stages/drift.h"
#include "stages/bleach.h"
#include "stages/depthpool.h"
#include "optics/psffit.h"
#include "io/frames.h"
#include "io/outdir.h"
#include "io/report.h"

struct c0_stage_confs {
	struct c0_support_conf support;
	struct c0_intensity_conf intensity;
	struct c0_matirf_conf matirf;
	double pool_nm;              /* depth pooling window (nm), 0: off */
	double pool_range_nm;        /* and its guide's depth range (nm), 0: the whole window */
	struct c0_psf_fit psf;       /* with psf_fitted: the fit of psf_image */
	double psf_pixel_nm;         /* its calibration, 0 when it has none */
	int psf_fitted;
};

/* The stages' configs from c at camera pixel size pixel_nm (fwhm_nm resolved,
 * intensity parameters checked). */
int c0_run_conf_stages(const struct c0_run_conf *c, double pixel_nm, struct c0_stage_confs *s);
/* The MA-TIRF config alone (no optics needed). */
void c0_run_conf_matirf(const struct c0_run_conf *c, struct c0_matirf_conf *m);
/* The bleaching step's config from c's acquisition options. */
void c0_run_conf_bleach(const struct c0_run_conf *c, struct c0_bleach_conf *bc);
/* Angles and gains against nimages, then the MA-TIRF config m. */
int c0_run_conf_matirf_check(const struct c0_run_conf *c, const struct c0_matirf_conf *m, int nimages);

struct c0_result {
	cJSON *rep;                  /* the report, filled step by step */
	char *json;                  /* its text, made on demand */
	int n;                       /* stacks */
	char (*names)[256];          /* n: path or "array N" (report, messages) */
	const char *paths[C0_MAX_STACKS]; /* into names where a stack is a file, else NULL (outdir check) */
	double pixel_nm;             /* camera pixel size */
	int srf;
	int nsup, sup[C0_MAX_STACKS];/* support step: its stacks (0-based) and results */
	struct c0_support_result *sres;
	uint8_t *mask;               /* Ly x Lx union of the supports (or the given mask) */
	int Ly, Lx;
	struct c0_intensity_result *ires; /* n, after the intensity step */
	float *mean;                 /* n planes of the camera grid: each stack's temporal mean (intensity step) */
	float **corrected;           /* n temporal means minus background, for the baseline */
	struct c0_matirf_result vol, base;
	double bleach_factor[C0_MAX_STACKS]; /* each stack's intensity is divided by this before MA-TIRF (1: none) */
	double vol_pixel_nm, z0_nm, dz_nm;
	cJSON *timings;
	struct c0_drift *drift;      /* after the drift step: the trajectory, and each stack's frame hook */
	void *hooks[C0_MAX_STACKS];
	double render_sd_nm;         /* after the render step (0 before): its Gaussian, */
	float render_lo, render_hi;  /* and the range of its values */
	float *render;               /* n planes Ly x Lx, made when the library's caller first asks (c0_result_render) */
	/* the intensities on the support alone (x is 0 off it), from the
	 * intensity step: the union mask's pixels pl and stack q's values xs[q]
	 * over them; ires[q].x is then NULL until the library's caller asks for
	 * it (c0_result_intensity). A stack whose x is not 0 off the mask keeps x. */
	struct c0_pixlist pl;
	float *xs[C0_MAX_STACKS];
	/* with the intensity conf's noise_block: the intensity of the difference of
	 * stack q's two block halves' means, scaled to the whole stack, over pl (a
	 * draw of xs[q]'s noise), else NULL */
	float *xnoise[C0_MAX_STACKS];
	double fwhm_stated_nm, fwhm_data_nm, fwhm_nm; /* the PSF width given, the covariance's (0: none), used (support step) */
	float *cal_offset, *cal_scale, *cal_noise; /* the camera calibration (app/calib.c), NULL without */
	float *cal_noise_q[C0_MAX_STACKS];        /* cal_noise as each stack's drift-corrected frames see it (NULL: as it is) */
	/* vol and base on the whole grid, made when the library's caller first
	 * asks for them (c0_result_volume): the run holds only their columns */
	float *vol_dense, *base_dense;
};

/* Rows y0..y1 of stack q's intensity (fine grid) into buf ((y1 - y0) x Lx),
 * from x or from xs; its value at pl's pixel k; its sum in raster order. */
void c0_result_x_rows(const struct c0_result *r, int q, int y0, int y1, float *buf);
float c0_result_x_at(const struct c0_result *r, int q, size_t k);
double c0_result_x_sum(const struct c0_result *r, int q);
/* A step's bookkeeping: its name for the out-of-memory message while it
 * runs (c0_mem_stage), then in the report its wall seconds (timings_s), the
 * peak resident memory so far (peak_rss_mb) and how much the step raised
 * that peak (rss_rise_mb; 0: it stayed below an earlier step's). */
struct c0_step_clock { const char *key; double t0, peak0; };
struct c0_step_clock c0_step_begin(const char *key);
void c0_step_end(struct c0_result *r, const struct c0_step_clock *k);
/* An empty result for command (the report's "command"), n stacks named. */
int c0_result_new(const char *command, int n, const char *const *names, const int *is_file, struct c0_result **out);
/* Adds one line to the report's "warnings" (the CLI prints them). */
void c0_result_warn(struct c0_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Records the command line in the report. */
void c0_result_set_argv(struct c0_result *r, int argc, char **argv);
/* Opens the stacks as frame sources, all the same size. */
int c0_stacks_open(const struct c0_stack *s, int n, struct c0_frames *f);
void c0_stacks_close(struct c0_frames *f, int n);
/* The camera pixel size: c->pixel_nm (>= 0, finite), else the stacks'
 * calibration, which must be the same for all n. */
int c0_stacks_pixel(const struct c0_run_conf *c, const struct c0_frames *f, int n, double *pixel_nm);
/* Every stack against the support config (size against the PSF band, frames). */
int c0_stacks_check(const struct c0_support_conf *sc, const struct c0_frames *f, int n);
/* The camera calibration maps of c (offset_map, variance_map, gain_map):
 * read and checked against f (size, values, the offset map's region),
 * attached to the frames and sc's support, owned by r. */
int c0_calib_attach(const struct c0_run_conf *c, struct c0_frames *f, int n, struct c0_stage_confs *sc, struct c0_result *r);
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

/* Drift over all n stacks of f on c's acquisition clock, correlations
 * filtered by g's PSF (stages/drift.h); the later steps undo it frame by frame. */
int c0_step_drift(struct c0_result *r, const struct c0_run_conf *c, const struct c0_grid *g, struct c0_frames *f, int n);
/* Support of stacks r->sup[0..nsup) (indices into f); sets the union mask. */
int c0_step_support(struct c0_result *r, const struct c0_support_conf *sc, struct c0_frames *f);
/* Intensity and background of every stack on r->mask: the support step's
 * mean and noise variance where it ran on the stack, else one pass (the
 * mean when sigma2[i] > 0, else the covariance, for the noise variance on
 * the mask). With corrected, keeps each mean minus its background. With
 * share (NULL or one flag per stack, and mu not given), the flagged stacks
 * get one mu, the largest of their discrepancy ones. */
int c0_step_intensity(struct c0_result *r, const struct c0_intensity_conf *ic, const struct c0_support_conf *sc,
		      struct c0_frames *f, const double *sigma2, int corrected, const int *share);
/* MA-TIRF volume from nq images (ny x nx at pixel_nm) into r->vol, or
 * r->base with baseline; pool (or NULL): the pixels' own and pooled
 * intensities when img are pooled (stages/depthpool.h). */
struct c0_pooled;
int c0_step_matirf(struct c0_result *r, const struct c0_run_conf *c, const struct c0_matirf_conf *m,
		   const float *const *img, const struct c0_pooled *pool, int ny, int nx, double pixel_nm, int baseline);
/* render: each intensity splatted with a Gaussian of the support's
 * localisation precision (at least half a fine pixel; stages/splat.h). */
int c0_step_render(struct c0_result *r);
/* Plane q of the render (Ly x Lx) into plane, after the render step. */
int c0_render_plane(const struct c0_result *r, int q, float *plane);
/* The standard MA-TIRF path on raw images (the matirf command): c's offset
 * and constant background subtracted (from copies; refused at or above an
 * image's mean), optional joint background estimation and deconvolution,
 * then c0_step_matirf into r->vol. */
int c0_step_matirf_raw(struct c0_result *r, const struct c0_run_conf *c, const struct c0_matirf_conf *m,
		       const float *const *img, int ny, int nx, double pixel_nm);
/* Bleaching across the stacks (stages/bleach.h) from c: the fade estimated
 * from the frame sums and the fitted backgrounds (or the known factors, or
 * none) into r->bleach_factor and rep["bleaching"]. */
int c0_step_bleach(struct c0_result *r, const struct c0_run_conf *c, struct c0_frames *f);
/* The intensity step alone on the stacks, on the support mask in the TIFF
 * support (fine grid), with c's noise variances when given (one per stack). */
int c0_run_intensity_files(const struct c0_run_conf *c, const struct c0_stack *stacks, int n, const char *support,
			   struct c0_result **out);
/* The standard MA-TIRF path on one 2D TIFF image per angle (paths[0..n)). */
int c0_run_matirf_files(const struct c0_run_conf *c, char *const *paths, int n, struct c0_result **out);
/* The one warning of an MA-TIRF run that left wavelength_nm or n_sample at its default. */
void c0_warn_assumed_optics(struct c0_result *r, const struct c0_run_conf *c);
/* Writes what r holds into an open output directory. */
int c0_result_write_to(const struct c0_result *r, struct c0_outdir *out);
