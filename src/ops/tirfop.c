#include "ops/tirfop.h"

void c0_tirfop_forward(const struct c0_tirfop *o, const double *u, double *y)
{
	const size_t M = o->M;
#pragma omp parallel for schedule(static) if (M * o->nz > 50000)
	for (size_t k = 0; k < M; k++) {
		double s[64] = { 0 };     /* nq <= 64; each voxel is read once */
		for (int j = 0; j < o->nz; j++) {
			double v = u[j * M + k];
			for (int q = 0; q < o->nq; q++)
				s[q] += o->W[q * o->nz + j] * v;
		}
		for (int q = 0; q < o->nq; q++)
			y[q * M + k] = s[q];
	}
}

void c0_tirfop_adjoint_add(const struct c0_tirfop *o, const double *y, double *u)
{
	const size_t M = o->M;
#pragma omp parallel for schedule(static) if (M * o->nz > 50000)
	for (size_t k = 0; k < M; k++)
		for (int j = 0; j < o->nz; j++) {
			double s = 0;
			for (int q = 0; q < o->nq; q++)
				s += o->W[q * o->nz + j] * y[q * M + k];
			u[j * M + k] += s;
		}
}
