/* Automatic lambda for the support, from the noise of the data itself.
 *
 * The frames split into two interleaved halves whose covariances R_A, R_B
 * come from the same streaming pass. Their noise is independent, so
 * D = (A^T R_A - A^T R_B) / 2 has the noise of C = A^T R (all frames) and no
 * signal: its robust sd (from the lower quartile of |D| over the fine pixels)
 * is sigma_C. With lambda_noise (the run's default) the l1 solve runs at
 * kappa * sigma_C: a labelled structure is wider than a fine pixel, and the
 * pixels beside its axis, which hold a fraction of its variance, enter once
 * they stand above the noise (docs/defaults.md#lambda_rule). Where the
 * support grows across the structures (label_radius_nm R > 0) the growth
 * gives that width, and lambda stands kappa sigma_C above the correlation a
 * tube's width leaves beside its axis: c0_lambda_width_share times the
 * median correlation over the pixels above kappa sigma_C.
 * Otherwise (the peaks rule) a pixel enters the l1 support where its
 * correlation exceeds the threshold
 *   t = max(rho * q90, kappa * sigma_C),
 * q90 the 90th percentile of the correlation image C - s0 n over the pixels
 * above kappa * sigma_C: a fraction of the bright structure's typical level
 * (lambda_max, the brightest pixel, follows one bright spot: where the
 * emitters' brightness spreads widely a fixed fraction of it lost the dim
 * ones), and never within kappa noise sds of zero, where pure noise would
 * enter (the background specks of real, noisier stacks). For l1 that is the
 * first step: the solve then runs at the second step's lambda (below). CEL0
 * gets the first step's threshold on its l0 scale, lowered as measured:
 * lambda = gamma t^2 / (2 ||a||^2) (median column norm).
 * Measured in docs/defaults.md#lambda, with why held-out cross-validation and
 * the discrepancy principle were not kept. */
#pragma once
#include "ops/covariance.h"

/* The criterion curve: at lambda / lambda_max = c0_lambda_curve_rel(k) (l1 scale),
 * 10^(-4 + k / 8) for k < C0_LAMBDA_CURVE, the share of the fine pixels
 * whose correlation C - s0 n (signal) and whose halves' noise image
 * |C_A - C_B| / 2 (noise) lie above lambda (on tiles: over the interiors
 * that gave q90 and sigma_C). */
#define C0_LAMBDA_CURVE 33
double c0_lambda_curve_rel(int k);

/* The cross-validation path (stages/lambda_cv.c): at most this many
 * points, lambda / lambda_max = C0_LAMBDA_CV_TOP 2^(-k/2) */
#define C0_LAMBDA_CV_MAX 24

struct c0_lambda_result {
	double chosen_rel;    /* lambda / lambda_max for the solve on all frames */
	double noise_rel;     /* sigma_C / lambda_max (l1 scale) */
	double signal_rel;    /* q90 / lambda_max (l1 scale) */
	double median_rel;    /* the median over the same pixels / lambda_max */
	double width_share;   /* c0_lambda_width_share: the noise rule's floor is this times median_rel */
	double rho, kappa;
	int noise_bound;      /* 1 when kappa sigma_C set the threshold */
	int noise;            /* 1: the noise rule, lambda = kappa sigma_C (l1, lambda_noise) */
	int noise_tiles;      /* tiles whose interiors gave sigma_C (0: the whole image, one tile) */
	int second;           /* 1: chosen_rel is the second step's (l1) */
	double first_rel;     /* the rule's lambda / lambda_max, at which the first solve ran */
	double peak_rel;      /* median over that solve's peaks of x ||a||^2, / lambda_max */
	double peaks;         /* how many peaks */
	double seconds;
	double curve_signal[C0_LAMBDA_CURVE], curve_noise[C0_LAMBDA_CURVE];
	/* cross-validation (l1): chosen_rel from it when cv is 1 */
	int cv, cv_points, cv_min, cv_pick;   /* points on the path, the criterion's least, the chosen */
	double cv_rel[C0_LAMBDA_CV_MAX], cv_err[C0_LAMBDA_CV_MAX];  /* lambda / lambda_max, error / error at x = 0 */
	double cv_se[C0_LAMBDA_CV_MAX];   /* standard error of err - least (same units), up to the chosen */
	int cv_iters;                 /* iterations per point and half */
	double cv_seconds;
	/* c0_lambda_psf_fwhm of the halves, or on tiles with fwhm_data of the band (nm; 0: not measured) */
	double fwhm_data_nm;
};

