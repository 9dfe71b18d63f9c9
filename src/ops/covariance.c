#include "ops/covariance.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define BLOCK 32   /* frames per pass over the accumulators */

struct c0_cov_acc {
	struct c0_cov c;
	double *shift;      /* first frame: sums are of y - shift, which keeps them small */
	double *s1;
	double *st;         /* sum over frames of t (y - shift): the linear trend */
	double *blk;        /* BLOCK frames, shifted */
	int nb;
};

int c0_cov_acc_new(int W, int H, int d, struct c0_cov_acc **out)
{
	*out = NULL;
	if (W < 1 || H < 1 || d < 0)
		return c0_fail(C0_EINVAL, "covariance: invalid size %dx%d or lag %d", W, H, d);
	struct c0_cov_acc *a = c0_alloc(1, sizeof *a);
	if (!a)
		return C0_ENOMEM;
	struct c0_cov *c = &a->c;
	c->W = W, c->H = H, c->d = d;
	c->nlag = (d + 1) * (2 * d + 1) - d;
	size_t n = (size_t)W * H;
	c->dy = c0_alloc((size_t)c->nlag, sizeof(int));
	c->dx = c0_alloc((size_t)c->nlag, sizeof(int));
	c->r = c0_alloc((size_t)c->nlag * n, sizeof(double));
	c->mean = c0_alloc(n, sizeof(double));
	a->shift = c0_alloc(n, sizeof(double));
	a->s1 = c0_alloc(n, sizeof(double));
	a->st = c0_alloc(n, sizeof(double));
	a->blk = c0_alloc(n * BLOCK, sizeof(double));
	if (!c->dy || !c->dx || !c->r || !c->mean || !a->shift || !a->s1 || !a->st || !a->blk) {
		c0_cov_acc_free(a);
		return c0_fail(C0_ENOMEM, "covariance: out of memory for %dx%d pixels x %d lags", W, H, c->nlag);
	}
	int l = 0;
	for (int dy = 0; dy <= d; dy++)
		for (int dx = -d; dx <= d; dx++)
			if (dy > 0 || dx >= 0)
				c->dy[l] = dy, c->dx[l] = dx, l++;
	*out = a;
	return C0_OK;
}

void c0_cov_free(struct c0_cov *c)
{
	free(c->dy), free(c->dx), free(c->r), free(c->mean);
	memset(c, 0, sizeof *c);
}

void c0_cov_acc_free(struct c0_cov_acc *a)
{
	if (!a)
		return;
	c0_cov_free(&a->c);
	free(a->shift), free(a->s1), free(a->st), free(a->blk);
	free(a);
}

static void flush(struct c0_cov_acc *a)
{
	struct c0_cov *c = &a->c;
	const int W = c->W, H = c->H, nb = a->nb;
	const size_t n = (size_t)W * H;
	/* each (lag, row) owns one accumulator row: no races, frames reused from cache */
#pragma omp parallel for collapse(2) schedule(dynamic, 8)
	for (int l = 0; l < c->nlag; l++)
		for (int y = 0; y < H; y++) {
			const int dy = c->dy[l], dx = c->dx[l];
			if (y + dy >= H)
				continue;
			const int x0 = dx < 0 ? -dx : 0, x1 = dx > 0 ? W - dx : W;
			double *acc = c->r + (size_t)l * n + (size_t)y * W;
			for (int b = 0; b < nb; b++) {
				const double *p = a->blk + b * n + (size_t)y * W;
				const double *q = a->blk + b * n + (size_t)(y + dy) * W + dx;
				for (int x = x0; x < x1; x++)
					acc[x] += p[x] * q[x];
			}
		}
	a->nb = 0;
}

int c0_cov_acc_add(struct c0_cov_acc *a, const float *frame)
{
	struct c0_cov *c = &a->c;
	const size_t n = (size_t)c->W * c->H;
	if (c->frames == 0)
		for (size_t i = 0; i < n; i++)
			a->shift[i] = frame[i];
	double *dst = a->blk + a->nb * n;
	const double t = (double)c->frames;
	for (size_t i = 0; i < n; i++) {
		dst[i] = frame[i] - a->shift[i];
		a->s1[i] += dst[i];
		a->st[i] += t * dst[i];
	}
	c->frames++;
	if (++a->nb == BLOCK)
		flush(a);
	return C0_OK;
}

int c0_cov_acc_finish(struct c0_cov_acc *a, struct c0_cov *out)
{
	struct c0_cov *c = &a->c;
	if (c->frames < 3) {
		int st = c0_fail(C0_EINVAL, "covariance needs at least 3 frames (got %lld)", (long long)c->frames);
		c0_cov_acc_free(a);
		return st;
	}
	flush(a);
	const int W = c->W, H = c->H;
	const size_t n = (size_t)W * H;
	const double T = (double)c->frames;
	/* a per-pixel linear trend (bleaching, slow drift of the lamp) is not
	 * fluctuation: remove it. With a_i = sum_t (t - tbar) y_i and
	 * Stt = sum_t (t - tbar)^2, the detrended cross-product is
	 * sum (y_i - ybar_i)(y_j - ybar_j) - a_i a_j / Stt, over T - 2 degrees of freedom. */
	const double tbar = (T - 1) / 2, Stt = T * (T * T - 1) / 12;
	for (size_t i = 0; i < n; i++) {
		c->mean[i] = a->s1[i] / T;       /* shifted mean */
		a->st[i] = (a->st[i] - tbar * a->s1[i]) / sqrt(Stt);   /* a_i / sqrt(Stt) */
	}
	for (int l = 0; l < c->nlag; l++) {
		const int dy = c->dy[l], dx = c->dx[l];
		for (int y = 0; y + dy < H; y++)
			for (int x = dx < 0 ? -dx : 0; x < (dx > 0 ? W - dx : W); x++) {
				size_t i = (size_t)y * W + x, j = (size_t)(y + dy) * W + x + dx;
				double *r = c->r + (size_t)l * n + i;
				*r = (*r - T * c->mean[i] * c->mean[j] - a->st[i] * a->st[j]) / (T - 2);
			}
	}
	for (size_t i = 0; i < n; i++)
		c->mean[i] += a->shift[i];
	*out = *c;
	memset(c, 0, sizeof *c);
	c0_cov_acc_free(a);
	return C0_OK;
}
