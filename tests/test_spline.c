/* core/spline: the recursive prefilter and the separable evaluation against
 * the obvious way (the interpolation system solved densely, the spline
 * summed over every coefficient), and the interpolation property. */
#include "check.h"
#include "core/spline.h"
#include "core/rng.h"
#include "core/err.h"

#include <math.h>
#include <stdlib.h>

static double beta3(double t)
{
	t = fabs(t);
	return t < 1 ? 2.0 / 3 - t * t + t * t * t / 2 : t < 2 ? (2 - t) * (2 - t) * (2 - t) / 6 : 0;
}

/* the half-sample symmetric extension's index */
static int ext(int i, int n)
{
	while (i < 0 || i >= n)
		i = i < 0 ? -1 - i : 2 * n - 1 - i;
	return i;
}

/* B[i][k]: sample i's weight on coefficient k, the extension folded in */
static void system1(int n, double *B)
{
	for (int i = 0; i < n * n; i++)
		B[i] = 0;
	for (int i = 0; i < n; i++)
		for (int j = i - 2; j <= i + 2; j++)
			B[i * n + ext(j, n)] += beta3(i - j);
}

/* x = B^-1 b by Gauss-Jordan with partial pivoting (B destroyed) */
static void solve(double *B, double *b, int n)
{
	for (int c = 0; c < n; c++) {
		int p = c;
		for (int i = c + 1; i < n; i++)
			if (fabs(B[i * n + c]) > fabs(B[p * n + c]))
				p = i;
		for (int k = 0; k < n; k++) {
			const double t = B[c * n + k];
			B[c * n + k] = B[p * n + k], B[p * n + k] = t;
		}
		const double t = b[c];
		b[c] = b[p], b[p] = t;
		for (int i = 0; i < n; i++)
			if (i != c) {
				const double f = B[i * n + c] / B[c * n + c];
				for (int k = 0; k < n; k++)
					B[i * n + k] -= f * B[c * n + k];
				b[i] -= f * b[c];
			}
	}
	for (int i = 0; i < n; i++)
		b[i] /= B[i * n + i];
}

/* the slow upsampling: coefficients from the dense systems (rows, then
 * columns), then the spline summed over every coefficient */
static void slow(const double *in, int H, int W, int r, double *out)
{
	const int N = H > W ? H : W;
	double *c = malloc(sizeof(double) * H * W), *B = malloc(sizeof(double) * N * N), *v = malloc(sizeof(double) * N);
	for (int i = 0; i < H * W; i++)
		c[i] = in[i];
	for (int y = 0; y < H; y++) {
		system1(W, B);
		solve(B, c + y * W, W);
	}
	for (int x = 0; x < W; x++) {
		for (int y = 0; y < H; y++)
			v[y] = c[y * W + x];
		system1(H, B);
		solve(B, v, H);
		for (int y = 0; y < H; y++)
			c[y * W + x] = v[y];
	}
	for (int j = 0; j < H * r; j++)
		for (int k = 0; k < W * r; k++) {
			const double u = (j + 0.5) / r - 0.5, w = (k + 0.5) / r - 0.5;
			double a = 0;
			for (int y = -3; y < H + 3; y++)
				for (int x = -3; x < W + 3; x++)
					a += c[ext(y, H) * W + ext(x, W)] * beta3(u - y) * beta3(w - x);
			out[j * W * r + k] = a;
		}
	free(c), free(B), free(v);
}

static void test_against_slow(void)
{
	static const int sz[][3] = { { 7, 5, 4 }, { 1, 6, 4 }, { 2, 2, 3 }, { 12, 9, 2 }, { 40, 3, 4 } };
	struct c0_rng g;
	c0_rng_init(&g, 5, 0);
	for (int s = 0; s < 5; s++) {
		const int H = sz[s][0], W = sz[s][1], r = sz[s][2];
		double *in = malloc(sizeof(double) * H * W), *a = malloc(sizeof(double) * H * W * r * r);
		double *b = malloc(sizeof(double) * H * W * r * r), worst = 0, big = 0;
		for (int i = 0; i < H * W; i++)
			in[i] = c0_rng_normal(&g);
		CHECK(c0_spline_upsample(in, H, W, r, a) == C0_OK);
		slow(in, H, W, r, b);
		for (int i = 0; i < H * W * r * r; i++)
			worst = fmax(worst, fabs(a[i] - b[i])), big = fmax(big, fabs(b[i]));
		CHECK_MSG(worst <= 1e-12 * big, "%d x %d, r %d: %.3g from the dense solve", H, W, r, worst);
		free(in), free(a), free(b);
	}
}

/* r odd: the middle fine pixel sits on the sample, and the spline passes through it */
static void test_interpolates(void)
{
	enum { H = 9, W = 11, r = 3 };
	double in[H * W], out[H * W * r * r], worst = 0;
	for (int i = 0; i < H * W; i++)
		in[i] = sin(0.7 * i) + (i % 5);
	CHECK(c0_spline_upsample(in, H, W, r, out) == C0_OK);
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
			worst = fmax(worst, fabs(out[(y * r + 1) * W * r + x * r + 1] - in[y * W + x]));
	CHECK_MSG(worst < 1e-12, "off its samples by %.3g", worst);
}

int main(void)
{
	RUN(test_against_slow);
	RUN(test_interpolates);
	return CHECK_DONE();
}