/* The FWHM (nm) of the Gaussian PSF whose pixel-integrated autocorrelation
 * has the covariance's ratio of lag 2 to lag 1 (summed over the image, x
 * and y): the width the data say, whatever the structure (lambda_psf.c).
 * more (or NULL): another covariance of the same field (the other half of
 * the frames) whose sums add. Refused when the band has no lag 2 or the
 * ratio fits no width. */
int c0_lambda_psf_fwhm(const struct c0_cov *cov, const struct c0_cov *more, double pixel_nm, double *fwhm_nm);
/* The same from the sums of lags 1 and 2 (x and y): s[0], s[1]; and row y's
 * share of them in cov (added to s), for sums over tiles and processes. */
int c0_lambda_psf_fwhm_sums(const double s[2], double pixel_nm, double *fwhm_nm);
void c0_lambda_psf_row_sums(const struct c0_cov *cov, int y, double s[2]);
/* The run's warning when the data's FWHM and the given one differ by more
 * than this share (the simulator's Gaussian stacks read within 2 %, its Airy
 * disk of the same FWHM 7 % narrower; docs/defaults.md#fwhm_rule) */
#define C0_LAMBDA_PSF_WARN 0.05

struct c0_support_conf;
/* The share of a straight tube's correlation (C across it) that its width
 * leaves beside its axis once l1 has put it on one fine pixel: a tube of
 * radius R labelled on its surface spreads its emitters w^2 = R^2 / 2
 * across the axis; C across a line is a Gaussian of variance s^2 = sigma^2
 * + p^2 / 12 (the PSF's and the camera pixel's), and the tube's is the
 * line's widened by w^2. A pixel beside the axis enters the l1 support while
 * lambda is below (w^2 / s^2) C_axis to second order in w / s, whatever its
 * distance. 0 when R is 0. */
double c0_lambda_width_share(const struct c0_support_conf *c);
/* Uses c's optics, lag and penalty. */
int c0_lambda_auto(const struct c0_support_conf *c, const struct c0_cov *a, const struct c0_cov *b,
		   struct c0_lambda_result *out);

/* The second step (l1): the rule's threshold is a fraction of the
 * structure's correlation, which sums the emitters under the PSF, so it
 * follows their density; the best lambda follows one emitter's variance
 * (docs/defaults.md#lambda). A first solve at the rule's lambda resolves the
 * structure into peaks: fine pixels with x > 0 and no larger x among their
 * 8 neighbours. At a peak, x ||a||^2 is the correlation an emitter of
 * variance x gives, and lambda = C0_LAMBDA_PEAK_SHARE times its median over
 * the peaks, never below kappa sigma_C, is the l1 solve's. */
#define C0_LAMBDA_PEAK_SHARE 0.28
/* Adds to hist (C0_LAMBDA_BINS counts) x ||a||^2 of the peaks of a solve's
 * rx (camera units; x = rx / norm) on the fine grid of a window Ny x Nx
 * camera pixels, over its interior (camera pixels iy, ix, ih, iw). */
int c0_lambda_peaks(const struct c0_support_conf *c, const float *rx, double norm, int Ny, int Nx, int iy, int ix,
		    int ih, int iw, double *hist);
/* The second step from the peaks' histogram and the first solve's
 * lambda_max: out->chosen_rel becomes its lambda (kept when there is no peak). */
void c0_lambda_second(const double *hist, double lmax, struct c0_lambda_result *out);

/* The l1 lambda by symmetric covariance cross-validation (DESIGN.md §8):
 * each half of the frames (a: even, b: odd) is solved along a path of
 * decreasing lambda, C0_LAMBDA_CV_TOP 2^(-k/2) lambda_max, warm started,
 * every point with the same iteration budget; the support of each is
 * refitted without penalty, and predicts the other half's off-diagonal
 * covariance (lags != 0, where the noise variance is absent); the two
 * squared errors are summed. The path stops C0_LAMBDA_CV_PATIENCE points
 * after its least. The choice is the largest lambda whose error exceeds the
 * least by no more than its standard error, from the paired differences
 * over blocks of lag x lag camera pixels (the one-standard-error rule: the
 * curve is flat near its least, within 1e-4 of it over a factor 4 of
 * lambda, and its noise would otherwise pick). Sets out's cv fields and
 * chosen_rel (relative to the halves' mean's lambda_max, as c0_lambda_auto). */
