/* The 5-point Laplacian of a grid with mirrored (Neumann) edges, and the
 * operators a I + beta L^k it makes, which the DCT-II diagonalises: with
 * edges that reflect, cos(pi k (j + 1/2) / N) is an eigenvector of the 1-D
 * second difference with eigenvalue 4 sin^2(pi k / 2N), so (a I + beta L^k)
 * is inverted exactly by two transforms and a scaling. */
#pragma once

/* out = L in (Ny x Nx, separate arrays): each pixel's sum over its existing
 * 4-neighbours of in_pixel - in_neighbour. Symmetric, positive semidefinite,
 * L 1 = 0. */
void c0_neumann_laplacian(int Ny, int Nx, const double *in, double *out);

struct c0_neumann;

/* pad 0: the exact inverse below, by DCT-II and DCT-III. pad > 0 (a
 * preconditioner): the grid set in one of 2,3,5-smooth sides at least
 * 2 pad larger, zero around it, and (a I + beta L'^k)^{-1} there with
 * periodic edges by real FFTs, restricted back: E^T (..)^{-1} E, symmetric
 * positive definite, near the exact inverse where the grid is more than
 * the smoothing length from an edge, at 2.5x less work than the cosine
 * transforms (FFTW's real-to-complex plans are its fastest; a transform of a
 * prime length is 5x slower than one of a smooth length near it). In single
 * precision (symmetric to float's rounding): a preconditioner only steers
 * CG, and the transforms of the intensity tiles' 300^2 and 320^2 grids took
 * 0.49 and 0.43 ms a pair in float against 0.62 and 0.60 in double (2,3,5,7-
 * smooth sides, as before, gave the edge tiles 294^2: 0.74 ms). */
int c0_neumann_new(int Ny, int Nx, int pad, struct c0_neumann **out);
void c0_neumann_free(struct c0_neumann *s);
/* out = (a I + beta L^k)^{-1} in, k >= 1, a > 0 or (a = 0 and the mean of in
 * is 0); in and out may be the same array. One caller at a time per object
 * (it holds one work buffer). */
void c0_neumann_solve(struct c0_neumann *s, double a, double beta, int k, const double *in, double *out);
