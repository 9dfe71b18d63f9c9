/* Safeguarded root finding for an increasing function on a log scale:
 * bracket by factor-of-10 steps, then regula falsi (Illinois) with bisection
 * fallback. g is called with t = log(mu) and returns g(mu). */
#pragma once

typedef double (*c0_scalar_fn)(void *ctx, double t);

enum c0_root_status {
	C0_ROOT_FOUND = 0,
	C0_ROOT_BELOW = 1,   /* g > 0 even at the smallest t tried: returned that t */
	C0_ROOT_ABOVE = 2,   /* g < 0 even at the largest t tried: returned that t */
	C0_ROOT_MAXIT = 3,
};

/* Finds t with |g(t)| <= ftol starting at t0; t range limited to [tmin, tmax]. */
int c0_root_increasing(c0_scalar_fn g, void *ctx, double t0, double tmin, double tmax, double ftol,
		       int maxeval, double *t, int *evals);
