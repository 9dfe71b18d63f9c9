#include "ops/covpool.h"
#include "core/err.h"
#include "core/mem.h"

#include <stdlib.h>
#include <string.h>

int c0_cov_pool(const struct c0_cov *a, const struct c0_cov *b, struct c0_cov *out)
{
	memset(out, 0, sizeof *out);
	if (a->W != b->W || a->H != b->H || a->d != b->d || a->frames < 2 || b->frames < 2)
		return c0_fail(C0_EINVAL, "covariance pooling: the two sets differ in size or lag, or hold < 2 frames");
	const int W = a->W, H = a->H;
	const size_t n = (size_t)W * H;
	*out = *a;
	out->dy = c0_alloc((size_t)a->nlag, sizeof(int));
	out->dx = c0_alloc((size_t)a->nlag, sizeof(int));
	out->r = c0_alloc((size_t)a->nlag * n, sizeof(double));
	out->mean = c0_alloc(n, sizeof(double));
	if (!out->dy || !out->dx || !out->r || !out->mean) {
		c0_cov_free(out);
		return C0_ENOMEM;
	}
	memcpy(out->dy, a->dy, (size_t)a->nlag * sizeof(int));
	memcpy(out->dx, a->dx, (size_t)a->nlag * sizeof(int));
	const double na = (double)a->frames, nb = (double)b->frames, N = na + nb;
	out->frames = a->frames + b->frames;
	for (size_t i = 0; i < n; i++)
		out->mean[i] = (na * a->mean[i] + nb * b->mean[i]) / N;
#pragma omp parallel for collapse(2) schedule(static)
	for (int l = 0; l < a->nlag; l++)
		for (int y = 0; y < H; y++) {
			const int dy = a->dy[l], dx = a->dx[l];
			for (int x = 0; x < W; x++) {
				size_t i = (size_t)l * n + (size_t)y * W + x;
				int y2 = y + dy, x2 = x + dx;
				if (y2 >= H || x2 < 0 || x2 >= W)
					continue;   /* partner outside: stays 0 */
				size_t p = (size_t)y * W + x, q = (size_t)y2 * W + x2;
				/* each set's covariance has its own linear trend removed
				 * (T - 2 degrees of freedom); interleaved sets share the
				 * trend, which also explains most of the difference of
				 * their means (one frame apart), so that term is left out */
				out->r[i] = ((na - 2) * a->r[i] + (nb - 2) * b->r[i]) / (N - 4);
				(void)p, (void)q;
			}
		}
	return C0_OK;
}

int c0_cov_pool_add(struct c0_cov *acc, struct c0_cov *b)
{
	if (!acc->r) {   /* the first set: taken over */
		*acc = *b;
		memset(b, 0, sizeof *b);
		return C0_OK;
	}
	if (acc->W != b->W || acc->H != b->H || acc->d != b->d || b->frames < 3)
		return c0_cov_free(b), c0_fail(C0_EINVAL, "covariance pooling: the sets differ in size or lag, or one holds < 3 frames");
	const size_t n = (size_t)acc->W * acc->H;
	const double na = (double)acc->frames, nb = (double)b->frames;
	const double wa = acc->dof > 0 ? acc->dof : na - 2, wb = nb - 2;
	for (size_t i = 0; i < n; i++)
		acc->mean[i] = (na * acc->mean[i] + nb * b->mean[i]) / (na + nb);
	/* partners outside the image are 0 in both: they stay 0 */
	for (size_t i = 0; i < (size_t)acc->nlag * n; i++)
		acc->r[i] = (wa * acc->r[i] + wb * b->r[i]) / (wa + wb);
	acc->frames += b->frames, acc->dof = wa + wb;
	c0_cov_free(b);
	return C0_OK;
}
