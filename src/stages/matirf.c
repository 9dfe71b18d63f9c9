/* MA-TIRF's entry point: the checks, one level of the solve (its setup,
 * the choice of steps, the run and the unpacking of the result) and the
 * objective; the steps themselves are in matirf_steps.c and matirf_exact.c
 * (matirf_ctx.h says which file holds what). */
#include "stages/matirf_ctx.h"
#include "ops/tirfop.h"
#include "optics/psf.h"
#include "solve/prox_schatten.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"

#include <stdlib.h>
#include <limits.h>
#include <stdint.h>
#include <string.h>

/* One level of the solve: mx0 > 0 fixes the data scale (a coarse level
 * solves in the fine level's units); coarse: levels of warm start below it;
 * yout, when not NULL, receives the final TV dual of the exact and apg
 * solvers by columns (2 nz M floats, allocated; NULL for the others). */
static int matirf_level(const struct c0_matirf_conf *c, int nq, const double *angles, const double *gain,
			const float *const *x, int ny, int nx, double mx0, int coarse, float **yout, struct c0_matirf_result *res);

int c0_matirf_check(const struct c0_matirf_conf *c, int nq, const double *angles)
{
	int st = c0_tirf_check(&c->tirf);
	if (st)
		return st;
	if (nq < 2 || nq > MAXQ)
		return c0_fail(C0_EINVAL, "angles: MA-TIRF needs 2..%d angles (got %d)", MAXQ, nq);
	for (int q = 0; q < nq; q++) {
		double p;
		if (c0_tirf_p(&c->tirf, angles[q], &p))
			return c0_fail_prefix(C0_EINVAL, "angles");
	}
	if (!(c->dz_nm > 0) || !(c->z1_nm > c->z0_nm) || !(c->z0_nm >= 0) || !isfinite(c->z1_nm))
		return c0_fail(C0_EINVAL, "matirf: depth bins z0_nm %g, z1_nm %g, dz_nm %g: need 0 <= z0 < z1 and dz > 0", c->z0_nm, c->z1_nm, c->dz_nm);
	if ((c->z1_nm - c->z0_nm) / c->dz_nm > 512)
		return c0_fail(C0_EINVAL, "matirf: more than 512 depth bins");
	if (!(c->bg_smooth >= 0))
		return c0_fail(C0_EINVAL, "matirf: bg_smooth %g: must be >= 0", c->bg_smooth);
	if (!(c->psf_sigma_px >= 0) || c->psf_sigma_px > 12)
		return c0_fail(C0_EINVAL, "matirf: psf_sigma_px %g: must be finite, in [0, 12]", c->psf_sigma_px);
	if (!(c->gamma > 0))
		return c0_fail(C0_EINVAL, "matirf: gamma %g must be > 0", c->gamma);
	if (!(c->kappa >= 0 && isfinite(c->kappa)) || !(c->wz >= 0 && isfinite(c->wz)) || !(c->sparsity >= 0 && isfinite(c->sparsity)))
		return c0_fail(C0_EINVAL, "matirf: kappa %g, wz %g, sparsity %g: must be finite and >= 0", c->kappa, c->wz,
			       c->sparsity);
	if (c->halo < 0 || c->halo > 64)
		return c0_fail(C0_EINVAL, "matirf: halo %d: must be 0..64", c->halo);
	if (!(c->coarse_tol >= 0 && isfinite(c->coarse_tol)))
		return c0_fail(C0_EINVAL, "matirf: coarse_tol %g: must be >= 0", c->coarse_tol);
	if (c->coarse < 0 || c->coarse > 8)
		return c0_fail(C0_EINVAL, "matirf: coarse %d: must be 0..8", c->coarse);
	if (c->pdhg.maxit < 1)
		return c0_fail(C0_EINVAL, "matirf: pdhg.maxit %d: must be at least 1", c->pdhg.maxit);
	if (!(c->pdhg.tol >= 0 && isfinite(c->pdhg.tol)) || !(c->pdhg.relax > 0 && c->pdhg.relax < 2))
		return c0_fail(C0_EINVAL, "matirf: pdhg.tol %g: must be >= 0 (relaxation %g in (0, 2))", c->pdhg.tol, c->pdhg.relax);
	return C0_OK;
}

