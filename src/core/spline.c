#include "core/spline.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>

/* The prefilter's pole and how many of its powers the causal start sums:
 * z^K < 1e-17 */
#define POLE (-0.26794919243112270)   /* sqrt(3) - 2 */
#define K 30

/* The coefficients of the interpolating spline of v[0], v[s], ..
 * v[(n-1) s], in place. The sample sequence is extended half-sample
 * symmetrically (v[-1-k] = v[k]), period 2n, which the causal start sums
 * over and the anticausal one closes on. */
static void prefilter(double *v, int n, long s)
{
	if (n == 1)
		return;
	const double z = POLE;
	double c0 = 0, zk = 1;
	for (int k = 0; k < K; k++, zk *= z)   /* sum_k z^k v[-k] over the extension */
		c0 += zk * 6 * v[c0_mirror(-k, n) * s];
	v[0] = c0;
	for (long i = 1; i < n; i++)
		v[i * s] = 6 * v[i * s] + z * v[(i - 1) * s];
	v[(long)(n - 1) * s] *= z / (z - 1);
	for (long i = n - 2; i >= 0; i--)
		v[i * s] = z * (v[(i + 1) * s] - v[i * s]);
}

static double beta3(double t)
{
	t = fabs(t);
	return t < 1 ? 2.0 / 3 - t * t + t * t * t / 2 : t < 2 ? (2 - t) * (2 - t) * (2 - t) / 6 : 0;
}

/* out[j os] (j < n r) from the coefficients c[i cs] (i < n) */
static void evaluate(const double *c, int n, long cs, int r, double *out, long os)
{
	for (long j = 0; j < (long)n * r; j++) {
		const double u = (j + 0.5) / r - 0.5;
		const int i0 = (int)floor(u);
		double a = 0;
		for (int i = i0 - 1; i <= i0 + 2; i++)
			a += c[(long)c0_mirror(i, n) * cs] * beta3(u - i);
		out[j * os] = a;
	}
}

int c0_spline_upsample(const double *in, int H, int W, int r, double *out)
{
	const long Wr = (long)W * r;
	double *c = c0_alloc((size_t)H * W, sizeof *c), *t = c0_alloc((size_t)H * Wr, sizeof *t);
	if (!c || !t) {
		free(c), free(t);
		return C0_ENOMEM;
	}
	for (long i = 0; i < (long)H * W; i++)
		c[i] = in[i];
	for (int y = 0; y < H; y++)
		prefilter(c + (long)y * W, W, 1);
	for (int x = 0; x < W; x++)
		prefilter(c + x, H, W);
	for (int y = 0; y < H; y++)
		evaluate(c + (long)y * W, W, 1, r, t + y * Wr, 1);
	for (long x = 0; x < Wr; x++)
		evaluate(t + x, H, Wr, r, out + x, Wr);
	free(c), free(t);
	return C0_OK;
}
