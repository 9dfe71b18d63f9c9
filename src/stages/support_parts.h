/* The support step's pieces that its files share (support.c: the
 * configuration and the per-stack phases, support_solve.c: one window's
 * solve, support_stream.c: the passes over the frames, support_tiles.c:
 * the loops over tiles, lambda.c); not for other stages. */
#pragma once
#include "stages/support.h"
#include "stages/tiles.h"
#include "ops/covop.h"

/* A tile solves with the whole image's normalisation and lambda, so that
 * every tile answers the same question. */
struct c0_support_scale {
	double norm;     /* largest pixel variance of the image */
	double lam;      /* absolute lambda (normalised units) */
};

/* lambda / lambda_max: c->lambda_rel, or the penalty's fixed default */
double c0_support_lambda_rel(const struct c0_support_conf *c);
/* The errors that several paths share (their texts are read by users and tests) */
int c0_support_fail_flat(void);
int c0_support_fail_short(const struct c0_frames *in);
/* A covariance accumulator for c's streamed stacks: with its pixel guard. */
int c0_support_acc_new(const struct c0_support_conf *c, int W, int H, int d, struct c0_cov_acc **a);

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
