#include "solve/root.h"

#include <math.h>

int c0_root_increasing(c0_scalar_fn g, void *ctx, double t0, double slope, double tmin, double tmax, double ftol,
		       int maxeval, double *t, int *evals)
{
	const double step = log(10.0);
	int n = 0;
	double a = t0, fa = g(ctx, a);
	n++;
	*t = a;
	if (fabs(fa) <= ftol) {
		*evals = n;
		return C0_ROOT_FOUND;
	}
	/* bracket: walk downhill or uphill, first by the expected slope (or a
	 * decade), then half again as far as the secant through the last two
	 * values puts the root (or a decade), at most to the range's end: a g
	 * that flattens below zero reaches the end in a step or two */
	double b = a, fb = fa, p = NAN, fp = NAN;
	while ((fa > 0) == (fb > 0)) {
		if (n >= maxeval) {
			*t = b, *evals = n;
			return C0_ROOT_MAXIT;
		}
		p = a, fp = fa, a = b, fa = fb;
		const double end = fa > 0 ? tmin : tmax, s = n > 1 ? (fa - fp) / (a - p) : slope;
		if (fabs(a - end) <= 1e-9) {   /* the ends themselves are in range */
			*t = a, *evals = n;
			return fa > 0 ? C0_ROOT_BELOW : C0_ROOT_ABOVE;
		}
		const double d = s > 0 ? (n > 1 ? 1.5 : 1) * fabs(fa) / s : step;
		b = a + (fa > 0 ? -1 : 1) * fmin(d, fabs(end - a));
		fb = g(ctx, b);
		n++;
		*t = b;
		if (fabs(fb) <= ftol) {
			*evals = n;
			return C0_ROOT_FOUND;
		}
	}
	if (a > b) {
		double tt = a; a = b; b = tt;
		tt = fa; fa = fb; fb = tt;
	}
	/* now fa < 0 < fb: Illinois regula falsi, bisect when it stalls */
	int side = 0;
	while (n < maxeval) {
		double c = (a * fb - b * fa) / (fb - fa);
		if (!(c > a && c < b))
			c = 0.5 * (a + b);
		double fc = g(ctx, c);
		n++;
		*t = c;
		if (fabs(fc) <= ftol || b - a < 1e-12) {
			*evals = n;
			return C0_ROOT_FOUND;
		}
		if (fc < 0) {
			a = c, fa = fc;
			if (side == -1) fb /= 2;
			side = -1;
		} else {
			b = c, fb = fc;
			if (side == 1) fa /= 2;
			side = 1;
		}
	}
	*evals = n;
	return C0_ROOT_MAXIT;
}
