/* A run's result, filled step by step, and its accessors (result.c). */
#pragma once
#include "col0rme.h"
#include "stages/support.h"
#include "stages/intensity.h"
#include "stages/matirf.h"
#include "stages/drift.h"
#include "stages/depthpool.h"
#include "io/report.h"

struct c0_result {
	cJSON *rep;                  /* the report, filled step by step */
	char *json;                  /* its text, made on demand */
	int n;                       /* stacks */
	char (*names)[256];          /* n: path or "array N" (report, messages) */
	const char *paths[C0_MAX_STACKS]; /* into names where a stack is a file, else NULL (outdir check) */
	double pixel_nm;             /* camera pixel size */
	int srf;
	int nsup, sup[C0_MAX_STACKS];/* support step: its stacks (0-based) and results */
	int npool, pool[C0_MAX_STACKS];/* the stacks pooled into sres[0] (nsup 1, sup[0] = pool[0]); 0: none */
	struct c0_support_result *sres;
	uint8_t *mask;               /* Ly x Lx union of the supports (or the given mask) */
	int Ly, Lx;
	struct c0_intensity_result *ires; /* n, after the intensity step */
	float *mean;                 /* n planes of the camera grid: each stack's temporal mean (intensity step) */
	float **corrected;           /* n temporal means minus background, for the baseline */
	struct c0_matirf_result vol, base;
	double bleach_factor[C0_MAX_STACKS]; /* each stack's intensity is divided by this before MA-TIRF (1: none) */
	double bleach_tau[C0_MAX_STACKS];    /* each stack's frames' mean time on the acquisition clock (frames) */
	double bleach_k_sd;                  /* the fitted fade rate's sd (NAN: not estimated from the stacks) */
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
/* An empty result for command (the report's "command"), n stacks named. */
int c0_result_new(const char *command, int n, const char *const *names, const int *is_file, struct c0_result **out);
/* Adds one line to the report's "warnings" (the CLI prints them). */
void c0_result_warn(struct c0_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Records the command line in the report. */
void c0_result_set_argv(struct c0_result *r, int argc, char **argv);
/* 1: the frames were moved by a drift correction */
int c0_result_drift_moved(const struct c0_result *r);
/* the read-noise map stack i's frames see (NULL: no map) */
const float *c0_result_noise(const struct c0_result *r, int i);
