#include "eval/frc.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/fftw_plan.h"
#include "core/mem.h"

#include <complex.h>
#include <fftw3.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void c0_frc_free(struct c0_frc *f)
{
	free(f->freq), free(f->corr);
	memset(f, 0, sizeof *f);
}

static void prepare(const float *v, int H, int W, double *re)
{
	double m = 0, ws = 0;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			double w = (0.5 - 0.5 * cos(2 * C0_PI * (y + 0.5) / H)) * (0.5 - 0.5 * cos(2 * C0_PI * (x + 0.5) / W));
			m += w * v[(size_t)y * W + x], ws += w;
		}
	m /= ws;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			double w = (0.5 - 0.5 * cos(2 * C0_PI * (y + 0.5) / H)) * (0.5 - 0.5 * cos(2 * C0_PI * (x + 0.5) / W));
			re[(size_t)y * W + x] = w * (v[(size_t)y * W + x] - m);
		}
}

int c0_frc_compute(const float *a, const float *b, int H, int W, struct c0_frc *out)
{
	memset(out, 0, sizeof *out);
	if (H < 8 || W < 8)
		return c0_fail(C0_EINVAL, "frc: %dx%d is too small (at least 8x8)", W, H);
	const int Wc = W / 2 + 1, M = H > W ? H : W, nr = M / 2;
	const size_t n = (size_t)H * W, nc = (size_t)H * Wc;
	double *re = fftw_malloc(n * sizeof *re);
	fftw_complex *fa = fftw_malloc(nc * sizeof *fa), *fb = fftw_malloc(nc * sizeof *fb);
	double *num = c0_alloc((size_t)nr, sizeof *num), *da = c0_alloc((size_t)nr, sizeof *da), *db = c0_alloc((size_t)nr, sizeof *db);
	out->freq = c0_alloc((size_t)nr, sizeof(double)), out->corr = c0_alloc((size_t)nr, sizeof(double));
	int st = C0_OK;
	fftw_plan p = NULL;
	if (!re || !fa || !fb || !num || !da || !db || !out->freq || !out->corr) {
		st = c0_fail(C0_ENOMEM, "frc: out of memory for %dx%d", W, H);
		goto out;
	}
#pragma omp critical(c0_fftw_plan)
	p = fftw_plan_dft_r2c_2d(H, W, re, fa, FFTW_ESTIMATE);
	if (!p) {
		st = c0_fail(C0_ENOMEM, "frc: cannot plan a %dx%d FFT", W, H);
		goto out;
	}
	prepare(a, H, W, re);
	fftw_execute_dft_r2c(p, re, fa);
	prepare(b, H, W, re);
	fftw_execute_dft_r2c(p, re, fb);
	for (int y = 0; y < H; y++)
		for (int x = 0; x < Wc; x++) {
			double fy = (double)(y <= H / 2 ? y : y - H) / H, fx = (double)x / W;
			int k = (int)floor(sqrt(fy * fy + fx * fx) * M + 0.5);
			if (k >= nr)
				continue;
			/* bins x > 0 stand for their mirror too; equal weights suffice
			 * for a ratio of sums over the same bins */
			fftw_complex u = fa[(size_t)y * Wc + x], v = fb[(size_t)y * Wc + x];
			num[k] += creal(u * conj(v)), da[k] += creal(u * conj(u)), db[k] += creal(v * conj(v));
		}
	out->n = nr;
	for (int k = 0; k < nr; k++) {
		double s = 0, sa = 0, sb = 0;
		for (int j = k - 1; j <= k + 1; j++)
			if (j >= 0 && j < nr)
				s += num[j], sa += da[j], sb += db[j];
		out->freq[k] = (double)k / M;
		out->corr[k] = sa > 0 && sb > 0 ? s / sqrt(sa * sb) : 0;
	}
	const double thr = 1.0 / 7;
	for (int k = 2; k < nr; k++)
		if (out->corr[k] < thr) {
			double f0 = out->freq[k - 1], f1 = out->freq[k], c0 = out->corr[k - 1], c1 = out->corr[k];
			double f = c0 > c1 ? f0 + (c0 - thr) / (c0 - c1) * (f1 - f0) : f1;
			out->resolution_px = 1 / f;
			break;
		}
out:
	c0_fftw_destroy(p);
	fftw_free(re), fftw_free(fa), fftw_free(fb);
	free(num), free(da), free(db);
	if (st)
		c0_frc_free(out);
	return st;
}

void c0_pair_sums(const unsigned char *a, const unsigned char *b, int H, int W, int radius_px, double *s2, double *n)
{
	double s = 0;
	long m = 0;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			if (!a[(size_t)y * W + x])
				continue;
			int best = -1;
			for (int dy = -radius_px; dy <= radius_px; dy++)
				for (int dx = -radius_px; dx <= radius_px; dx++) {
					int yy = y + dy, xx = x + dx, d2 = dy * dy + dx * dx;
					if (yy < 0 || yy >= H || xx < 0 || xx >= W || d2 > radius_px * radius_px || !b[(size_t)yy * W + xx])
						continue;
					if (best < 0 || d2 < best)
						best = d2;
				}
			if (best >= 0)
				s += best, m++;
		}
	*s2 = s, *n = (double)m;
}

double c0_pair_precision(const unsigned char *a, const unsigned char *b, int H, int W, int radius_px)
{
	double s, n;
	c0_pair_sums(a, b, H, W, radius_px, &s, &n);
	return n > 0 ? sqrt(s / n / 4) : -1;
}
