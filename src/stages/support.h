/* COL0RME support estimation: sparse fine-grid emitter variances r_x from
 * the banded covariance of a stack, with the noise variance in closed form.
 *   min_{x >= 0, s >= 0}  1/2 ||R - Psi diag(x) Psi^T - s I||_F^2 + pen(x)
 * R normalised by its largest pixel variance; pen = lam ||x||_1 or CEL0(lam). */
#pragma once
#include "ops/covariance.h"
#include "solve/fista.h"
#include "stages/lambda.h"
#include "eval/frc.h"
#include "io/frames.h"
#include "optics/grid.h"

#include <stdint.h>

#include "col0rme.h"   /* enum c0_penalty */

/* Per-frame preprocessing in the streaming passes (drift correction): frame
 * t (0-based in its stack, H x W) is changed in place before it is used. */
typedef int (*c0_frame_fn)(void *ctx, int64_t t, float *frame, int H, int W);

struct c0_support_conf {
	struct c0_grid grid;       /* pixel_nm, fwhm_nm required; srf 4 */
	enum c0_penalty penalty;   /* l1 */
	double lambda_rel;         /* lambda / lambda_max; 0: automatic (stages/lambda.h) when the stack is
				    * streamed, else the penalty's fixed default (c0_support_default_lambda) */
	int lag;                   /* covariance lag radius in pixels; 0: ceil(6 sigma / p) */
	struct c0_fista_conf fista;/* 2000 iterations; tol -1: the solver's (c0_support_tol) */
	int cel0_outer;            /* 10 reweightings */
	enum c0_support_solver solver; /* l1: fista (the whole grid's step) or pruned (the working set's) */
	int frc;                   /* 1: also solve each half of the frames (on its own, at most 300
				    * iterations) for the localisation precision and the FRC curve */
	int tile;                  /* tile side in camera pixels; 0: C0_SUPPORT_TILE (or the image when smaller) */
	c0_frame_fn frame_fn;      /* NULL: frames as read */
	void *frame_ctx;
	int guard;                 /* 1: streamed covariances clip each pixel's variance (c0_cov_guard
				    * with c0_support_guard_ratio) */
	const float *noise_map;    /* NULL, or the stack's H x W: subtracted from each pixel's variance before
				    * the guard (c0_cov_acc_set_noise; the camera's read noise made even) */
	int noise_map_w;           /* its width (the stack's) */
	int lambda_cv;             /* automatic l1 lambda: 1 by cross-validation of the frame halves
				    * (c0_lambda_cv), else: */
	int lambda_noise;          /* 1: kappa sigma_C alone (stages/lambda.h); 0: the peaks of a first
				    * solve (the second step) */
	int fwhm_data;             /* 1: where the covariance's PSF width (c0_lambda_psf_fwhm) differs from
				    * grid.fwhm_nm by more than C0_LAMBDA_PSF_WARN, the solves use it */
	double label_radius_nm;    /* 15; 0: the support is the l1 solve's; > 0: the labelled structures' radius
				    * about their axis, and the support grows across their ridges to it
				    * (support_solve.c) */
};
#define C0_SUPPORT_DEFAULTS { { 0, 0, 4 }, C0_PENALTY_L1, 0, 0, { C0_FISTA_MAXIT, -1 }, 10, C0_SUPPORT_FISTA, 1, 0, NULL, NULL, 1, NULL, 0, 0, 1, 0, 15 }
/* g of c0_cov_guard for this PSF: the smallest mean ratio of a point
 * source's signal in a pixel's 4 neighbours to its signal in the pixel,
 * over positions in and around the pixel (0.6 at 229 nm / 100 nm). */
double c0_support_guard_ratio(const struct c0_support_conf *c);
/* The iteration caps: fista's is part of the estimator (its capped iterate
 * matched the simulated truth better than the minimiser, docs/defaults.md#support_solver);
 * pruned's is a safety net (it stops on converging, 3300-5300 at 256 tiles). */
#define C0_FISTA_MAXIT 2000
#define C0_PRUNED_MAXIT 10000
/* The tolerance a solve uses: c->fista.tol, or when that is -1 the
 * solver's own: 0 for fista on l1 (every iteration up to the cap: a stop on
 * the relative change came at 1100-1800 iterations and moved with lambda by
 * 20 % of the support, docs/defaults.md#tol), C0_SUPPORT_TOL for pruned and
 * CEL0, which stop on converging (and for c0_support_noise_solve). */
#define C0_SUPPORT_TOL 1e-5
double c0_support_tol(const struct c0_support_conf *c);
/* Default tile side (docs/defaults.md#tile): tiles are solved side by side and
 * overlap by two covariance lags on each side. */
#define C0_SUPPORT_TILE 256

struct c0_support_result {
	int Ly, Lx, lag, nlag;
	int64_t frames;
	uint8_t *mask;             /* Ly x Lx, 1 where r_x > 0 and where the support grew (label_radius_nm) */
	float *rx;                 /* Ly x Lx, emitter variance in camera units^2 */
	double *mean;              /* Ny x Nx temporal mean of the stack */
	double sigma2;             /* noise variance, camera units^2 */
	double lambda, lambda_max; /* in normalised covariance units */
	double norm;               /* normalisation: largest pixel variance */
	int iters, converged, support_pixels;
	double gap;                /* l1: relative duality gap at the end, (P - D) / P */
	double *hist;              /* objective per iteration */
	int nhist;
	double t_cov, t_solve;     /* seconds */
	int lambda_auto;           /* lambda chosen from the data (stages/lambda.h): */
	struct c0_lambda_result cv;/* its inputs and time */
	struct c0_frc frc;         /* of the emitter variances of the two halves (fine grid), with frc */
	double t_frc;              /* seconds of the half solves, their FRC and the precision */
	double precision_nm;       /* localisation sd per axis from the halves' supports (c0_pair_precision),
				    * for all frames (the halves' / sqrt 2); -1: unknown */
	int tiles, tile;           /* tile count and side (camera pixels) */
	double fwhm_nm;            /* the PSF FWHM the solves used (nm): grid.fwhm_nm, or the data's with fwhm_data */
};

