/* The spectral pieces of the Schatten-1 (nuclear) norm on symmetric 3x3
 * matrices, the Hessian-Schatten regulariser's: the eigen-decomposition by
 * cyclic Jacobi, and the projection on the spectral-norm ball (the dual
 * norm's unit ball scaled by k), which is the prox of the dual's indicator
 * in PDHG. Knows nothing of the problem. */
#pragma once

/* a symmetric, overwritten: its diagonal ends with the eigenvalues and the
 * columns of v with their eigenvectors, a = v diag(e) v^T. */
void c0_eig3(double a[3][3], double v[3][3]);

/* h (xx, yy, zz, sqrt2 xy, sqrt2 xz, sqrt2 yz), the packing in which the
 * Frobenius norm is the Euclidean one, <- the symmetric matrix with its
 * eigenvalues clipped to [-k, k]: the nearest matrix of spectral norm <= k.
 * Left as it is when no eigenvalue exceeds k. */
void c0_spectral_clip(double h[6], double k);
