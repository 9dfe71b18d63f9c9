/* The fixed pattern the angles' stacks share (stages/pattern.h). */
#include "stages/pattern.h"
#include "ops/psi_omega.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/order.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { ON = 0, NEAR = 1, FAR = 2 };

int c0_pattern_residuals(const struct c0_grid *g, int n, const double *const *ybar, const float *const *x, const float *const *b,
			 int H, int W, const uint8_t *mask, double **res)
{
	struct c0_psi_omega P;
	int st = c0_psi_omega_init(&P, H, W, g->srf, c0_grid_sigma_px(g), mask, 1);
	if (st)
		return st;
	double *v = c0_alloc(P.n ? (size_t)P.n : 1, sizeof *v);
	if (!v)
		st = C0_ENOMEM;
	for (int q = 0; !st && q < n; q++) {
		for (int k = 0; k < P.n; k++)
			v[k] = x[q][k];
		c0_psi_omega_forward(&P, v, res[q]);
		for (size_t i = 0; i < (size_t)H * W; i++)
			res[q][i] = ybar[q][i] - res[q][i] - b[q][i];
	}
	free(v);
	c0_psi_omega_free(&P);
	return st;
}

/* 1 where a row (stride s, length len, step d) of in has a 1 within r */
static void dilate_line(const uint8_t *in, uint8_t *out, int len, size_t d, int r)
{
	int last = -1 - r;   /* the last 1 seen, then the next one ahead */
	for (int i = 0; i < len; i++)
		if (in[(size_t)i * d])
			last = i;
		else if (i - last <= r)
			out[(size_t)i * d] = 1;
	last = len + r;
	for (int i = len - 1; i >= 0; i--)
		if (in[(size_t)i * d])
			last = i, out[(size_t)i * d] = 1;
		else if (last - i <= r)
			out[(size_t)i * d] = 1;
}

/* cls: ON where a camera pixel holds a support pixel, NEAR within r camera
 * pixels of one (Chebyshev), FAR beyond */
static int classes(const uint8_t *mask, int H, int W, int srf, int r, uint8_t *cls)
{
	const size_t N = (size_t)H * W;
	uint8_t *on = c0_alloc(3 * N, 1), *a = on + N, *b = on + 2 * N;
	if (!on)
		return C0_ENOMEM;
	const size_t Lx = (size_t)W * srf;
	for (size_t y = 0; y < (size_t)H * srf; y++)
		for (size_t x = 0; x < Lx; x++)
			if (mask[y * Lx + x])
				on[(y / srf) * W + x / srf] = 1;
	for (int y = 0; y < H; y++)
		dilate_line(on + (size_t)y * W, a + (size_t)y * W, W, 1, r);
	for (int x = 0; x < W; x++)
		dilate_line(a + x, b + x, H, (size_t)W, r);
	for (size_t i = 0; i < N; i++)
		cls[i] = on[i] ? ON : b[i] ? NEAR : FAR;
	free(on);
	return C0_OK;
}

/* c: the stacks' mean pairwise covariance over the FAR pixels */
static double shared_variance(int n, const double *const *res, const uint8_t *cls, size_t N, int *nfar)
{
	double mean[C0_MAX_STACKS] = { 0 }, s = 0;
	int m = 0;
	for (size_t i = 0; i < N; i++)
		if (cls[i] == FAR) {
			m++;
			for (int q = 0; q < n; q++)
				mean[q] += res[q][i];
		}
	*nfar = m;
	if (m < 2)
		return 0;
	for (int q = 0; q < n; q++)
		mean[q] /= m;
	for (size_t i = 0; i < N; i++)
		if (cls[i] == FAR) {
			double t = 0, t2 = 0;
			for (int q = 0; q < n; q++) {
				double d = res[q][i] - mean[q];
				t += d, t2 += d * d;
			}
			s += 0.5 * (t * t - t2);
		}
	return s / m / (0.5 * n * (n - 1));
}

int c0_pattern_estimate(const struct c0_grid *g, int n, const double *const *res, int H, int W, const uint8_t *mask, float *pat,
			struct c0_pattern_stats *s)
{
	memset(s, 0, sizeof *s);
	s->stacks = n;
	const size_t N = (size_t)H * W;
	memset(pat, 0, N * sizeof *pat);
	if (n < 2 || n > C0_MAX_STACKS)
		return C0_OK;
	uint8_t *cls = c0_alloc(N, 1);
	double *med = c0_alloc(N, sizeof *med);
	if (!cls || !med) {
		free(cls), free(med);
		return C0_ENOMEM;
	}
	/* beyond 2 FWHM a support pixel's light is below 1e-4 of its peak */
	int st = classes(mask, H, W, g->srf, (int)ceil(2 * g->fwhm_nm / g->pixel_nm), cls);
	for (size_t i = 0; !st && i < N; i++) {
		double v[C0_MAX_STACKS];
		for (int q = 0; q < n; q++)
			v[q] = res[q][i];
		med[i] = c0_median(v, (size_t)n);
	}
	if (!st)
		s->common_var = shared_variance(n, res, cls, N, &s->far_pixels);
	double sum[3] = { 0 }, sum2[3] = { 0 }, k[3] = { 0 };
	size_t cnt[3] = { 0 };
	for (size_t i = 0; !st && i < N; i++)
		sum[cls[i]] += med[i], sum2[cls[i]] += med[i] * med[i], cnt[cls[i]]++;
	for (int c = 0; c < 3; c++) {
		double var = cnt[c] ? sum2[c] / cnt[c] - (sum[c] / cnt[c]) * (sum[c] / cnt[c]) : 0;
		k[c] = var > 0 && s->common_var > 0 ? fmin(1, s->common_var / var) : 0;
	}
	s->k_on = k[ON], s->k_near = k[NEAR], s->k_far = k[FAR];
	s->applied = !st && cnt[ON] > 0 && s->far_pixels >= 2 && k[ON] >= 0.5;
	for (size_t i = 0; s->applied && i < N; i++)
		pat[i] = (float)(k[cls[i]] * med[i]);
	free(cls), free(med);
	return st;
}