int c0_support_check(const struct c0_support_conf *c, int W, int H, int64_t frames, const char *name);
int c0_support_lag(const struct c0_support_conf *c);
/* Solve at the PSF width fwhm_nm from now on, the covariance keeping the
 * lag of the width c had (the data's width replacing the stated one). */
void c0_support_set_width(struct c0_support_conf *c, double fwhm_nm);
/* Measured on simulated filaments (docs/history/support.md): l1 1e-2, cel0 3e-5.
 * The two differ because CEL0's lambda_max is on the l0 scale. */
double c0_support_default_lambda(enum c0_penalty p);
/* Streams the stack once for the covariance of every tile and its two
 * interleaved halves (for the automatic lambda and the FRC), each process
 * reading its rows only, then solves the tiles side by side and keeps
 * their interiors. sigma2: the tiles' noise variances averaged over their
 * interiors; iters: the most of any tile; converged: every tile did;
 * the objective: the tiles' summed in tile order. With one tile (images up
 * to the tile size) this is the plain whole-image solve, which every
 * process then makes alone. Under MPI the result is complete on rank 0,
 * and the same on any number of processes. */
int c0_support_stack(const struct c0_support_conf *c, struct c0_frames *f, struct c0_support_result *res);
/* The support of n stacks of one field (MA-TIRF angles: one sample, the
 * same emitters) from their covariances pooled: each stack's about its own
 * mean and trend, weighted by its degrees of freedom (ops/covpool.h; on
 * tiles, a segment of the bands each, c0_cov_acc_next). c[q] is stack q's
 * configuration, the same but for its frame hook and noise map; c[0]'s
 * decides the rest. The emitter variances are then the stacks' mean ones,
 * and sigma2 their pooled noise variance, not any one stack's. n = 1 is
 * c0_support_stack. */
int c0_support_stacks(const struct c0_support_conf *c, struct c0_frames *in, int n, struct c0_support_result *res);
/* Solves from a finished covariance (which is left unchanged). */
int c0_support_solve(const struct c0_support_conf *c, const struct c0_cov *cov, struct c0_support_result *res);
void c0_support_result_free(struct c0_support_result *r);
/* The tile side used for a WxH image. */
int c0_support_tile_size(const struct c0_support_conf *c, int W, int H);
/* One streaming pass: banded covariance (lag from the PSF) and temporal mean. */
int c0_stack_covariance(const struct c0_support_conf *c, struct c0_frames *f, struct c0_cov *cov, double *seconds);
/* The same pass, even frames into half[0], odd into half[1]. */
int c0_stack_covariance_halves(const struct c0_support_conf *c, struct c0_frames *f, struct c0_cov half[2],
			       double *seconds);
/* One streaming pass for the temporal mean only (allocated), when the noise
 * variance is already known and the covariance is not needed. */
int c0_stack_mean(const struct c0_support_conf *c, struct c0_frames *f, double **mean, int64_t *frames,
		  double *seconds);
/* The means of a stack's two block halves: the frames whose block of
 * `block` frames has an even number (t / block even) into half 0, the
 * others into half 1. Blocks longer than a blink keep the halves' blinking
 * apart, which alternate frames share (docs/defaults.md#depth_noise_block). Summed by a
 * frame hook that wraps another (fn, ctx; NULL: none), so that a pass made
 * for something else sums them too: set c0_block_halves_fn with the struct
 * as the conf's hook; finish gives the means (allocated, float), both NULL
 * when a half has no frame, and frees the sums. */
struct c0_block_halves {
	c0_frame_fn fn;
	void *ctx;
	int block;
	size_t n;                  /* pixels a frame */
	double *sum[2];
	int64_t count[2];
};
int c0_block_halves_init(struct c0_block_halves *h, int block, size_t n, c0_frame_fn fn, void *ctx);
int c0_block_halves_fn(void *ctx, int64_t t, float *frame, int H, int W);
int c0_block_halves_finish(struct c0_block_halves *h, float *half[2], int64_t count[2]);
/* One streaming pass for them alone (count[k] frames each; none under 2
 * blocks). */
int c0_stack_block_means(const struct c0_support_conf *c, struct c0_frames *f, int block, float *half[2],
			 int64_t count[2], double *seconds);
/* Noise variance of a stack whose support is known: the same model with
 * r_x free on the mask only and no penalty (100 iterations), in one pass on
 * the support's tile grid (memory: the float band of the frame and one
 * window's covariance per thread): each tile's noise variance from its
 * window, averaged over the interiors (one tile: the whole image's fit).
 * Also the temporal mean (allocated). */
int c0_stack_noise(const struct c0_support_conf *c, struct c0_frames *f, const uint8_t *mask, double **mean,
		   int64_t *frames, double *sigma2, double *seconds);
/* One window's part of it: the fit on the mask (L = H r x W r fine pixels),
 * res->sigma2 its noise variance (c->fista.maxit iterations, l1 scale). */
int c0_support_noise_solve(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *mask,
			   struct c0_support_result *res);
