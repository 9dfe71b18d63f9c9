/* The covariance accumulator alone (ops/covariance.h, issue 55): T frames
 * of W x W pixels (8 distinct pseudo-random uint16-like frames, cycled),
 * lag radius D (6: the support's 57 lags at 229 nm FWHM, 100 nm pixels),
 * added and flushed; prints wall and CPU seconds (user + system) and the
 * products summed per second, and one variance so that two builds can be
 * compared (it is the same number, bit for bit, when their sums are).
 *   cov_accumulate [W [T [D]]]   (default 1024 128 6) */
#define _POSIX_C_SOURCE 200809L
#include "ops/covariance.h"

#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <time.h>

static double wall(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec + 1e-9 * t.tv_nsec;
}

static double cpu(void)
{
	struct rusage u;
	getrusage(RUSAGE_SELF, &u);
	return u.ru_utime.tv_sec + 1e-6 * u.ru_utime.tv_usec + u.ru_stime.tv_sec + 1e-6 * u.ru_stime.tv_usec;
}

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
	const double w0 = wall(), c0 = cpu();
	for (int t = 0; t < T; t++)
		c0_cov_acc_add(a, f + (t % 8) * n);
	c0_cov_acc_seal(a);
	const double dw = wall() - w0, dc = cpu() - c0;
	printf("%dx%d, %d frames, %d lags: wall %.2f s, CPU %.2f s, %.2f G products/s (wall); variance %.17g\n", W, W, T,
	       c0_cov_lag_count(D), dw, dc, (double)n * T * c0_cov_lag_count(D) / dw / 1e9, c0_cov_acc_variance(a, W / 2, W / 2));
	c0_cov_acc_free(a);
	free(f);
	return 0;
}
