/* The covariance of a stack from those of its two interleaved halves (even
 * and odd frames), each detrended on its own (ops/covariance.h): their
 * pooled within-set sums of squares. Equal to the covariance of all frames
 * up to how the trend is fitted (tests/test_autosupport.c bounds it). */
#pragma once
#include "ops/covariance.h"

/* out (allocated) = covariance and mean of the frames of a and b together;
 * a and b have the same size and lags. */
int c0_cov_pool(const struct c0_cov *a, const struct c0_cov *b, struct c0_cov *out);
