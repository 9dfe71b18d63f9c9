/* Separable blur of 2D images (ny x nx) by a symmetric kernel k[-r..r]
 * (k[r + d] for offset d), zero outside the image. The matrix is symmetric,
 * so the operator is its own adjoint. */
#pragma once
#include <stddef.h>

struct c0_blur2 { int ny, nx, r; const float *k; float *work; /* ny x nx floats */ };

/* in place on n images stored one after another */
void c0_blur2_apply(const struct c0_blur2 *b, float *img, int n);
