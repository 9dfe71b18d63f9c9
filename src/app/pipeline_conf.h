/* The run configuration into the stages' configs (pipeline_conf.c). */
#pragma once
#include "col0rme.h"
#include "stages/support.h"
#include "stages/intensity.h"
#include "stages/matirf.h"
#include "stages/bleach.h"
#include "stages/drift.h"
#include "optics/psffit.h"

struct c0_stage_confs {
	struct c0_support_conf support;
	struct c0_intensity_conf intensity;
	struct c0_matirf_conf matirf;
	double pool_nm;              /* depth pooling window (nm), 0: off */
	double pool_range_nm;        /* and its guide's depth range (nm), 0: the whole window */
	int pool_per_fwhm;           /* 1: pool_nm is C0_DEPTH_POOL_FWHM times the PSF's FWHM (depth_pool_nm -1) */
	struct c0_psf_fit psf;       /* with psf_fitted: the fit of psf_image */
	double psf_pixel_nm;         /* its calibration, 0 when it has none */
	int psf_fitted;
	struct c0_bleach_conf bleach; /* the acquisition's clock and the bleaching (c0_run_conf_bleach) */
	struct c0_drift_conf drift;   /* its correlations filtered by the support grid's PSF */
};

/* The MA-TIRF images' angles (deg) and gains (ngains 0: all 1), in the
 * order of the images the step is given. */
struct c0_angles {
	int n, ngains;
	double deg[C0_MAX_STACKS], gain[C0_MAX_STACKS];
};
/* The matirf command's raw images: the angles, what is subtracted from
 * every image, and the PSF width and background smoothness as given (the
 * report's). */
struct c0_matirf_raw {
	struct c0_angles angles;
	double offset, background;
	double psf_fwhm_nm, background_smooth;
};

/* The stages' configs from c at camera pixel size pixel_nm (fwhm_nm resolved,
 * intensity parameters checked). */
int c0_run_conf_stages(const struct c0_run_conf *c, double pixel_nm, struct c0_stage_confs *s);
/* The MA-TIRF config alone (no optics needed). */
void c0_run_conf_matirf(const struct c0_run_conf *c, struct c0_matirf_conf *m);
/* The bleaching step's config from c's acquisition options. */
void c0_run_conf_bleach(const struct c0_run_conf *c, struct c0_bleach_conf *bc);
/* The stages after the support at the data's PSF width fwhm_nm (fwhm_rule
 * data): the intensity grid, the default pool window and the support's
 * grid, whose covariances keep the stated width's lag. */
void c0_stage_confs_width(struct c0_stage_confs *s, double fwhm_nm);
/* c's angles and gains. */
void c0_run_conf_angles(const struct c0_run_conf *c, struct c0_angles *a);
/* The raw MA-TIRF path's options of c at pixel_nm: raw, and into m the PSF's
 * sd (psf_fwhm_nm) and the background's smoothness (checked). */
int c0_run_conf_matirf_raw(const struct c0_run_conf *c, double pixel_nm, struct c0_matirf_conf *m, struct c0_matirf_raw *raw);
/* One angle per stack of n, and one gain per stack or none. */
int c0_run_conf_angles_check(const struct c0_run_conf *c, int n);
/* Angles and gains against nimages, then the MA-TIRF config m. */
int c0_run_conf_matirf_check(const struct c0_run_conf *c, const struct c0_matirf_conf *m, int nimages);
