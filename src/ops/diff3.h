/* Finite differences on a volume v[z][y][x] (Nz x Ny x Nx), Neumann borders.
 * Gradient: forward differences scaled by (wl, wl, wz): 3 components.
 * Hessian: second differences (xx, yy, zz as -D^T D; xy, xz, yz as forward
 * D_a D_b), scaled by the product of the axis weights; off-diagonal entries
 * are stored times sqrt(2) so that the Euclidean product of the 6 stored
 * components is the Frobenius product of the symmetric 3x3 matrices. */
#pragma once
#include <stddef.h>

/* Volumes are float, as the iterates of solve/pdhg.h. */

struct c0_diff3 {
	int nx, ny, nz;
	double wl, wz;
	float *work;     /* 2 N floats owned by the caller, for the temporaries */
};

void c0_grad3(const struct c0_diff3 *d, const float *v, float *g);        /* N -> 3N */
void c0_grad3_adjoint(const struct c0_diff3 *d, const float *g, float *v);/* 3N -> N */
void c0_hess3(const struct c0_diff3 *d, const float *v, float *h);        /* N -> 6N */
void c0_hess3_adjoint(const struct c0_diff3 *d, const float *h, float *v);/* 6N -> N */
