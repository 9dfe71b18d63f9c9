/* The covariance of a stack from those of its two interleaved halves (even
 * and odd frames), each detrended on its own (ops/covariance.h): their
 * pooled within-set sums of squares. Equal to the covariance of all frames
 * up to how the trend is fitted (tests/test_autosupport.c bounds it). */
#pragma once
#include "ops/covariance.h"

/* out (allocated) = covariance and mean of the frames of a and b together;
 * a and b have the same size and lags. */
int c0_cov_pool(const struct c0_cov *a, const struct c0_cov *b, struct c0_cov *out);
/* Sets of independent frames (stacks) pooled one after another: b is
 * added to acc, their covariances weighted by their degrees of freedom
 * (T - 2 each, or acc->dof once acc is itself a pool), their means by
 * frames. b is consumed: an empty acc (r NULL) takes it over, else it is
 * freed. */
int c0_cov_pool_add(struct c0_cov *acc, struct c0_cov *b);
