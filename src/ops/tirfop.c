#include "ops/tirfop.h"
#include "core/c0math.h"

/* Columns are processed in chunks so that the inner loops run along k over
 * contiguous memory (vectorised) while a chunk of every depth plane and of
 * every angle stays in cache. */
#define CHUNK 512

/* the columns k0 .. k1 - 1 of W u */
C0_HOT_SAME static void forward_chunk(const struct c0_tirfop *o, const float *u, float *y, size_t k0, size_t k1)
{
	const size_t M = o->M;
	for (int q = 0; q < o->nq; q++) {
		float *yq = y + q * M;
		for (size_t k = k0; k < k1; k++)
			yq[k] = 0;
		for (int j = 0; j < o->nz; j++) {
			const float w = (float)o->W[q * o->nz + j], *uj = u + j * M;
			for (size_t k = k0; k < k1; k++)
				yq[k] += w * uj[k];
		}
	}
}

/* the columns k0 .. k1 - 1 of u += W^T y */
C0_HOT_SAME static void adjoint_chunk(const struct c0_tirfop *o, const float *y, float *u, size_t k0, size_t k1)
{
	const size_t M = o->M;
	for (int j = 0; j < o->nz; j++) {
		float *uj = u + j * M;
		for (int q = 0; q < o->nq; q++) {
			const float w = (float)o->W[q * o->nz + j], *yq = y + q * M;
			for (size_t k = k0; k < k1; k++)
				uj[k] += w * yq[k];
		}
	}
}

void c0_tirfop_forward(const struct c0_tirfop *o, const float *u, float *y)
{
	const size_t M = o->M;
#pragma omp parallel for schedule(static) if (M * o->nz > 50000)
	for (size_t k0 = 0; k0 < M; k0 += CHUNK)
		forward_chunk(o, u, y, k0, k0 + CHUNK < M ? k0 + CHUNK : M);
}

void c0_tirfop_adjoint_add(const struct c0_tirfop *o, const float *y, float *u)
{
	const size_t M = o->M;
#pragma omp parallel for schedule(static) if (M * o->nz > 50000)
	for (size_t k0 = 0; k0 < M; k0 += CHUNK)
		adjoint_chunk(o, y, u, k0, k0 + CHUNK < M ? k0 + CHUNK : M);
}
