#include "solve/pdhg.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int c0_pdhg_solve(const struct c0_pdhg_problem *p, const struct c0_pdhg_conf *c, float *x, float *y,
		  struct c0_pdhg_info *info)
{
	const size_t n = p->n, m = p->m;
	const float rho = (float)c->relax;
	float *t = c0_alloc(n, sizeof *t), *s = p->dual_fused ? NULL : c0_alloc(m, sizeof *s);
	memset(info, 0, sizeof *info);
	if (!t || (!s && !p->dual_fused)) {
		free(t), free(s);
		return C0_ENOMEM;
	}
	for (int it = 0; it < c->maxit; it++) {
		double px[2] = { 0, 0 }, py[2] = { 0, 0 };
		if (p->primal_fused)
			p->primal_fused(p->ctx, y, x, t, rho, px);
		else {
			p->KT(p->ctx, y, t);
			p->primal_step(p->ctx, x, t, rho, px);
		}                                        /* t: the extrapolated point */
		if (p->dual_fused)
			p->dual_fused(p->ctx, t, y, rho, py);
		else {
			p->K(p->ctx, t, s);
			p->dual_step(p->ctx, y, s, rho, py);
		}
		info->iters = it + 1;
		if (p->iter)
			p->iter(p->ctx, it + 1);
		info->dx = sqrt(px[0] / fmax(px[1], 1e-300));
		info->dy = sqrt(py[0] / fmax(py[1], 1e-300));
		if (it > 10 && info->dx <= c->tol && info->dy <= c->tol) {
			info->converged = 1;
			break;
		}
	}
	free(t), free(s);
	return C0_OK;
}
