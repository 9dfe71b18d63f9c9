/* The covariance accumulator alone (ops/covariance.h, issue 55): T frames
 * of W x W pixels (8 distinct pseudo-random uint16-like frames, cycled),
 * lag radius D (6: the support's 57 lags at 229 nm FWHM, 100 nm pixels),
 * added and flushed; prints wall and CPU seconds (user + system) and the
 * products summed per second, and one variance so that two builds can be
 * compared (it is the same number, bit for bit, when their sums are).
 *   cov_accumulate [W [T [D]]]   (default 1024 128 6) */
#include "ops/covariance.h"
#include "core/clock.h"

#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
	const int W = argc > 1 ? atoi(argv[1]) : 1024, T = argc > 2 ? atoi(argv[2]) : 128, D = argc > 3 ? atoi(argv[3]) : 6;
	const size_t n = (size_t)W * W;
	float *f = malloc(n * 8 * sizeof *f);
	struct c0_cov_acc *a;
	if (W < 8 || T < 3 || D < 0 || !f || c0_cov_acc_new(W, W, D, &a)) {
		fprintf(stderr, "usage: cov_accumulate [W >= 8 [T >= 3 [D >= 0]]]\n");
		return 1;
	}
	unsigned s = 1;
	for (size_t i = 0; i < n * 8; i++)
		s = s * 1103515245u + 12345u, f[i] = (float)(100 + (s >> 16) % 200);
	const double w0 = c0_now(), c0 = c0_cpu_seconds();
	for (int t = 0; t < T; t++)
		c0_cov_acc_add(a, f + (t % 8) * n);
	c0_cov_acc_seal(a);
	const double dw = c0_now() - w0, dc = c0_cpu_seconds() - c0;
	printf("%dx%d, %d frames, %d lags: wall %.2f s, CPU %.2f s, %.2f G products/s (wall); variance %.17g\n", W, W, T,
	       c0_cov_lag_count(D), dw, dc, (double)n * T * c0_cov_lag_count(D) / dw / 1e9, c0_cov_acc_variance(a, W / 2, W / 2));
	c0_cov_acc_free(a);
	free(f);
	return 0;
}
