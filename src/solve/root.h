/* Safeguarded root finding for an increasing function on a log scale:
 * bracket by a Newton step on the expected slope, then by secant steps
 * (half again as far as the secant puts the root), then regula falsi
 * (Illinois) with bisection fallback. g is called with t = log(mu) and
 * returns g(mu). */
#pragma once

typedef double (*c0_scalar_fn)(void *ctx, double t);

enum c0_root_status {
	C0_ROOT_FOUND = 0,
	C0_ROOT_BELOW = 1,   /* g > 0 even at the smallest t tried: returned that t */
	C0_ROOT_ABOVE = 2,   /* g < 0 even at the largest t tried: returned that t */
	C0_ROOT_MAXIT = 3,
};

/* Finds t with |g(t)| <= ftol starting at t0; t range limited to [tmin, tmax].
 * slope: g's expected slope dg/dt, for the first step (0: a step of a decade). */
int c0_root_increasing(c0_scalar_fn g, void *ctx, double t0, double slope, double tmin, double tmax, double ftol,
		       int maxeval, double *t, int *evals);
