/* Conjugate gradients for a symmetric positive (semi)definite operator. */
#pragma once
#include <stddef.h>

typedef void (*c0_linop_fn)(void *ctx, const double *in, double *out);

struct c0_cg_info { int iters, converged; double relres; };

/* Solves A x = b from the start in x, preconditioned by the diagonal
 * 1/dinv (NULL: none); stops when ||b - A x|| <= tol ||b|| or after maxit
 * steps (a zero b gives x = 0 at once). */
int c0_cg(c0_linop_fn A, void *ctx, size_t n, const double *b, const double *dinv, double *x, double tol,
	  int maxit, struct c0_cg_info *info);
/* The same, preconditioned by M (symmetric positive definite, an
 * approximate inverse of A): z = M(mctx, r) each step. */
int c0_pcg(c0_linop_fn A, void *ctx, size_t n, const double *b, c0_linop_fn M, void *mctx, double *x, double tol,
	   int maxit, struct c0_cg_info *info);