int c0_matirf_subtract(float *const *x, int nq, size_t np, double v, const char *what)
{
	if (!(v == v) || v < 0)
		return c0_fail(C0_EINVAL, "%s %g: must be >= 0", what, v);
	for (int q = 0; q < nq && v > 0; q++) {
		double s = 0;
		for (size_t p = 0; p < np; p++)
			s += x[q][p];
		if (!(v < s / np))
			return c0_fail(C0_EINVAL, "%s %g: not below the mean of image %d (%g): nothing would be left of it", what,
				       v, q + 1, s / np);
	}
	for (int q = 0; q < nq && v > 0; q++)
		for (size_t p = 0; p < np; p++)
			x[q][p] -= (float)v;
	return C0_OK;
}

void c0_matirf_result_free(struct c0_matirf_result *r)
{
	free(r->f), free(r->pixel), free(r->z_nm), free(r->depth), free(r->total), free(r->background);
	memset(r, 0, sizeof *r);
}

void c0_matirf_plane(const struct c0_matirf_result *r, int j, float *plane)
{
	memset(plane, 0, sizeof *plane * r->ny * (size_t)r->nx);
	for (size_t k = 0; k < (size_t)r->M; k++)
		plane[r->pixel[k]] = r->f[j * (size_t)r->M + k];
}

float *c0_matirf_dense(const struct c0_matirf_result *r)
{
	const size_t np = (size_t)r->ny * r->nx;
	float *v = r->f ? c0_alloc(np * r->nz, sizeof *v) : NULL;
	for (int j = 0; v && j < r->nz; j++)
		c0_matirf_plane(r, j, v + j * np);
	return v;
}

/* The objective at u (scaled units): 1/2 ||B W u - b||^2 + kappa R(u) + l1 sum u,
 * to compare solvers; work: ncomp N floats. */
static double objective(struct matirf_ctx *c, const float *u, float *work)
{
	const size_t M = c->M, N = c->N;
	double data = 0, reg = 0, l1 = 0;
	if (c->blur.k) {          /* 1/2 ||B W u - b||^2 */
		const struct c0_tirfop w = { c->nq, c->nz, M, c->W };
		c0_tirfop_forward(&w, u, c->dwork);
		c0_blur2_apply(&c->blur, c->dwork, c->nq);
		for (size_t i = 0; i < (size_t)c->nq * M; i++)
			data += 0.5 * ((double)c->dwork[i] - c->b[i]) * ((double)c->dwork[i] - c->b[i]);
	} else
		for (size_t k = 0; k < M; k++)
			for (int q = 0; q < c->nq; q++) {
				double s = -c->b[q * M + k];
				for (int j = 0; j < c->nz; j++)
					s += c->W[q * c->nz + j] * u[j * M + k];
				data += 0.5 * s * s;
			}
	for (size_t i = 0; i < N; i++)
		l1 += u[i];
	if (c->reg == C0_REG_TV) {
		c0_grad3m_forward(&c->g, u, work);
		for (size_t i = 0; i < N; i++) {
			double s = 0;
			for (int e = 0; e < c->ncomp; e++)
				s += (double)work[e * N + i] * work[e * N + i];
			reg += sqrt(s);
		}
	} else {
		c0_hess3(&c->d, u, work);
		const double r2 = sqrt(2.0);
		for (size_t i = 0; i < N; i++) {
			double h[6], v[3][3];
			for (int e = 0; e < 6; e++)
				h[e] = work[e * N + i];
			double a[3][3] = { { h[0], h[3] / r2, h[4] / r2 }, { h[3] / r2, h[1], h[5] / r2 }, { h[4] / r2, h[5] / r2, h[2] } };
			c0_eig3(a, v);
			reg += fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
		}
	}
	return data + c->kappa * reg + c->l1 * l1;
}

