/* The 5-point Laplacian of a grid with mirrored (Neumann) edges, and the
 * operators a I + beta L^k it makes, which the DCT-II diagonalises: with
 * edges that reflect, cos(pi k (j + 1/2) / N) is an eigenvector of the 1-D
 * second difference with eigenvalue 4 sin^2(pi k / 2N), so (a I + beta L^k)
 * is inverted exactly by two transforms and a scaling. */
#pragma once

/* out = L in (Ny x Nx): each pixel's sum over its existing 4-neighbours of
 * in_pixel - in_neighbour. Symmetric, positive semidefinite, L 1 = 0. */
void c0_neumann_laplacian(int Ny, int Nx, const double *in, double *out);

struct c0_neumann;

/* pad 0: the exact inverse below. pad 1 (a preconditioner): the inverse on
 * the smallest grid of 2,3,5,7-smooth sides that holds this one, in set to 0
 * outside it and the result restricted to it, E^T (a I + beta L'^k)^{-1} E:
 * still symmetric positive definite, exact in the interior's smooth modes,
 * and never a transform of a prime length (5x slower). */
int c0_neumann_new(int Ny, int Nx, int pad, struct c0_neumann **out);
void c0_neumann_free(struct c0_neumann *s);
/* out = (a I + beta L^k)^{-1} in, k >= 1, a > 0 or (a = 0 and the mean of in
 * is 0); in and out may be the same array. One caller at a time per object
 * (it holds one work buffer). */
void c0_neumann_solve(struct c0_neumann *s, double a, double beta, int k, const double *in, double *out);
