#pragma once
#include <stddef.h>

/* Order statistics: medians and quantiles of an array's values. */

/* The median of v[0..n) (the mean of the middle two for an even n; NAN for
 * n = 0); sorts v in place. */
double c0_median(double *v, size_t n);

/* The same of n floats, on a copy in double (NAN when it cannot be made). */
double c0_median_of(const float *v, size_t n);

/* The floor(q m)-th smallest (from 0) of the m values of v that are not NaN,
 * the largest for q >= 1; 0 when there are none. On a copy. */
double c0_quantile(const float *v, size_t n, double q);