int c0_matirf_nz(const struct c0_matirf_conf *c)
{
	return (int)ceil((c->z1_nm - c->z0_nm) / c->dz_nm - 1e-9);
}

int c0_matirf_solve(const struct c0_matirf_conf *c, int nq, const double *angles, const double *gain,
		    const float *const *x, int ny, int nx, struct c0_matirf_result *res)
{
	/* a wider PSF is no longer a lateral blur of this field but most of it */
	const double fw = c->psf_sigma_px * sqrt(8 * log(2.0));
	memset(res, 0, sizeof *res);
	int st = c0_matirf_check(c, nq, angles);
	if (st)
		return st;
	if ((double)ny * nx > INT_MAX)
		return c0_fail(C0_EINVAL, "matirf: a %dx%d grid has more pixels than the columns' index holds", nx, ny);
	if (fw > (ny < nx ? ny : nx) / 4.0)
		return c0_fail(C0_EINVAL, "psf_fwhm_nm: a FWHM of %.3g pixels is wider than a quarter of the %dx%d field", fw,
			       nx, ny);
	return matirf_level(c, nq, angles, gain, x, ny, nx, 0, c->coarse, NULL, res);
}

/* One level's problem and its buffers */
struct level {
	struct matirf_ctx ctx;
	double W[MAXQ * 512], col[512];   /* W column-normalised; col: the norms */
	float kern[2 * 64 + 1];           /* the PSF's 1D kernel */
	float *b, *u, *y, *tau, *b0;      /* data, primal, dual, primal steps, data before background */
	size_t m;                         /* the dual's length */
	double mx;                        /* the data scale */
};

/* W, column-normalised (the solver works on u = col f), and the data scale:
 * the images' global maximum, or mx0 > 0 (a coarse level's) */
static int level_weights(struct level *L, const struct c0_matirf_conf *c, int nq, const double *angles,
			 const double *gain, const float *const *x, size_t np, double mx0)
{
	const int nz = L->ctx.nz;
	double *W = L->W;
	int st = c0_tirf_weights(&c->tirf, nq, angles, gain, nz, c->z0_nm, c->dz_nm, W);
	if (st)
		return st;
	for (int j = 0; j < nz; j++) {
		double s = 0;
		for (int q = 0; q < nq; q++)
			s += W[q * nz + j] * W[q * nz + j];
		L->col[j] = sqrt(s);
		for (int q = 0; q < nq; q++)
			W[q * nz + j] /= L->col[j];
	}
	double mx = 0;
	for (int q = 0; q < nq; q++)
		for (size_t p = 0; p < np; p++)
			mx = fmax(mx, x[q][p]);
	if (!(mx > 0))
		return c0_fail(C0_EINVAL, "the angle images are empty (no positive value)");
	L->mx = mx0 > 0 ? mx0 : mx;
	return C0_OK;
}

/* the mask (0/1) grown by steps 4-neighbour steps; a pixel added in a step
 * is 2 until the step ends */
static void mask_dilate(uint8_t *mask, int ny, int nx, int steps)
{
	for (int s = 0; s < steps; s++) {
		for (int y = 0; y < ny; y++)
			for (int x = 0; x < nx; x++) {
				const size_t p = (size_t)y * nx + x;
				if (!mask[p])
					mask[p] = 2 * ((x > 0 && mask[p - 1] == 1) || (x + 1 < nx && mask[p + 1] == 1) ||
						       (y > 0 && mask[p - nx] == 1) || (y + 1 < ny && mask[p + nx] == 1));
			}
		for (size_t p = 0; p < (size_t)ny * nx; p++)
			mask[p] = mask[p] != 0;
	}
}

