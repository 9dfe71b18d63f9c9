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
 * nothing about the problem. c0_nnqp_batch: many programs of one H at once,
 * approximately. */
#pragma once

#define C0_NNQP_MAX 64

/* H and its inverse Hi: n x n row-major; returns the number of subspace solves, or -1 when it
 * hit its cap (x is then feasible and no worse than the start). */
int c0_nnqp(int n, const double *H, const double *Hi, const double *g, double *x);

/* Ai = A^-1 for A symmetric positive definite (n <= C0_NNQP_MAX), by
 * Cholesky; -1 if A is not numerically positive definite. */
int c0_spd_inverse(int n, const double *A, double *Ai);

/* C0_NNQP_BATCH programs of one H (n x n, float row-major), each with its own
 * g, approximately: `steps` projected gradient steps with constant momentum
 * beta and step `step` (1/L, L >= H's largest eigenvalue), from u and into
 * it. Column i's variable l is at [l * C0_NNQP_BATCH + i] in g and u. No
 * branches and no sums across columns: vectorised across them. */
#define C0_NNQP_BATCH 256
void c0_nnqp_batch(int n, const float *H, float step, float beta, int steps, const float *g, float *u);
