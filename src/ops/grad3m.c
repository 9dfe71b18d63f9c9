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
	*g = (struct c0_grad3m){ M, nz, wz != 0 ? 3 : 2, wl, wz, NULL, NULL, NULL, NULL, NULL, NULL };
	size_t n = M ? (size_t)M : 1;
	g->hr = malloc(n * sizeof(float)), g->hd = malloc(n * sizeof(float)), g->hu = malloc(n * sizeof(float));
	g->down = malloc(n * sizeof(int)), g->up = malloc(n * sizeof(int)), g->pixel = malloc(n * sizeof(int));
	if (!g->hr || !g->hd || !g->hu || !g->down || !g->up || !g->pixel) {
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
			int d = y + 1 < ny ? idx[p + nx] : -1, u = y > 0 ? idx[p - nx] : -1;
			g->pixel[k] = (int)p;
			g->hr[k] = x + 1 < nx && idx[p + 1] >= 0;
			g->hd[k] = d >= 0, g->down[k] = d >= 0 ? d : k;
			g->hu[k] = u >= 0, g->up[k] = u >= 0 ? u : k;
		}
	free(idx);
	return C0_OK;
}

void c0_grad3m_free(struct c0_grad3m *g)
{
	free(g->hr), free(g->hd), free(g->hu), free(g->down), free(g->up), free(g->pixel);
	g->hr = g->hd = g->hu = NULL;
	g->down = g->up = g->pixel = NULL;
}

/* Columns in chunks, every depth of a chunk in turn: the per-column tables
 * of a chunk stay in cache for all depths. */
#define CHUNK 2048

void c0_grad3m_forward(const struct c0_grad3m *g, const float *v, float *d)
{
	const size_t M = (size_t)g->M, N = M * g->nz;
	const float wl = (float)g->wl, wz = (float)g->wz;
#pragma omp parallel for schedule(static) if (N > 50000)
	for (size_t k0 = 0; k0 < M; k0 += CHUNK) {
		const size_t k1 = k0 + CHUNK < M ? k0 + CHUNK : M, kr = k1 < M ? k1 : M - 1;
		for (int j = 0; j < g->nz; j++) {
			const float *c = v + j * M;
			float *dx = d + j * M, *dy = d + N + j * M;
			for (size_t k = k0; k < kr; k++)       /* the right neighbour is k + 1 */
				dx[k] = wl * g->hr[k] * (c[k + 1] - c[k]);
			if (kr < k1)
				dx[kr] = 0;                        /* the last column has none */
			for (size_t k = k0; k < k1; k++)
				dy[k] = wl * (c[g->down[k]] - c[k]);
			if (g->nc == 3) {
				float *dz = d + 2 * N + j * M;
				for (size_t k = k0; k < k1; k++)
					dz[k] = j + 1 < g->nz ? wz * (c[k + M] - c[k]) : 0;
			}
		}
	}
}

/* gather form: each voxel collects the rows it appears in, so no two
 * threads write the same value */
void c0_grad3m_adjoint(const struct c0_grad3m *g, const float *d, float *v)
{
	const size_t M = (size_t)g->M, N = M * g->nz;
	const float wl = (float)g->wl, wz = (float)g->wz;
#pragma omp parallel for schedule(static) if (N > 50000)
	for (size_t k0 = 0; k0 < M; k0 += CHUNK) {
		const size_t k1 = k0 + CHUNK < M ? k0 + CHUNK : M;
		for (int j = 0; j < g->nz; j++) {
			const float *dx = d + j * M, *dy = d + N + j * M;
			float *o = v + j * M;
			size_t k = k0;
			if (k == 0)                           /* no left neighbour */
				o[0] = wl * (-g->hr[0] * dx[0] - g->hd[0] * dy[0] + g->hu[0] * dy[g->up[0]]), k = 1;
			for (; k < k1; k++)
				o[k] = wl * (g->hr[k - 1] * dx[k - 1] - g->hr[k] * dx[k] - g->hd[k] * dy[k] + g->hu[k] * dy[g->up[k]]);
			if (g->nc == 3) {
				const float *dz = d + 2 * N + j * M;
				for (k = k0; k < k1; k++)
					o[k] += wz * ((j + 1 < g->nz ? -dz[k] : 0) + (j > 0 ? (dz - M)[k] : 0));
			}
		}
	}
}

double c0_grad3m_colsum(const struct c0_grad3m *g, int k, int j)
{
	double nl = g->hr[k] + (k > 0 ? g->hr[k - 1] : 0) + g->hd[k] + g->hu[k];
	int na = (j + 1 < g->nz) + (j > 0);
	return g->wl * nl + g->wz * na;
}