/* The columns solved for and the solver: TV solves only for the pixels with
 * signal in some image (a pixel that is zero at every angle has f = 0); the
 * Hessian, the background and the blur work on the full grid. */
static int level_grid(struct level *L, const struct c0_matirf_conf *c, int nq, const float *const *x, int ny, int nx)
{
	struct matirf_ctx *ctx = &L->ctx;
	const int nz = ctx->nz;
	const size_t np = (size_t)ny * nx;
	uint8_t *mask = c0_alloc(np, 1);
	if (!mask)
		return C0_ENOMEM;
	for (size_t p = 0; p < np; p++)
		for (int q = 0; q < nq; q++)
			mask[p] |= c->reg == C0_REG_HESSIAN || c->bg_smooth > 0 || c->psf_sigma_px > 0 || c->full_grid || x[q][p] > 0;
	mask_dilate(mask, ny, nx, c->halo);
	int st = c0_grad3m_init(&ctx->g, mask, ny, nx, nz, 1, c->wz);
	free(mask);
	if (st)
		return st;
	ctx->M = ctx->g.M, ctx->N = (size_t)ctx->g.M * nz;
	ctx->ncomp = c->reg == C0_REG_TV ? ctx->g.nc : 6;
	ctx->exact = (c->solver == C0_MATIRF_EXACT || c->solver == C0_MATIRF_APG) && nz <= C0_NNQP_MAX;
	ctx->apg = ctx->exact && c->solver == C0_MATIRF_APG;
	ctx->ny = ny, ctx->nx = nx, ctx->bg_smooth = c->bg_smooth;
	return C0_OK;
}

/* the blur's kernel and every buffer of the level and of the result */
static int level_alloc(struct level *L, const struct c0_matirf_conf *c, size_t np, struct c0_matirf_result *res)
{
	struct matirf_ctx *ctx = &L->ctx;
	const size_t M = ctx->M, N = ctx->N, nd = (size_t)ctx->nq * M;
	const int nz = ctx->nz;
	int st = C0_OK;
	if (c->psf_sigma_px > 0) {
		double kd[2 * 64 + 1];
		int r = (int)ceil(C0_PSF_CUTOFF * c->psf_sigma_px);
		r = r > 64 ? 64 : r;
		c0_psf_pixel_weights(0.5, c->psf_sigma_px, -r, 2 * r + 1, kd);
		for (int i = 0; i <= 2 * r; i++)
			L->kern[i] = (float)kd[i];
		ctx->blur = (struct c0_blur2){ ctx->ny, ctx->nx, r, L->kern, c0_alloc(np, sizeof(float)) };
		if (!ctx->blur.work)
			st = C0_ENOMEM;
	}
	if ((c->psf_sigma_px > 0 || c->bg_smooth > 0) && !(ctx->dwork = c0_alloc(nd, sizeof(float))))
		st = C0_ENOMEM;
	if (c->psf_sigma_px > 0 && ctx->exact &&
	    (!(ctx->dwork2 = c0_alloc(nd, sizeof(float))) || (!ctx->apg && !(ctx->corr = c0_alloc(N, sizeof(float))))))
		st = C0_ENOMEM;
	if (c->bg_smooth > 0) {
		ctx->bg = c0_alloc(M, sizeof *ctx->bg), ctx->bgd = c0_alloc(M, sizeof *ctx->bgd), ctx->bgr = c0_alloc(M, sizeof *ctx->bgr);
		L->b0 = c0_alloc(nd, sizeof *L->b0);
		res->background = c0_alloc(np, sizeof *res->background);
		if (!ctx->bg || !ctx->bgd || !ctx->bgr || !L->b0 || !res->background)
			st = C0_ENOMEM;
	}
	L->m = ctx->exact ? ctx->ncomp * N : nd + ctx->ncomp * N;
	L->b = c0_alloc(nd, sizeof *L->b), L->u = c0_alloc(N, sizeof *L->u), L->y = c0_alloc(L->m, sizeof *L->y);
	L->tau = c0_alloc(N, sizeof *L->tau);
	if (ctx->exact && !(ctx->c = c0_alloc(N, sizeof *ctx->c)))
		st = C0_ENOMEM;
	if (c->reg == C0_REG_HESSIAN && !(ctx->d.work = c0_alloc(2 * N, sizeof *ctx->d.work)))
		st = C0_ENOMEM;
	res->f = c0_alloc(N, sizeof *res->f);
	res->z_nm = c0_alloc((size_t)nz, sizeof *res->z_nm);
	res->depth = c0_alloc(np, sizeof *res->depth);
	res->total = c0_alloc(np, sizeof *res->total);
	if (st || !L->b || !L->u || !L->y || !L->tau || !res->f || !res->z_nm || !res->depth || !res->total)
		return C0_ENOMEM;
	ctx->b = L->b, ctx->tau = L->tau, ctx->u = L->u;
	return C0_OK;
}

