/* The covariance accumulator's hot loop (ops/covariance.c's flush): a
 * block's products of frame values added to the float sums.
 *
 * acc[x] = (float)(acc[x] + sum_b p[b s + x] q[b s + x]), x < len, b < nb,
 * the sum in double, frame by frame in order, rounded once. p and q hold
 * float values (as doubles): each product is exact in double, so a fused
 * multiply-add gives the same number as the multiply and the add, and the
 * AVX2+FMA path (chosen at run time) the same sums, bit for bit, as the
 * portable one. */
#pragma once
#include <stddef.h>

void c0_covsum_span(float *acc, const double *p, const double *q, int len, int nb, size_t s);
