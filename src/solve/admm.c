#include "solve/admm.h"
#include "solve/cg.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct xop { const struct c0_admm_problem *p; double rho; double *t; };

/* (2 rho) x + rho K^T K x: rho1 = rho2 = rho3 = rho */
static void xnormal(void *vc, const double *in, double *out)
{
	struct xop *o = vc;
	o->p->K(o->p->ctx, in, o->t);
	o->p->KT(o->p->ctx, o->t, out);
	for (size_t i = 0; i < o->p->n; i++)
		out[i] = o->rho * (out[i] + 2 * in[i]);
}

int c0_admm_solve(const struct c0_admm_problem *p, const struct c0_admm_conf *c, double *x, struct c0_admm_info *info)
{
	const size_t n = p->n, m = p->m;
	const double rho = c->rho;
	double *z1 = c0_alloc(n, sizeof *z1), *w1 = c0_alloc(n, sizeof *w1), *z3 = c0_alloc(n, sizeof *z3);
	double *w3 = c0_alloc(n, sizeof *w3), *z2 = c0_alloc(m, sizeof *z2), *w2 = c0_alloc(m, sizeof *w2);
	double *kx = c0_alloc(m, sizeof *kx), *rhs = c0_alloc(n, sizeof *rhs), *t = c0_alloc(n, sizeof *t);
	double *xo = c0_alloc(n, sizeof *xo);
	int st = z1 && w1 && z3 && w3 && z2 && w2 && kx && rhs && t && xo ? C0_OK : C0_ENOMEM;
	struct xop op = { p, rho, kx };
	info->converged = 0;
	if (!st) {
		memcpy(z1, x, n * sizeof *x);
		memcpy(z3, x, n * sizeof *x);
		p->K(p->ctx, x, z2);
	}
	for (int it = 0; !st && it < c->maxit; it++) {
		/* x-update */
		for (size_t i = 0; i < m; i++)
			kx[i] = z2[i] - w2[i];
		p->KT(p->ctx, kx, rhs);
		for (size_t i = 0; i < n; i++)
			rhs[i] = rho * (rhs[i] + z1[i] - w1[i] + z3[i] - w3[i]);
		memcpy(xo, x, n * sizeof *x);
		struct c0_cg_info ci;
		if ((st = c0_cg(xnormal, &op, n, rhs, NULL, x, 1e-10, c->cg_iters, &ci)))
			break;
		/* z-updates and multipliers */
		for (size_t i = 0; i < n; i++)
			t[i] = x[i] + w1[i];
		p->prox_h(p->ctx, t, rho, z1);
		p->K(p->ctx, x, kx);
		for (size_t i = 0; i < m; i++)
			z2[i] = kx[i] + w2[i];
		p->prox_f(p->ctx, z2, rho);
		double dn = 0, xn = 0;
		for (size_t i = 0; i < n; i++) {
			z3[i] = fmax(0, x[i] + w3[i]);
			w1[i] += x[i] - z1[i];
			w3[i] += x[i] - z3[i];
			dn += (x[i] - xo[i]) * (x[i] - xo[i]);
			xn += x[i] * x[i];
		}
		for (size_t i = 0; i < m; i++)
			w2[i] += kx[i] - z2[i];
		info->iters = it + 1;
		info->relchange = sqrt(dn) / fmax(sqrt(xn), 1e-300);
		if (it > 5 && info->relchange <= c->tol) {
			info->converged = 1;
			break;
		}
	}
	/* return the feasible split: non-negative */
	if (!st)
		memcpy(x, z3, n * sizeof *x);
	free(z1), free(w1), free(z3), free(w3), free(z2), free(w2), free(kx), free(rhs), free(t), free(xo);
	return st;
}