static void level_free(struct level *L)
{
	struct matirf_ctx *ctx = &L->ctx;
	c0_grad3m_free(&ctx->g);
	free(L->b), free(L->u), free(L->y), free(L->tau), free(ctx->d.work), free(ctx->c);
	free(ctx->blur.work), free(ctx->dwork), free(ctx->dwork2), free(ctx->corr);
	free(ctx->bg), free(ctx->bgd), free(ctx->bgr), free(L->b0);
}

/* the scaled data of the columns (and its copy when the background moves it) */
static void level_data(struct level *L, const float *const *x)
{
	struct matirf_ctx *ctx = &L->ctx;
	const size_t M = ctx->M, nd = (size_t)ctx->nq * M;
	for (int q = 0; q < ctx->nq; q++)
		for (size_t k = 0; k < M; k++)
			L->b[q * M + k] = (float)(x[q][ctx->g.pixel[k]] / L->mx);
	if (L->b0) {
		memcpy(L->b0, L->b, sizeof *L->b0 * nd);
		ctx->b0 = L->b0, ctx->b_mut = L->b;
	}
}

/* diagonal steps: 1 / (absolute row or column sums of K) */
static void diag_steps(struct matirf_ctx *ctx, const struct c0_matirf_conf *c, float *tau)
{
	const int nq = ctx->nq, nz = ctx->nz;
	const size_t M = ctx->M;
	const double *W = ctx->W;
	const double wa[3] = { 1, 1, c->wz };
	double hcol = 0;
	for (int a = 0; a < 3; a++)
		for (int e = a; e < 3; e++)
			hcol += (a == e ? 4 : 4 * sqrt(2.0)) * wa[a] * wa[e];
	ctx->hcol = hcol;
	for (int j = 0; j < nz; j++) {
		double sw = 0;
		for (int q = 0; q < nq; q++)
			sw += W[q * nz + j];
		for (size_t k = 0; k < M; k++) {
			double r = c->reg == C0_REG_TV ? c0_grad3m_colsum(&ctx->g, (int)k, j) : hcol;
			tau[j * M + k] = (float)(1 / (sw + r));
		}
	}
	for (int q = 0; q < nq; q++) {
		double sw = 0;
		for (int j = 0; j < nz; j++)
			sw += W[q * nz + j];
		ctx->sig_d[q] = 1 / sw;
	}
	for (int comp = 0; comp < ctx->ncomp; comp++) {
		static const int HA[6] = { 0, 1, 2, 0, 0, 1 }, HB[6] = { 0, 1, 2, 1, 2, 2 };
		double rs = c->reg == C0_REG_TV ? 2 * wa[comp]
			  : (comp < 3 ? 4 : 4 * sqrt(2.0)) * wa[HA[comp]] * wa[HB[comp]];
		ctx->sig_r[comp] = rs > 0 ? 1 / rs : 1;
	}
}

