/* The covariance accumulator's hot loop (ops/covsum.h, ops/covariance.c's
 * flush) against the obvious sums: the kernel (several lags at once) bit for bit against the plain
 * loop over frames in double, and a whole accumulator (widths that leave
 * vector tails, a partial last block, columns in two strips, a region
 * whose spans cross them) against the covariance summed in double from the
 * frames directly. */
#include "check.h"
#include "ops/covariance.h"
#include "ops/covsum.h"
#include "core/rng.h"
#include "core/err.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static struct c0_rng rng;

/* a float of a wide range (the exactness of the products matters there) */
static float rnd_float(void)
{
	return (float)(ldexp(c0_rng_normal(&rng), (int)(c0_rng_uniform(&rng) * 16) - 4));
}

static void test_kernel(void)
{
	enum { LEN = 75, NB = 17, NLAG = 15 };
	const size_t s = LEN + NLAG + 3, plane = LEN + 5;
	double *p = malloc(sizeof *p * s * NB), *q = malloc(sizeof *q * s * NB);
	float *acc = malloc(sizeof *acc * plane * NLAG), *ref = malloc(sizeof *ref * plane * NLAG);
	for (size_t i = 0; i < s * NB; i++)
		p[i] = rnd_float(), q[i] = rnd_float();
	int same = 1;
	for (int len = 0; len <= LEN; len += 1 + len / 8)
		for (int nb = 1; nb <= NB; nb += 3)
			for (int nlag = 1; nlag <= NLAG; nlag += 1 + nlag / 4) {   /* groups of 12 and their rest */
				for (size_t i = 0; i < plane * NLAG; i++)
					acc[i] = ref[i] = 1000 * rnd_float();
				c0_covsum_lags(acc, plane, p, q, len, nlag, nb, s);
				for (int k = 0; k < nlag; k++)
					for (int x = 0; x < len; x++) {
						double v = ref[k * plane + x];
						for (int b = 0; b < nb; b++)
							v += p[b * s + x] * q[b * s + x + k];
						ref[k * plane + x] = (float)v;
					}
				same &= !memcmp(acc, ref, sizeof *acc * plane * NLAG);   /* nothing else written */
			}
	CHECK_MSG(same, "covsum kernel differs from the plain double loop");
	free(p), free(q), free(acc), free(ref);
}

enum { W = 299, H = 13, D = 3, T = 41 };

/* lag l of the detrended covariance at pixel (y, x), summed in double from
 * the frames (mean and per-pixel trend removed, T - 2) */
static double direct(const float *fr, int dy, int dx, int y, int x)
{
	const int i = y * W + x, j = (y + dy) * W + x + dx;
	double mi = 0, mj = 0, ai = 0, aj = 0, stt = 0, s = 0;
	const double tb = (T - 1) / 2.0;
	for (int t = 0; t < T; t++)
		mi += fr[t * W * H + i] / (double)T, mj += fr[t * W * H + j] / (double)T;
	for (int t = 0; t < T; t++) {
		ai += (t - tb) * fr[t * W * H + i], aj += (t - tb) * fr[t * W * H + j], stt += (t - tb) * (t - tb);
		s += (fr[t * W * H + i] - mi) * (fr[t * W * H + j] - mj);
	}
	return (s - ai * aj / stt) / (T - 2);
}

static void test_accumulator(void)
{
	float *fr = malloc(sizeof *fr * W * H * T);
	uint8_t keep[W * H];
	for (int i = 0; i < W * H; i++)   /* spans of 29 columns, shifted by 7 each row: across the strips */
		keep[i] = ((i % W) + 7 * (i / W)) % 58 < 29;
	for (int i = 0; i < W * H * T; i++)   /* an offset, noise, a trend, a few bright pixels */
		fr[i] = (float)(500 + 20 * c0_rng_normal(&rng) + 0.3 * (i / (W * H)) * ((i % 5) - 2.0) +
				((i % (W * H)) % 11 == 0 ? 200 * c0_rng_uniform(&rng) : 0));
	struct c0_cov_acc *a, *b;
	CHECK(c0_cov_acc_new(W, H, D, &a) == C0_OK && c0_cov_acc_new(W, H, D, &b) == C0_OK);
	/* 41 = 2 x 19 + 3 frames; 299 columns make flush take two strips, the second ending in a vector's tail */
	CHECK(c0_cov_acc_set_block(a, 19) == C0_OK && c0_cov_acc_set_block(b, 19) == C0_OK);
	CHECK(c0_cov_acc_set_region(b, keep) == C0_OK);
	for (int t = 0; t < T; t++)
		c0_cov_acc_add(a, fr + t * W * H), c0_cov_acc_add(b, fr + t * W * H);
	struct c0_cov c, r;
	CHECK(c0_cov_acc_window(a, 0, 0, H, W, &c) == C0_OK && c0_cov_acc_window(b, 0, 0, H, W, &r) == C0_OK);
	double err = 0, scale = 0;
	int same = 1;
	for (int i = 0; i < W * H; i++)
		scale = fmax(scale, c.r[i]);
	for (int l = 0; l < c.nlag; l++)
		for (int y = 0; y + c.dy[l] < H; y++)
			for (int x = 0; x < W; x++) {
				if (x + c.dx[l] < 0 || x + c.dx[l] >= W)
					continue;
				const size_t k = (size_t)l * W * H + (size_t)y * W + x;
				err = fmax(err, fabs(c.r[k] - direct(fr, c.dy[l], c.dx[l], y, x)) / scale);
				const int whole = (c.dy[l] == 0 && c.dx[l] <= 1) || (c.dy[l] == 1 && c.dx[l] == 0);
				if (whole || keep[y * W + x])
					same &= c.r[k] == r.r[k];
				else
					same &= r.r[k] == 0;
			}
	/* float sums, a block of frames added in double and rounded once: ~1e-7
	 * of the sums, which are of values shifted by the first frame */
	CHECK_MSG(err < 1e-6, "accumulator vs direct double covariance: %g of the largest variance", err);
	CHECK_MSG(same, "a region's sums differ from the whole image's");
	c0_cov_free(&c), c0_cov_free(&r);
	c0_cov_acc_free(a), c0_cov_acc_free(b);
	free(fr);
}

int main(void)
{
	c0_rng_init(&rng, 7, 0);
	RUN(test_kernel);
	RUN(test_accumulator);
	return CHECK_DONE();
}
