#include "ops/grad3m.h"
#include "core/err.h"
#include "core/mem.h"

#include <stdlib.h>

int c0_grad3m_init(struct c0_grad3m *g, const uint8_t *mask, int ny, int nx, int nz, double wl, double wz)
{
	const size_t np = (size_t)ny * nx;
	int *idx = malloc((np ? np : 1) * sizeof *idx);
	if (!idx)
		return C0_ENOMEM;
	int M = 0;
	for (size_t p = 0; p < np; p++)
		idx[p] = mask[p] ? M++ : -1;
	*g = (struct c0_grad3m){ M, nz, wz != 0 ? 3 : 2, wl, wz, NULL, NULL, NULL, NULL, NULL };
	size_t n = M ? (size_t)M : 1;
	g->right = malloc(n * sizeof(int)), g->down = malloc(n * sizeof(int));
	g->left = malloc(n * sizeof(int)), g->up = malloc(n * sizeof(int)), g->pixel = malloc(n * sizeof(int));
	if (!g->right || !g->down || !g->left || !g->up || !g->pixel) {
		free(idx);
		c0_grad3m_free(g);
		return C0_ENOMEM;
	}
	for (int y = 0; y < ny; y++)
		for (int x = 0; x < nx; x++) {
			size_t p = (size_t)y * nx + x;
			int k = idx[p];
			if (k < 0)
				continue;
			g->pixel[k] = (int)p;
			g->right[k] = x + 1 < nx ? idx[p + 1] : -1;
			g->left[k] = x > 0 ? idx[p - 1] : -1;
			g->down[k] = y + 1 < ny ? idx[p + nx] : -1;
			g->up[k] = y > 0 ? idx[p - nx] : -1;
		}
	free(idx);
	return C0_OK;
}

void c0_grad3m_free(struct c0_grad3m *g)
{
	free(g->right), free(g->down), free(g->left), free(g->up), free(g->pixel);
	g->right = g->down = g->left = g->up = g->pixel = NULL;
}

void c0_grad3m_forward(const struct c0_grad3m *g, const float *v, float *d)
{
	const size_t M = (size_t)g->M, N = M * g->nz;
#pragma omp parallel for schedule(static) if (N > 50000)
	for (int j = 0; j < g->nz; j++) {
		const float *c = v + j * M;
		const float wl = (float)g->wl, wz = (float)g->wz;
		float *dx = d + j * M, *dy = d + N + j * M;
		for (size_t k = 0; k < M; k++) {
			int r = g->right[k], w = g->down[k];
			dx[k] = r >= 0 ? wl * (c[r] - c[k]) : 0;
			dy[k] = w >= 0 ? wl * (c[w] - c[k]) : 0;
		}
		float *dz = g->nc == 3 ? d + 2 * N + j * M : NULL;
		for (size_t k = 0; dz && k < M; k++)
			dz[k] = j + 1 < g->nz ? wz * (c[k + M] - c[k]) : 0;
	}
}

/* gather form: each voxel collects the rows it appears in, so no two
 * threads write the same value */
void c0_grad3m_adjoint(const struct c0_grad3m *g, const float *d, float *v)
{
	const size_t M = (size_t)g->M, N = M * g->nz;
#pragma omp parallel for schedule(static) if (N > 50000)
	for (int j = 0; j < g->nz; j++) {
		const float *dx = d + j * M, *dy = d + N + j * M, wl = (float)g->wl, wz = (float)g->wz;
		float *o = v + j * M;
		for (size_t k = 0; k < M; k++) {
			int l = g->left[k], u = g->up[k];
			float s = (g->right[k] >= 0 ? -dx[k] : 0) + (g->down[k] >= 0 ? -dy[k] : 0);
			if (l >= 0)
				s += dx[l];
			if (u >= 0)
				s += dy[u];
			o[k] = wl * s;
		}
		const float *dz = g->nc == 3 ? d + 2 * N + j * M : NULL;
		for (size_t k = 0; dz && k < M; k++)
			o[k] += wz * ((j + 1 < g->nz ? -dz[k] : 0) + (j > 0 ? dz[k - M] : 0));
	}
}

double c0_grad3m_colsum(const struct c0_grad3m *g, int k, int j)
{
	int nl = (g->right[k] >= 0) + (g->left[k] >= 0) + (g->down[k] >= 0) + (g->up[k] >= 0);
	int na = (j + 1 < g->nz) + (j > 0);
	return g->wl * nl + g->wz * na;
}
