#include "solve/cg.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Sums in DOT_LANES independent partial sums, added in a fixed order: one
 * chain of n dependent additions was bound by the addition's latency (three
 * such sums a CG step, of the intensity step's 75 k unknowns), and the
 * fixed lanes give the same bits whatever the vector width. */
#define DOT_LANES 8
static double lanes_total(const double s[DOT_LANES])
{
	return ((s[0] + s[4]) + (s[1] + s[5])) + ((s[2] + s[6]) + (s[3] + s[7]));
}

static double dot(const double *a, const double *b, size_t n)
{
	double s[DOT_LANES] = { 0 };
	size_t i = 0;
	for (; i + DOT_LANES <= n; i += DOT_LANES)
		for (int j = 0; j < DOT_LANES; j++)
			s[j] += a[i + j] * b[i + j];
	for (; i < n; i++)
		s[i % DOT_LANES] += a[i] * b[i];
	return lanes_total(s);
}

/* x += a p, r -= a q; returns ||r||^2 (in lanes, as dot) */
static double update(double *x, double *r, const double *p, const double *q, double a, size_t n)
{
	double s[DOT_LANES] = { 0 };
	size_t i = 0;
	for (; i + DOT_LANES <= n; i += DOT_LANES)
		for (int j = 0; j < DOT_LANES; j++) {
			x[i + j] += a * p[i + j], r[i + j] -= a * q[i + j];
			s[j] += r[i + j] * r[i + j];
		}
	for (; i < n; i++) {
		x[i] += a * p[i], r[i] -= a * q[i];
		s[i % DOT_LANES] += r[i] * r[i];
	}
	return lanes_total(s);
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
		const double rr = update(x, r, p, q, a, n);
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
