/* Simultaneous-direction ADMM (SDMM) for
 *   min_x  h(x) + F(K x) + i_{>=0}(x)
 * with three splits z1 = x, z2 = K x, z3 = x: each prox is exact (h's by a
 * callback, F's by a callback, positivity by clipping) and the x-update
 * solves (rho1 + rho3) x + rho2 K^T K x = rhs by warm-started CG.
 * Knows nothing about the problem. */
#pragma once
#include <stddef.h>

struct c0_admm_problem {
	size_t n, m;
	void *ctx;
	void (*prox_h)(void *ctx, const double *v, double rho, double *out);   /* argmin h + rho/2 ||. - v||^2 */
	void (*prox_f)(void *ctx, double *v, double rho);                     /* in place, argmin F + rho/2 ||. - v||^2 */
	void (*K)(void *ctx, const double *x, double *y);
	void (*KT)(void *ctx, const double *y, double *x);
};

struct c0_admm_conf { int maxit; double tol; double rho; int cg_iters; };  /* 300, 1e-4, 1, 10 */
#define C0_ADMM_DEFAULTS { 300, 1e-4, 1.0, 10 }

struct c0_admm_info { int iters, converged; double relchange; };

int c0_admm_solve(const struct c0_admm_problem *p, const struct c0_admm_conf *c, double *x, struct c0_admm_info *info);
