/* Adapters from each operator's own calls to the common shape. The casts
 * drop const only to fit one context type; no adapter writes through it
 * except the covariance operator, whose workspaces are its own. */
#include "testkit/linop.h"
#include "ops/blur2.h"
#include "core/band.h"
#include "ops/covop.h"
#include "ops/diff3.h"
#include "ops/grad3m.h"
#include "ops/psi_omega.h"
#include "ops/tirfop.h"
#include "testkit/reference.h"

#include <string.h>

static void covop_fw(void *c, const double *x, double *y)
{
	const struct c0_covop_band *b = c;
	c0_covop_forward(b->op, b->cov, x, y);
}
static void covop_ad(void *c, const double *y, double *x)
{
	const struct c0_covop_band *b = c;
	c0_covop_adjoint(b->op, b->cov, y, x);
}
struct c0_linop c0_covop_linop(struct c0_covop_band *b)
{
	const size_t nin = (size_t)b->op->Ly * b->op->Lx, np = (size_t)b->op->Ny * b->op->Nx;
	return (struct c0_linop){ nin, (size_t)b->cov->nlag * np, b, covop_fw, covop_ad };
}

static void psi_fw(void *c, const double *x, double *y) { c0_covop_psi(c, x, y); }
static void psi_ad(void *c, const double *y, double *x) { c0_covop_psit(c, y, x); }
struct c0_linop c0_covop_psi_linop(struct c0_covop *op)
{
	return (struct c0_linop){ (size_t)op->Ly * op->Lx, (size_t)op->Ny * op->Nx, op, psi_fw, psi_ad };
}

static void pso_fw(void *c, const double *x, double *y) { c0_psi_omega_forward(c, x, y); }
static void pso_ad(void *c, const double *y, double *x) { c0_psi_omega_adjoint(c, y, x); }
struct c0_linop c0_psi_omega_linop(const struct c0_psi_omega *p)
{
	return (struct c0_linop){ (size_t)p->n, (size_t)p->Ny * p->Nx, (void *)p, pso_fw, pso_ad };
}

static void gro_fw(void *c, const double *x, double *y) { c0_grad_omega(c, x, y); }
static void gro_ad(void *c, const double *y, double *x) { c0_grad_omega_adjoint(c, y, x); }
struct c0_linop c0_grad_omega_linop(const struct c0_psi_omega *p)
{
	return (struct c0_linop){ (size_t)p->n, (size_t)p->ne, (void *)p, gro_fw, gro_ad };
}

static void band_fw(void *c, const double *x, double *y)
{
	const struct c0_band_rows *b = c;
	c0_band_apply_x(b->b, b->ny, x, y);
}
static void band_ad(void *c, const double *y, double *x)
{
	const struct c0_band_rows *b = c;
	const struct c0_band *B = b->b;
	memset(x, 0, sizeof *x * (size_t)b->ny * B->n);
	for (int r = 0; r < b->ny; r++)
		for (int i = 0; i < B->m; i++)
			for (int k = 0; k < B->w; k++)
				x[(size_t)r * B->n + B->start[i] + k] += B->v[(size_t)i * B->w + k] * y[(size_t)r * B->m + i];
}
struct c0_linop c0_band_linop(struct c0_band_rows *b)
{
	return (struct c0_linop){ (size_t)b->ny * b->b->n, (size_t)b->ny * b->b->m, b, band_fw, band_ad };
}

static size_t diff3_n(const struct c0_diff3 *d) { return (size_t)d->nx * d->ny * d->nz; }
static void grad3_fw(void *c, const float *x, float *y) { c0_grad3(c, x, y); }
static void grad3_ad(void *c, const float *y, float *x) { c0_grad3_adjoint(c, y, x); }
struct c0_linopf c0_grad3_linop(const struct c0_diff3 *d)
{
	return (struct c0_linopf){ diff3_n(d), 3 * diff3_n(d), (void *)d, grad3_fw, grad3_ad };
}

static void hess3_fw(void *c, const float *x, float *y) { c0_hess3(c, x, y); }
static void hess3_ad(void *c, const float *y, float *x) { c0_hess3_adjoint(c, y, x); }
struct c0_linopf c0_hess3_linop(const struct c0_diff3 *d)
{
	return (struct c0_linopf){ diff3_n(d), 6 * diff3_n(d), (void *)d, hess3_fw, hess3_ad };
}

static void g3m_fw(void *c, const float *x, float *y) { c0_grad3m_forward(c, x, y); }
static void g3m_ad(void *c, const float *y, float *x) { c0_grad3m_adjoint(c, y, x); }
struct c0_linopf c0_grad3m_linop(const struct c0_grad3m *g)
{
	const size_t n = (size_t)g->M * g->nz;
	return (struct c0_linopf){ n, (size_t)g->nc * n, (void *)g, g3m_fw, g3m_ad };
}

static void tirf_fw(void *c, const float *x, float *y) { c0_tirfop_forward(c, x, y); }
static void tirf_ad(void *c, const float *y, float *x)
{
	const struct c0_tirfop *o = c;
	memset(x, 0, sizeof *x * o->M * (size_t)o->nz);
	c0_tirfop_adjoint_add(o, y, x);
}
struct c0_linopf c0_tirfop_linop(const struct c0_tirfop *o)
{
	return (struct c0_linopf){ o->M * (size_t)o->nz, o->M * (size_t)o->nq, (void *)o, tirf_fw, tirf_ad };
}

static void blur_fw(void *c, const float *x, float *y)
{
	const struct c0_blur2 *b = c;
	memcpy(y, x, sizeof *y * b->ny * (size_t)b->nx);
	c0_blur2_apply(b, y, 1);
}
struct c0_linopf c0_blur2_linop(const struct c0_blur2 *b)
{
	const size_t np = (size_t)b->ny * b->nx;
	return (struct c0_linopf){ np, np, (void *)b, blur_fw, blur_fw };   /* symmetric */
}
