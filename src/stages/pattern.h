/* The fixed pattern the angles' stacks share: an sCMOS camera's per-pixel
 * dark levels (its offset map), when no map is given. One acquisition's
 * stacks are read by the same pixels, so whatever their intensity fits leave
 * in every stack alike is the camera's, not the sample's, whose light
 * changes with the angle. Estimated from the fits' residuals
 * r_q = ybar_q - (Psi_Omega x_q + b_q): their median over the stacks, shrunk
 * towards 0 by how much of it the stacks share. The shared variance c is
 * read far from the support (beyond 2 FWHM of every support pixel), where
 * the residuals hold the pattern and each stack's own noise: c is the mean
 * covariance of two stacks' residuals there. Each class of pixels (on the
 * support, near it, far) keeps the median times k = min(1, c / its variance
 * over the class): the Wiener factor of a pattern of variance c seen through
 * the class's noise and misfit. Used only where the support's k >= 1/2 (the
 * estimate's error is then smaller than the pattern it removes; on CCD and
 * EMCCD stacks k is 0.1-0.2 on the support, docs/defaults.md#common_pattern). */
#pragma once
#include "optics/grid.h"
#include "col0rme.h"   /* C0_MAX_STACKS */

#include <stdint.h>

struct c0_pattern_stats {
	int stacks;             /* residuals used */
	int far_pixels;         /* camera pixels beyond 2 FWHM of the support */
	double common_var;      /* c: the stacks' shared variance far from the support, ADU^2 */
	double k_on, k_near, k_far;  /* the shrink factors of the three classes */
	int applied;            /* k_on >= 1/2 (pat is 0 otherwise) */
	/* the caller's, where a drift correction moved the frames: */
	int camera_frame;       /* 1: estimated in the camera's frame, 0: the sample's */
	double common_var_other;/* the shared variance in the other frame, ADU^2 (0: not evaluated) */
};

/* Residual ybar - (Psi_Omega x + b) on the camera grid (H x W), for n
 * stacks: x[q] holds the mask's values in raster order (the fine grid of
 * srf g->srf), b[q] the background. res: n arrays of H x W. */
int c0_pattern_residuals(const struct c0_grid *g, int n, const double *const *ybar, const float *const *x, const float *const *b,
			 int H, int W, const uint8_t *mask, double **res);
/* The pattern pat (H x W) from n >= 2 residuals; pat is 0 and s->applied 0
 * when the rule above does not apply. */
int c0_pattern_estimate(const struct c0_grid *g, int n, const double *const *res, int H, int W, const uint8_t *mask, float *pat,
			struct c0_pattern_stats *s);
