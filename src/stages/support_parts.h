/* The support step's pieces that its files share (support.c: the
 * configuration and the per-stack phases, support_solve.c: one window's
 * solve, support_stream.c: the passes over the frames, support_tiles.c:
 * the loops over tiles, lambda.c); not for other stages. */
#pragma once
#include "stages/support_util.h"
#include "ops/covop.h"

/* A tile solves with the whole image's normalisation and lambda, so that
 * every tile answers the same question. */
struct c0_support_scale {
	double norm;     /* largest pixel variance of the image */
	double lam;      /* absolute lambda (normalised units) */
};

/* The halves' solves for the FRC and the precision stop at this many
 * iterations. */
#define C0_SUPPORT_FRC_MAXIT 300
/* c for the halves' solves: at most C0_SUPPORT_FRC_MAXIT iterations, and
 * no label radius (the precision matches the solves' own pixels) */
struct c0_support_conf c0_support_halves_conf(const struct c0_support_conf *c);

/* The covariance operator on cov's window for c's optics. */
int c0_support_covop(const struct c0_support_conf *c, const struct c0_cov *cov, struct c0_covop *op);
/* C = A^T R of cov (not normalised), *trR = tr(R) / norm, and lambda_max
 * on the l1 and the l0 scale (c0_lambda_max) at normalisation norm. */
void c0_support_correlate(struct c0_covop *op, const struct c0_cov *cov, double norm, double *C, double *trR,
			  double lm[2]);
/* One window's solve. mask (or NULL): lambda = 0 with x free on the mask
 * only; band (or NULL): &cov->r, freed once read; g (or NULL): the image's
 * scale, else the window's own normalisation and lambda. */
int c0_support_window_solve(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *mask,
			    double **band, const struct c0_support_scale *g, struct c0_support_result *res);

/* The l1 solve of ctx at ctx->lam from x as it is (a warm start), with c's
 * solver and tolerance and at most maxit iterations (the automatic lambda's
 * path, stages/lambda_cv.c); *iters: how many it made. */
struct c0_covfit;
int c0_support_l1_warm(const struct c0_support_conf *c, struct c0_covfit *ctx, int maxit, double *x, int *iters);
/* x refitted without penalty on its own support (x > 0), from x, at most
 * maxit iterations (tolerance C0_SUPPORT_TOL). */
int c0_support_refit(struct c0_covfit *ctx, int maxit, double *x);

/* One process's share of a tiled stack (c0_support_stack): the tile grid,
 * its tiles [k0, k1), the rows its windows read [ya, yb) and its interiors
 * cover [ia, ib); the band of all frames over those rows (acc, from row ya)
 * and, for the automatic lambda and the FRC, the odd frames' band of each
 * of its tiles in the noise subset sub (odd[k - k0], else NULL). With
 * several stacks pooled (each a segment of the bands, c0_cov_acc_next) the
 * even frames have bands of their own too (even, else NULL). */
struct c0_support_share {
	struct c0_tiling tl;
	int k0, k1, ya, yb, ia, ib;
	struct c0_cov_acc *acc;
	struct c0_cov_acc **odd, **even;
	uint8_t *sub;
};
/* The one pass over each stack's frames for the share (c[q], in[q], q < n,
 * one segment each), each process reading only its rows. */
int c0_support_stream_tiles(const struct c0_support_conf *c, struct c0_frames *in, int n, struct c0_support_share *s);
/* Subset tile k's covariance over the even frames (from its own band, or
 * from all frames' less the odd ones'). */
int c0_support_even_window(const struct c0_support_share *s, int k, struct c0_cov *out);

/* The loops over the share's tiles (support_tiles.c), side by side, one
 * tile per thread (the solvers' own loops then run serially, so a tile's
 * numbers do not depend on how many threads or processes share the work).
 * The noise subset of the automatic lambda (stages/lambda.h): tiles spread
 * evenly over the grid; it depends on the grid only. */
void c0_support_subset(const struct c0_tiling *tl, uint8_t *sub);
/* Every tile's lambda_max on both scales (lm: 2 per tile); with hist, every
 * tile adds its correlation image, and the subset's halves their noise. */
int c0_support_tiles_lambda(const struct c0_support_conf *c, struct c0_support_share *s, double norm, double *lm,
			    double *hist);
/* The automatic lambda's second step: the subset's tiles solved at g's
 * lambda, their peaks summed over tiles and ranks. Collective. */
int c0_support_tiles_second(const struct c0_support_conf *c, struct c0_support_share *s,
			    const struct c0_support_scale *g, double lmax, struct c0_support_result *res);
/* The automatic lambda by cross-validation (stages/lambda.h): each subset
 * tile's halves along the path at the image's norm and lambda_max (l1
 * scale), the errors summed over tiles and ranks. Collective. */
int c0_support_tiles_cv(const struct c0_support_conf *c, struct c0_support_share *s, double norm, double lmax,
			struct c0_support_result *res);
/* The localisation precision from the subset's halves. Collective: its
 * status is every rank's. */
int c0_support_tiles_precision(const struct c0_support_conf *c, struct c0_support_share *s,
			       const struct c0_support_scale *g, struct c0_support_result *res);
/* Every tile solved at g: its interior into res's mask, rx and mean, its
 * noise variance into s2[k], its iterations, convergence, gap and
 * lambda_max into stats[4 k..], its objective history into obj[k nhist..]. */
int c0_support_tiles_solve(const struct c0_support_conf *c, struct c0_support_share *s,
			   const struct c0_support_scale *g, struct c0_support_result *res, double *s2, double *stats,
			   double *obj);
