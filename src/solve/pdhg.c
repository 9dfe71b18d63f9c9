#include "solve/pdhg.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int c0_pdhg_solve(const struct c0_pdhg_problem *p, const struct c0_pdhg_conf *c, double *x, double *y,
		  struct c0_pdhg_info *info)
{
	const size_t n = p->n, m = p->m;
	double *xn = c0_alloc(n, sizeof *xn), *t = c0_alloc(n, sizeof *t), *s = c0_alloc(m, sizeof *s);
	memset(info, 0, sizeof *info);
	if (!xn || !t || !s) {
		free(xn), free(t), free(s);
		return C0_ENOMEM;
	}
	for (int it = 0; it < c->maxit; it++) {
		p->KT(p->ctx, y, t);
#pragma omp parallel for schedule(static) if (n > 50000)
		for (size_t i = 0; i < n; i++)
			xn[i] = x[i] - p->tau[i] * t[i];
		p->prox_g(p->ctx, xn, p->tau);
		double dx = 0, nx = 0;
#pragma omp parallel for schedule(static) reduction(+ : dx, nx) if (n > 50000)
		for (size_t i = 0; i < n; i++) {
			double d = xn[i] - x[i];
			t[i] = xn[i] + d;          /* the extrapolated point */
			x[i] += c->relax * d;
			dx += d * d, nx += xn[i] * xn[i];
		}
		p->K(p->ctx, t, s);
#pragma omp parallel for schedule(static) if (m > 50000)
		for (size_t i = 0; i < m; i++)
			s[i] = y[i] + p->sigma[i] * s[i];
		p->prox_fstar(p->ctx, s, p->sigma);
		double dy = 0, ny = 0;
#pragma omp parallel for schedule(static) reduction(+ : dy, ny) if (m > 50000)
		for (size_t i = 0; i < m; i++) {
			double d = s[i] - y[i];
			y[i] += c->relax * d;
			dy += d * d, ny += s[i] * s[i];
		}
		info->iters = it + 1;
		if (p->iter)
			p->iter(p->ctx, it + 1);
		info->dx = sqrt(dx / fmax(nx, 1e-300));
		info->dy = sqrt(dy / fmax(ny, 1e-300));
		if (it > 10 && info->dx <= c->tol && info->dy <= c->tol) {
			info->converged = 1;
			break;
		}
	}
	free(xn), free(t), free(s);
	return C0_OK;
}
