/* FISTA for  min_{x >= 0}  f(x) + lam * sum_i w_i x_i  with f smooth (L-Lipschitz
 * gradient), gradient-based adaptive restart (O'Donoghue & Candes 2015).
 * Knows nothing about the problem: f comes as a callback. */
#pragma once
#include <stddef.h>

/* Returns f(x) and writes its gradient. */
typedef double (*c0_smooth_fn)(void *ctx, const double *x, double *grad);

struct c0_fista_conf {
	int maxit;        /* 1000 */
	double tol;       /* 1e-5: stop when ||x+ - x|| <= tol * max(||x+||, tiny) */
};
#define C0_FISTA_DEFAULTS { 1000, 1e-5 }

struct c0_fista_info {
	int iters, converged, restarts;
	double obj;        /* F at the last extrapolated point (f + penalty) */
	double *hist;      /* optional: F per iteration, capacity nhist */
	int nhist;
	/* optional momentum carried from one call to the next (a solve cut into
	 * pieces): prev holds the iterate before x and theta its step; both are
	 * read on entry (theta <= 1: none) and written on return */
	double *prev;
	double theta;
};

/* x holds the start and receives the result. w may be NULL (all ones). */
int c0_fista_nn(c0_smooth_fn f, void *ctx, size_t n, double lip, const double *w, double lam,
		double *x, const struct c0_fista_conf *conf, struct c0_fista_info *info);

/* CEL0 (Soubies et al. 2015) by iteratively reweighted l1: each outer step
 * solves a weighted non-negative l1 problem with
 *   w_i = max(0, sqrt(2 lam) a_i - a_i^2 x_i),  a_i = column norm of the data operator,
 * warm started. Stops when the iterate changes by < tol relatively. */
int c0_irl1_cel0(c0_smooth_fn f, void *ctx, size_t n, double lip, const double *anorm, double lam,
		 double *x, const struct c0_fista_conf *inner, int outer_max, double tol, struct c0_fista_info *info);