#define C0_LAMBDA_CV_TOP 0.1
#define C0_LAMBDA_CV_ITERS 100
#define C0_LAMBDA_CV_REFIT 50
#define C0_LAMBDA_CV_PATIENCE 2
/* The path starts at its first point at most C0_LAMBDA_CV_START times the
 * rule's first step (out->chosen_rel on entry; the choice was at most 2.3
 * times it on the panel), and the whole's lambda is the halves' choice
 * times C0_LAMBDA_CV_WHOLE (each half's covariance has twice the noise
 * variance; lambda follows the noise sd). */
#define C0_LAMBDA_CV_START 4.0
#define C0_LAMBDA_CV_WHOLE 0.70710678118654752
/* On tiles (an interior given) each path runs at least this many points:
 * the sums stop at the shortest tile's path, which could end before the
 * least of the sum (down to 1/4 of the rule's first step) */
#define C0_LAMBDA_CV_TILE_POINTS 9
int c0_lambda_cv(const struct c0_support_conf *c, const struct c0_cov *a, const struct c0_cov *b,
		 struct c0_lambda_result *out);
/* Its pieces, for tiles. The path point k's lambda / lambda_max; the sums
 * one window gives (all doubles, so that windows and ranks add them): the
 * errors, their paired differences' sums and squares over the blocks
 * (s1[k][q], s2[k][q]: of err_k - err_q), the error of x = 0, the blocks
 * and the points; one window's path (halves a, b; norm and lmax the
 * image's, or 0: the halves' own; the errors over the camera pixels of
 * interior = { y, x, h, w } in the window, NULL: all); the choice from such
 * sums. */
double c0_lambda_cv_rel(int k);
int c0_lambda_cv_first(double rule_rel);
struct c0_lambda_cv_sums {
	double err[C0_LAMBDA_CV_MAX], s1[C0_LAMBDA_CV_MAX][C0_LAMBDA_CV_MAX], s2[C0_LAMBDA_CV_MAX][C0_LAMBDA_CV_MAX];
	double e0, nb, npts;
};
int c0_lambda_cv_window(const struct c0_support_conf *c, const struct c0_cov *a, const struct c0_cov *b, double norm,
			double lmax, int k0, const int *interior, struct c0_lambda_cv_sums *v);
void c0_lambda_cv_choose(const struct c0_lambda_cv_sums *v, int k0, struct c0_lambda_result *out);

/* The tiled path (stages/support_tiles.c), where the band of the whole image is
 * kept for all frames, and the halves only for some tiles' windows.
 * A tile's lambda_max on the l1 and the l0 scale (lmax[0], lmax[1]) as its
 * solve finds it (normalisation norm); with hist, the correlation image over
 * its interior (camera pixels iy, ix, ih, iw inside the window) is added to
 * hist's third part. */
int c0_lambda_tile_max(const struct c0_support_conf *c, const struct c0_cov *all, double norm, int iy, int ix, int ih,
		       int iw, double lmax[2], double *hist);
/* One half's correlation image *C = A^T R (fine grid of its window), so
 * that the two halves' bands need not be held at once; with n, also the
 * column norms ||a||^2 there (both allocated). */
int c0_lambda_tile_corr(const struct c0_support_conf *c, const struct c0_cov *half, double **C, double **n);
/* A tile's halves (even, odd frames; their correlation images ca, cb and
 * the column norms n on the fine grid of a window W camera pixels wide):
 * |C_a - C_b| / 2 and the column norms over its interior (camera pixels iy,
 * ix, ih, iw inside the window) added to hist's first two parts. hist:
 * C0_LAMBDA_HIST counts in fixed log bins, so that sums over tiles and ranks
 * are exact and their quantiles do not depend on who computed what. */
#define C0_LAMBDA_BINS 14000
#define C0_LAMBDA_HIST (3 * C0_LAMBDA_BINS)
void c0_lambda_tile_noise(const struct c0_support_conf *c, const double *ca, const double *cb, const double *n, int W,
			  double norm, int iy, int ix, int ih, int iw, double *hist);
/* The rule from the summed histograms and the image's lambda_max (l1, l0 scale). */
void c0_lambda_tiles_choose(const struct c0_support_conf *c, const double *hist, double lmax, double lmax0,
			    struct c0_lambda_result *out);