/* The solver's callbacks: diag's, or exact's and apg's (then their steps
 * and matrices); lateral TV's fused forms where they apply */
static struct c0_pdhg_problem level_problem(struct level *L, const struct c0_matirf_conf *c)
{
	struct matirf_ctx *ctx = &L->ctx;
	struct c0_pdhg_problem pb = { ctx->N, L->m, ctx, matirf_K, matirf_KT, matirf_primal_step, matirf_dual_step,
				      matirf_iter, NULL, NULL };
	const int tv2 = c->reg == C0_REG_TV && ctx->g.nc == 2 && c->kappa > 0 && c->fused;
	if (ctx->exact) {
		pb.primal_step = ctx->apg ? matirf_primal_step_apg : matirf_primal_step_exact;
		pb.dual_step = matirf_dual_step_exact;
		matirf_exact_setup(ctx, c, L->W);
		if (tv2) {
			pb.dual_fused = matirf_dual_fused;   /* its TV part alone */
			if (ctx->apg)
				pb.primal_fused = matirf_primal_fused_apg;
		}
	} else if (tv2 && !ctx->blur.k)
		pb.primal_fused = matirf_primal_fused, pb.dual_fused = matirf_dual_fused;
	return pb;
}

/* the coarse start: the apg and exact solvers with TV (no background), on
 * grids large enough to bin; u and y at the columns from the coarse levels */
static int level_warm(struct level *L, const struct c0_matirf_conf *c, int nq, const double *angles,
		      const double *gain, const float *const *x, int ny, int nx, int coarse, int *iters)
{
	struct matirf_ctx *ctx = &L->ctx;
	if (!(coarse > 0 && ctx->exact && c->reg == C0_REG_TV && !ctx->bg && ny >= 16 && nx >= 16 && ctx->g.nc <= 2))
		return C0_OK;
	const struct matirf_cols cols = { ctx->g.pixel, ctx->M };
	struct c0_matirf_conf cc;
	const float *xc[MAXQ];
	float *buf = matirf_coarse_bin(c, nq, x, ny, nx, xc, &cc), *yc = NULL;
	if (!buf)
		return C0_ENOMEM;
	struct c0_matirf_result r;
	int st = matirf_level(&cc, nq, angles, gain, xc, (ny + 1) / 2, (nx + 1) / 2, L->mx, coarse - 1, &yc, &r);
	if (!st) {
		*iters = r.iters + r.coarse_iters;
		matirf_coarse_lift(&r, yc, ny, nx, ctx->nz, L->mx, L->col, &cols, L->u, L->y);
		c0_matirf_result_free(&r);
	}
	free(buf), free(yc);
	return st;
}

/* PDHG from u, y with the solver's default tolerance */
static int level_run(struct level *L, const struct c0_matirf_conf *c, const struct c0_pdhg_problem *pb,
		     struct c0_pdhg_info *info)
{
	struct matirf_ctx *ctx = &L->ctx;
	struct c0_progress pr;
	c0_progress_begin(&pr, "matirf (iterations, at most)", c->pdhg.maxit);
	ctx->pr = &pr;
	struct c0_pdhg_conf pc = c->pdhg;
	/* each solver's default; apg with TV: at 1e-3 the pipeline's demo depths
	 * were 1.4 nm worse than diag's, at 5e-4 as good (docs/defaults.md#matirf_tol) */
	if (pc.tol == 0)
		pc.tol = ctx->apg && c->reg == C0_REG_TV ? 5e-4 : ctx->exact ? 1e-3 : 1e-4;
	int st = c0_pdhg_solve(pb, &pc, L->u, L->y, info);
	c0_progress_end(&pr);
	ctx->pr = NULL;
	return st;
}

/* The result by columns: f = u / col in image units, its depth and sum on
 * the full grid, the background and the objective; yout: the TV dual (the
 * level's own, handed over) */
