#include "solve/cg.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double dot(const double *a, const double *b, size_t n)
{
	double s = 0;
	for (size_t i = 0; i < n; i++)
		s += a[i] * b[i];
	return s;
}

int c0_cg(c0_linop_fn A, void *ctx, size_t n, const double *b, const double *dinv, double *x, double tol,
	  int maxit, struct c0_cg_info *info)
{
	double *r = c0_alloc(n, sizeof *r), *p = c0_alloc(n, sizeof *p), *q = c0_alloc(n, sizeof *q);
	double *z = c0_alloc(n, sizeof *z);
	if (!r || !p || !q || !z) {
		free(r), free(p), free(q), free(z);
		return C0_ENOMEM;
	}
	double bn = sqrt(dot(b, b, n));
	info->iters = 0, info->converged = 0, info->relres = 0;
	if (bn == 0) {
		memset(x, 0, n * sizeof *x);
		info->converged = 1;
		goto out;
	}
	A(ctx, x, q);
	for (size_t i = 0; i < n; i++) {
		r[i] = b[i] - q[i];
		p[i] = z[i] = dinv ? dinv[i] * r[i] : r[i];
	}
	double rz = dot(r, z, n), rn = sqrt(dot(r, r, n));
	for (int it = 0; it < maxit; it++) {
		info->relres = rn / bn;
		if (info->relres <= tol) {
			info->converged = 1;
			break;
		}
		A(ctx, p, q);
		double pq = dot(p, q, n);
		if (!(pq > 0))           /* semidefinite direction: nothing more to gain */
			break;
		/* one pass for the update, the preconditioner and both sums (each
		 * summed in index order, as apart: the same numbers); two
		 * independent sums, where apart each waited on its own adds */
		const double a = rz / pq;
		double rz2 = 0, rr = 0;
		for (size_t i = 0; i < n; i++) {
			x[i] += a * p[i], r[i] -= a * q[i];
			z[i] = dinv ? dinv[i] * r[i] : r[i];
			rz2 += r[i] * z[i], rr += r[i] * r[i];
		}
		const double beta = rz2 / rz;
		for (size_t i = 0; i < n; i++)
			p[i] = z[i] + beta * p[i];
		rz = rz2;
		rn = sqrt(rr);
		info->iters = it + 1;
	}
	info->relres = rn / bn;
	info->converged |= info->relres <= tol;
out:
	free(r), free(p), free(q), free(z);
	return C0_OK;
}
