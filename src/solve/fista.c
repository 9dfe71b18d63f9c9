#include "solve/fista.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int c0_fista_nn(c0_smooth_fn f, void *ctx, size_t n, double lip, const double *w, double lam,
		double *x, const struct c0_fista_conf *conf, struct c0_fista_info *info)
{
	if (!(lip > 0) || !(lam >= 0))
		return c0_fail(C0_EINVAL, "fista: need a positive Lipschitz constant and lambda >= 0 (got %g, %g)", lip, lam);
	const size_t nb = (n + C0_SUM_BLOCK - 1) / C0_SUM_BLOCK;
	double *z = c0_alloc(n, sizeof *z), *g = c0_alloc(n, sizeof *g), *xn = c0_alloc(n, sizeof *xn);
	double *part = c0_alloc(4 * nb + 4, sizeof *part);
	if (!z || !g || !xn || !part) {
		free(z), free(g), free(xn), free(part);
		return C0_ENOMEM;
	}
	double theta = info->prev && info->theta > 1 ? info->theta : 1, step = 1 / lip;
	if (theta > 1) {
		/* resume: z = x + beta (x - prev) as if the run had not stopped */
		const double tp = (1 + sqrt(1 + 4 * theta * theta)) / 2, beta = (theta - 1) / tp;
		for (size_t i = 0; i < n; i++)
			z[i] = fmax(0, x[i] + beta * (x[i] - info->prev[i]));
		theta = tp;
	} else
		memcpy(z, x, n * sizeof *x);
	int nh = info->nhist, restarts = 0;
	info->iters = info->converged = 0;
	for (int it = 0; it < conf->maxit; it++) {
		double fz = f(ctx, z, g), pen = 0, dn = 0, dot = 0, vv = 0;
		/* block by block (C0_SUM_BLOCK): x+ = max(0, z - step (g + lam w)),
		 * then the sums in a loop of their own (both loops vectorise; with
		 * the clamp among the sums one would not) */
#pragma omp parallel for schedule(static) if (n > 100000)
		for (size_t b = 0; b < nb; b++) {
			const size_t i0 = b * C0_SUM_BLOCK, i1 = n - i0 < C0_SUM_BLOCK ? n : i0 + C0_SUM_BLOCK;
			double pb = 0, db = 0, ob = 0, vb = 0;
			if (w) {
#pragma omp simd reduction(+ : pb)
				for (size_t i = i0; i < i1; i++) {
					pb += w[i] * z[i];
					double v = z[i] - step * (g[i] + lam * w[i]);
					xn[i] = v > 0 ? v : 0;
				}
			} else {
#pragma omp simd reduction(+ : pb)
				for (size_t i = i0; i < i1; i++) {
					pb += z[i];
					double v = z[i] - step * (g[i] + lam);
					xn[i] = v > 0 ? v : 0;
				}
			}
#pragma omp simd reduction(+ : db, ob, vb)
			for (size_t i = i0; i < i1; i++) {
				const double d = xn[i] - x[i];
				db += d * d;
				ob += (z[i] - xn[i]) * d;     /* restart test <z - x+, x+ - x> */
				vb += xn[i] * xn[i];
			}
			part[4 * b] = pb, part[4 * b + 1] = db, part[4 * b + 2] = ob, part[4 * b + 3] = vb;
		}
		for (size_t b = 0; b < nb; b++)
			pen += part[4 * b], dn += part[4 * b + 1], dot += part[4 * b + 2], vv += part[4 * b + 3];
		info->obj = fz + lam * pen;
		if (info->hist && it < nh)
			info->hist[it] = info->obj;
		info->iters = it + 1;
		double xnorm = sqrt(vv);
		double tp = (1 + sqrt(1 + 4 * theta * theta)) / 2, beta = (theta - 1) / tp;
		if (dot > 0) {
			beta = 0, tp = 1;   /* momentum points uphill: restart */
			restarts++;
		}
		const int stop = sqrt(dn) <= conf->tol * fmax(xnorm, 1e-300);
		if (info->prev && (stop || it == conf->maxit - 1))   /* only the last is read (a resume) */
			memcpy(info->prev, x, n * sizeof *x);
#pragma omp parallel for if (n > 100000)
		for (size_t i = 0; i < n; i++) {
			z[i] = xn[i] + beta * (xn[i] - x[i]);
			x[i] = xn[i];
		}
		theta = tp;
		if (stop) {
			info->converged = 1;
			break;
		}
	}
	info->restarts = restarts;
	info->theta = theta;
	free(z), free(g), free(xn), free(part);
	return C0_OK;
}

int c0_irl1_cel0(c0_smooth_fn f, void *ctx, size_t n, double lip, const double *anorm, double lam,
		 double *x, const struct c0_fista_conf *inner, int outer_max, double tol, struct c0_fista_info *info)
{
	double *w = c0_alloc(n, sizeof *w), *prev = c0_alloc(n, sizeof *prev);
	if (!w || !prev) {
		free(w), free(prev);
		return C0_ENOMEM;
	}
	int total = 0, st = C0_OK;
	info->converged = 0;
	double s2l = sqrt(2 * lam);
	struct c0_fista_info in = *info;
	for (int k = 0; k < outer_max && !st; k++) {
		for (size_t i = 0; i < n; i++) {
			double v = s2l * anorm[i] - anorm[i] * anorm[i] * fabs(x[i]);
			w[i] = v > 0 ? v : 0;
		}
		memcpy(prev, x, n * sizeof *x);
		in.hist = info->hist ? info->hist + total : NULL;
		in.nhist = info->hist ? info->nhist - total : 0;
		if (in.nhist < 0)
			in.nhist = 0;
		st = c0_fista_nn(f, ctx, n, lip, w, 1, x, inner, &in);
		total += in.iters;
		double dn = 0, xn = 0;
		for (size_t i = 0; i < n; i++)
			dn += (x[i] - prev[i]) * (x[i] - prev[i]), xn += x[i] * x[i];
		if (k > 0 && sqrt(dn) <= tol * fmax(sqrt(xn), 1e-300)) {
			info->converged = 1;
			break;
		}
	}
	info->iters = total;
	info->obj = in.obj;
	info->restarts = in.restarts;
	free(w), free(prev);
	return st;
}
