/* Small dense non-negative quadratic programs
 *   min_x 1/2 x^T H x - g^T x   subject to x >= 0
 * with H symmetric positive definite (n <= C0_NNQP_MAX), by a primal active
 * set method (Lawson-Hanson's, for a quadratic): x_F = H_FF^-1 g_F on the
 * free set F, stepping back to the boundary when that leaves the orthant,
 * and freeing the bound variable with the largest descent g - H x until
 * none has any. Warm-started from x (clipped to x >= 0): when x comes from
 * a nearby problem its free set is nearly right and one or two solves of
 * the size of F finish. Each solve factors the smaller of the free block of
 * H and the bound block of H^-1 (x = H^-1 g corrected on the bound set), so
 * that it costs little whether the solution is sparse or dense. Knows
 * nothing about the problem. */
#pragma once

#define C0_NNQP_MAX 64

/* H and its inverse Hi: n x n row-major; returns the number of subspace solves, or -1 when it
 * hit its cap (x is then feasible and no worse than the start). */
int c0_nnqp(int n, const double *H, const double *Hi, const double *g, double *x);

/* Ai = A^-1 for A symmetric positive definite (n <= C0_NNQP_MAX), by
 * Cholesky; -1 if A is not numerically positive definite. */
int c0_spd_inverse(int n, const double *A, double *Ai);