static void level_unpack(struct level *L, const struct c0_matirf_conf *c, const struct c0_pdhg_info *info,
			 float **yout, struct c0_matirf_result *res)
{
	struct matirf_ctx *ctx = &L->ctx;
	const int nz = ctx->nz, ny = ctx->ny, nx = ctx->nx;
	const size_t M = ctx->M, N = ctx->N;
	const double mx = L->mx;
	res->nz = nz, res->ny = ny, res->nx = nx, res->iters = info->iters, res->converged = info->converged;
	res->exact = ctx->exact, res->apg = ctx->apg, res->rel_change = fmax(info->dx, info->dy);
	if (yout && ctx->exact && c->reg == C0_REG_TV && ctx->g.nc <= 2)
		*yout = L->y, L->y = NULL;     /* 2 N: component e of bin j of column k at e N + j M + k */
	if (ctx->bg) {
		matirf_background_update(ctx, L->W);      /* the background of the final iterate */
		double sb = 0;
		for (size_t k = 0; k < M; k++)
			res->background[ctx->g.pixel[k]] = (float)(ctx->bg[k] * mx), sb += ctx->bg[k] * mx;
		res->background_mean = sb / (M ? M : 1);
	}
	float *work = c0_alloc(ctx->ncomp * N, sizeof *work);
	res->objective = work ? objective(ctx, L->u, work) : NAN;
	free(work);
	for (int j = 0; j < nz; j++) {
		res->z_nm[j] = c->z0_nm + (j + 0.5) * c->dz_nm;
		for (size_t k = 0; k < M; k++)
			res->f[j * M + k] = (float)(L->u[j * M + k] / L->col[j] * mx);
	}
	for (size_t k = 0; k < M; k++) {     /* total and depth stay 0 off the columns */
		double s = 0, sz = 0;
		for (int j = 0; j < nz; j++)
			s += res->f[j * M + k], sz += res->f[j * M + k] * res->z_nm[j];
		res->total[ctx->g.pixel[k]] = (float)s;
		res->depth[ctx->g.pixel[k]] = s > 0 ? (float)(sz / s) : 0;
	}
	res->M = ctx->M, res->pixel = ctx->g.pixel, ctx->g.pixel = NULL;   /* handed over */
}

static int matirf_level(const struct c0_matirf_conf *c, int nq, const double *angles, const double *gain,
			const float *const *x, int ny, int nx, double mx0, int coarse, float **yout, struct c0_matirf_result *res)
{
	memset(res, 0, sizeof *res);
	double t0 = c0_now();
	int st = c0_matirf_check(c, nq, angles);
	if (st)
		return st;
	const size_t np = (size_t)ny * nx;
	struct level *L = c0_alloc(1, sizeof *L);
	if (!L)
		return C0_ENOMEM;
	L->ctx = (struct matirf_ctx){ .nq = nq, .nz = c0_matirf_nz(c), .W = L->W, .reg = c->reg, .kappa = c->kappa,
				      .l1 = c->sparsity, .d = { nx, ny, c0_matirf_nz(c), 1, c->wz, NULL } };
	struct c0_pdhg_info info;
	if ((st = level_weights(L, c, nq, angles, gain, x, np, mx0)))
		goto out;
	res->scale = L->mx;
	if ((st = level_grid(L, c, nq, x, ny, nx)) || (st = level_alloc(L, c, np, res)))
		goto out;
	level_data(L, x);
	diag_steps(&L->ctx, c, L->tau);
	struct c0_pdhg_problem pb = level_problem(L, c);
	if ((st = level_warm(L, c, nq, angles, gain, x, ny, nx, coarse, &res->coarse_iters)) ||
	    (st = level_run(L, c, &pb, &info)))
		goto out;
	level_unpack(L, c, &info, yout, res);
out:
	level_free(L);
	free(L);
	if (st)
		c0_matirf_result_free(res);
	res->seconds = c0_now() - t0;
	return st;
}
