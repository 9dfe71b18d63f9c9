/* Diagonally preconditioned primal-dual hybrid gradient (Chambolle-Pock,
 * Pock-Chambolle 2011 with alpha = 1) for
 *   min_x  G(x) + F(K x)
 * given the proximal maps of G and of F* (the convex conjugate), both in
 * place with per-entry steps. Steps tau_j <= 1 / sum_i |K_ij| and
 * sigma_i <= 1 / sum_j |K_ij| converge without knowing ||K||.
 * Knows nothing about the problem. */
#pragma once
#include <stddef.h>

struct c0_pdhg_problem {
	size_t n, m;                 /* primal and dual sizes */
	void *ctx;
	void (*K)(void *ctx, const double *x, double *y);
	void (*KT)(void *ctx, const double *y, double *x);
	void (*prox_g)(void *ctx, double *x, const double *tau);
	void (*prox_fstar)(void *ctx, double *y, const double *sigma);
	const double *tau, *sigma;   /* n and m step sizes */
	void (*iter)(void *ctx, int it);  /* optional, after each iteration (progress) */
};

struct c0_pdhg_conf {
	int maxit;                   /* 3000 */
	double tol;                  /* 1e-4: relative change of x and of y per iteration */
	double relax;                /* 1.8: over-relaxation in (0, 2); 1 is plain PDHG */
};
#define C0_PDHG_DEFAULTS { 3000, 1e-4, 1.8 }

struct c0_pdhg_info { int iters, converged; double dx, dy; };

/* x (n) and y (m) hold the start and receive the result. */
int c0_pdhg_solve(const struct c0_pdhg_problem *p, const struct c0_pdhg_conf *c, double *x, double *y,
		  struct c0_pdhg_info *info);
