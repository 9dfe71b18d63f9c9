/* Over-relaxed primal-dual hybrid gradient (Chambolle-Pock 2011; Condat
 * 2013) for
 *   min_x  G(x) + F(K x)
 * The problem supplies K, K^T and the two proximal steps with its own
 * (e.g. diagonal, Pock-Chambolle 2011) step sizes tau and sigma, each step
 * fused with its relaxed update so that it is one pass over memory:
 *   primal_step: with t = K^T y on entry, xn = prox_{tau G}(x - tau t),
 *                then c0_pdhg_primal_entry for every entry;
 *   dual_step:   with s = K xbar, yn = prox_{sigma F*}(y + sigma s),
 *                then c0_pdhg_dual_entry for every entry.
 * Diagonal steps tau_j <= 1 / sum_i |K_ij|, sigma_i <= 1 / sum_j |K_ij|
 * converge without knowing ||K||. Iterates are float (half the memory
 * traffic of double and twice the SIMD width). The stopping test's sums are
 * float within a thread's share (vectorised; good to about 1e-4 relative,
 * plenty for a test on the relative change) and double across threads.
 * Knows nothing about the problem. */
#pragma once
#include <math.h>
#include <stddef.h>

struct c0_pdhg_problem {
	size_t n, m;                 /* primal and dual sizes */
	void *ctx;
	void (*K)(void *ctx, const float *x, float *y);
	void (*KT)(void *ctx, const float *y, float *x);
	void (*primal_step)(void *ctx, float *x, float *t, float rho, double sums[2]);
	void (*dual_step)(void *ctx, float *y, const float *s, float rho, double sums[2]);
	void (*iter)(void *ctx, int it);  /* optional, after each iteration (progress) */
	/* optional, used instead of KT + primal_step and K + dual_step: the same
	 * with the operator applied on the fly, when that saves a pass */
	void (*primal_fused)(void *ctx, const float *y, float *x, float *t, float rho, double sums[2]);
	void (*dual_fused)(void *ctx, const float *t, float *y, float rho, double sums[2]);
};

struct c0_pdhg_conf {
	int maxit;                   /* 3000 */
	double tol;                  /* 1e-4: relative change of x and of y per iteration */
	double relax;                /* 1.8: over-relaxation in (0, 2); 1 is plain PDHG */
};
#define C0_PDHG_DEFAULTS { 3000, 1e-4, 1.8 }

/* The relaxed updates of one entry, given its new value: x moves by rho
 * times the step, t receives the extrapolated point 2 xn - x, and sums
 * collect ||xn - x||^2 and ||xn||^2 for the stopping test. Over-relaxation
 * makes an entry whose prox is 0 decay as (1 - rho)^k; it is flushed to 0
 * before it turns subnormal, where float arithmetic is many times slower. */
#define C0_PDHG_TINY 1e-30f

static inline void c0_pdhg_primal_entry(float *x, float *t, float xn, float rho, float *d2, float *n2)
{
	float d = xn - *x, v = *x + rho * d;
	*t = xn + d;
	*x = fabsf(v) < C0_PDHG_TINY ? 0 : v;
	*d2 += d * d, *n2 += xn * xn;
}

static inline void c0_pdhg_dual_entry(float *y, float yn, float rho, float *d2, float *n2)
{
	float d = yn - *y, v = *y + rho * d;
	*y = fabsf(v) < C0_PDHG_TINY ? 0 : v;
	*d2 += d * d, *n2 += yn * yn;
}

struct c0_pdhg_info { int iters, converged; double dx, dy; };

/* x (n) and y (m) hold the start and receive the result. */
int c0_pdhg_solve(const struct c0_pdhg_problem *p, const struct c0_pdhg_conf *c, float *x, float *y,
		  struct c0_pdhg_info *info);
