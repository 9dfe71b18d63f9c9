/* The support stage's helpers that its files share (support_util.c); the
 * public ones (c0_support_lag, _tol, _check, ...) are declared in support.h. */
#pragma once
#include "stages/support.h"
#include "core/tiles.h"

/* lambda / lambda_max: c->lambda_rel, or the penalty's fixed default */
double c0_support_lambda_rel(const struct c0_support_conf *c);
/* The errors that several paths share (their texts are read by users and tests) */
int c0_support_fail_flat(void);
int c0_support_fail_short(const struct c0_frames *in);
/* A covariance accumulator for c's streamed stacks: with its pixel guard and
 * noise map; its pixel (0, 0) is the image's (y0, x0). */
int c0_support_acc_new(const struct c0_support_conf *c, int W, int H, int d, int x0, int y0, struct c0_cov_acc **a);

/* The checks on in for c, and its tile grid (halo: two lags). */
int c0_support_grid(const struct c0_support_conf *c, const struct c0_frames *in, struct c0_tiling *tl);

/* lambda_max on the l1 and the l0 scale (lm[0], lm[1]) of the gradient at
 * x = 0, g = C / norm - s0 n (C = A^T R, n the column norms, s0 the noise
 * variance at x = 0): the smallest lambda for which x = 0 is optimal. */
void c0_lambda_max(const double *C, double norm, double s0, const double *n, size_t L, double lm[2]);
