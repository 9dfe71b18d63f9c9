/* ops/ridge: the distance to a crest against the Newton step from the
 * analytic derivatives of a Gaussian ridge, and the grown mask against the
 * pixels that distance allows. */
#include "check.h"
#include "ops/ridge.h"

#include <stdint.h>
#include <stdlib.h>

enum { N = 40 };
static const double S = 3;   /* the ridge's sd, pixels: about the pixel variances' at 25 nm fine pixels (69 nm) */

/* signed distance of pixel (y, x) from the line through (cy, cx) along (sin t, cos t) */
static double across(double y, double x, double cy, double cx, double t)
{
	return (y - cy) * cos(t) - (x - cx) * sin(t);
}

static void ridge(double cy, double cx, double t, double *f)
{
	for (int y = 0; y < N; y++)
		for (int x = 0; x < N; x++) {
			const double d = across(y, x, cy, cx, t);
			f[y * N + x] = exp(-d * d / (2 * S * S));
		}
}

/* one Newton step across a Gaussian profile: |f'/f''| = |d| / |1 - d^2/S^2| */
static double newton(double d)
{
	return fabs(d) / fabs(1 - d * d / (S * S));
}

static void test_dist(void)
{
	double *f = malloc(sizeof(double) * N * N), worst = 0;
	static const double ang[] = { 0, 0.3, 0.785398, 1.2, 1.5707963 };
	for (int a = 0; a < 5; a++) {
		const double cy = 19.3, cx = 20.6;
		ridge(cy, cx, ang[a], f);
		for (int y = 5; y < N - 5; y++)
			for (int x = 5; x < N - 5; x++) {
				const double d = across(y, x, cy, cx, ang[a]);
				if (fabs(d) <= 1.5)
					worst = fmax(worst, fabs(c0_ridge_dist(f, N, N, y, x) - newton(d)));
			}
	}
	/* central differences: 0.055 at 1.5 pixels */
	CHECK_MSG(worst < 0.08, "distance to the crest: largest error %.3f pixels", worst);
	/* no crest: a plane, a bowl; and the outermost pixels */
	for (int i = 0; i < N * N; i++)
		f[i] = 0.1 * (i % N) + 0.2 * (i / N);
	CHECK(isinf(c0_ridge_dist(f, N, N, 10, 10)));
	for (int i = 0; i < N * N; i++)
		f[i] = pow(i % N - 20.0, 2) + pow(i / N - 20.0, 2);
	CHECK(isinf(c0_ridge_dist(f, N, N, 12, 17)));
	ridge(20, 20, 0, f);
	CHECK(isinf(c0_ridge_dist(f, N, N, 0, 20)) && isinf(c0_ridge_dist(f, N, N, 20, N - 1)));
	free(f);
}

/* a mask one pixel across (the pixel nearest the crest in each column)
 * grows by the 4-neighbours within reach of the crest, once */
static void test_grow(void)
{
	double *f = malloc(sizeof(double) * N * N);
	uint8_t *m = calloc(N * N, 1), *m0 = calloc(N * N, 1);
	const double cy = 19.7, cx = 20, t = 0.2, reach = 1.1;
	ridge(cy, cx, t, f);
	for (int x = 4; x < N - 4; x++) {
		const int y = (int)lround(cy + (x - cx) * tan(t));
		m[y * N + x] = m0[y * N + x] = 1;
	}
	const long n = c0_ridge_grow(f, N, N, reach, m);
	long joined = 0, ok = 1, near = 0, missed = 0;
	for (int y = 1; y < N - 1; y++)
		for (int x = 1; x < N - 1; x++) {
			const int i = y * N + x;
			const int nb = m0[i - 1] | m0[i + 1] | m0[i - N] | m0[i + N];
			const double e = newton(across(y, x, cy, cx, t));
			ok &= !m0[i] || m[i];                      /* the mask stays */
			if (m[i] && !m0[i]) {
				joined++;
				ok &= nb && e <= reach + 0.05;        /* a neighbour, within reach */
			}
			if (!m0[i] && nb && e <= reach - 0.05)
				near++, missed += !m[i];
		}
	CHECK_MSG(ok && n == joined && joined > 0, "grown: %ld joined (%ld counted)", joined, n);
	CHECK_MSG(near > 20 && missed == 0, "grown: %ld of %ld neighbours within reach missed", missed, near);
	free(f), free(m), free(m0);
}

int main(void)
{
	RUN(test_dist);
	RUN(test_grow);
	return CHECK_DONE();
}
