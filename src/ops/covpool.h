/* The covariance of a stack from those of two disjoint sets of its frames
 * (the interleaved halves that choose lambda), exactly: the within-set sums
 * of squares plus the between-set term of the two means. */
#pragma once
#include "ops/covariance.h"

/* out (allocated) = covariance and mean of the frames of a and b together;
 * a and b have the same size and lags. */
int c0_cov_pool(const struct c0_cov *a, const struct c0_cov *b, struct c0_cov *out);
