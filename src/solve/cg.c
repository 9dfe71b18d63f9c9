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

struct diag { const double *d; size_t n; };

static void diag_apply(void *ctx, const double *in, double *out)
{
	const struct diag *g = ctx;
	for (size_t i = 0; i < g->n; i++)
		out[i] = g->d ? g->d[i] * in[i] : in[i];
}

int c0_cg(c0_linop_fn A, void *ctx, size_t n, const double *b, const double *dinv, double *x, double tol,
	  int maxit, struct c0_cg_info *info)
{
	struct diag g = { dinv, n };
	return c0_pcg(A, ctx, n, b, diag_apply, &g, x, tol, maxit, info);
}

int c0_pcg(c0_linop_fn A, void *ctx, size_t n, const double *b, c0_linop_fn M, void *mctx, double *x, double tol,
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
	for (size_t i = 0; i < n; i++)
		r[i] = b[i] - q[i];
	M(mctx, r, z);
	memcpy(p, z, n * sizeof *p);
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
		const double a = rz / pq;
		double rr = 0;
		for (size_t i = 0; i < n; i++) {
			x[i] += a * p[i], r[i] -= a * q[i];
			rr += r[i] * r[i];
		}
		M(mctx, r, z);
		const double rz2 = dot(r, z, n), beta = rz2 / rz;
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
