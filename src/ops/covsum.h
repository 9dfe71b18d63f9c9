/* The covariance accumulator's hot loop (ops/covariance.c's flush): a
 * block's products of frame values added to the float sums of several
 * neighbouring lags at once.
 *
 * acc[k plane + x] = (float)(acc[k plane + x] + sum_b p[b s + x] q[b s + x + k]),
 * k < nlag, x < len, b < nb: each sum in double, frame by frame in order,
 * rounded once. p and q hold float values (as doubles): each product is
 * exact in double, so a fused multiply-add gives the same number as the
 * multiply and the add, and the vector paths (chosen at run time) the same
 * sums, bit for bit, as the portable one. q[b s + x + k] must be readable
 * for every x < len and k < nlag. Holding a p vector in a register while
 * nlag shifted q vectors meet it takes one load per multiply-add where one
 * lag at a time takes two. */
#pragma once
#include <stddef.h>

void c0_covsum_lags(float *acc, size_t plane, const double *p, const double *q, int len, int nlag, int nb, size_t s);
