#include "stages/matirf.h"
#include "ops/diff3.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAXQ 64

int c0_matirf_check(const struct c0_matirf_conf *c, int nq, const double *angles)
{
	int st = c0_tirf_check(&c->tirf);
	if (st)
		return st;
	if (nq < 2 || nq > MAXQ)
		return c0_fail(C0_EINVAL, "--angles: MA-TIRF needs 2..%d angles (got %d)", MAXQ, nq);
	for (int q = 0; q < nq; q++) {
		double p;
		if (c0_tirf_p(&c->tirf, angles[q], &p))
			return c0_fail(C0_EINVAL, "--angles: %s", c0_errmsg());
	}
	if (!(c->dz_nm > 0) || !(c->z1_nm > c->z0_nm) || c->z0_nm < 0)
		return c0_fail(C0_EINVAL, "--z-range %g,%g,%g: need 0 <= min < max and a positive step (nm)", c->z0_nm, c->z1_nm, c->dz_nm);
	if ((c->z1_nm - c->z0_nm) / c->dz_nm > 512)
		return c0_fail(C0_EINVAL, "--z-range: more than 512 depth bins");
	if (!(c->kappa >= 0) || !(c->wz >= 0))
		return c0_fail(C0_EINVAL, "--kappa and --axial-weight must be >= 0");
	return C0_OK;
}

void c0_matirf_result_free(struct c0_matirf_result *r)
{
	free(r->f), free(r->z_nm), free(r->depth), free(r->total);
	memset(r, 0, sizeof *r);
}

struct ctx {
	int nq, nz;
	size_t np;                /* lateral pixels */
	const double *W;          /* nq x nz, column-normalised */
	const double *y;          /* nq x np, scaled data */
	struct c0_diff3 d;
	enum c0_reg reg;
	double kappa;
	double rho;               /* the inverse below is for this rho */
	double *Minv, *MWty;      /* (W^T W + rho I)^-1 and that times W^T y, per pixel */
	double *proj;             /* scratch of the dual's size for prox_f */
};

/* prox of the data term per lateral pixel: (W^T W + rho I)^-1 (W^T y + rho v) */
static void prox_h(void *vc, const double *v, double rho, double *out)
{
	struct ctx *c = vc;
	(void)rho;     /* Minv was built for c->rho */
	const int nz = c->nz;
#pragma omp parallel for if (c->np > 4096)
	for (size_t p = 0; p < c->np; p++) {
		double b[512];
		for (int j = 0; j < nz; j++)
			b[j] = v[j * c->np + p];
		for (int j = 0; j < nz; j++) {
			double s = 0;
			for (int k = 0; k < nz; k++)
				s += c->Minv[j * nz + k] * b[k];
			out[j * c->np + p] = c->MWty[j * c->np + p] + c->rho * s;
		}
	}
}

static void K(void *vc, const double *u, double *y)
{
	struct ctx *c = vc;
	if (c->reg == C0_REG_TV)
		c0_grad3(&c->d, u, y);
	else
		c0_hess3(&c->d, u, y);
}

static void KT(void *vc, const double *y, double *u)
{
	struct ctx *c = vc;
	if (c->reg == C0_REG_TV)
		c0_grad3_adjoint(&c->d, y, u);
	else
		c0_hess3_adjoint(&c->d, y, u);
}

/* eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi */
static void eig3(double a[3][3], double v[3][3])
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			v[i][j] = i == j;
	for (int sweep = 0; sweep < 12; sweep++) {
		double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
		if (off < 1e-15 * (fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2])) || off == 0)
			break;
		for (int p = 0; p < 2; p++)
			for (int q = p + 1; q < 3; q++) {
				if (a[p][q] == 0)
					continue;
				double th = (a[q][q] - a[p][p]) / (2 * a[p][q]);
				double t = (th >= 0 ? 1 : -1) / (fabs(th) + sqrt(th * th + 1));
				double cs = 1 / sqrt(t * t + 1), sn = t * cs;
				for (int k = 0; k < 3; k++) {      /* A <- J^T A J */
					double akp = a[k][p], akq = a[k][q];
					a[k][p] = cs * akp - sn * akq;
					a[k][q] = sn * akp + cs * akq;
				}
				for (int k = 0; k < 3; k++) {
					double apk = a[p][k], aqk = a[q][k];
					a[p][k] = cs * apk - sn * aqk;
					a[q][k] = sn * apk + cs * aqk;
				}
				for (int k = 0; k < 3; k++) {
					double vkp = v[k][p], vkq = v[k][q];
					v[k][p] = cs * vkp - sn * vkq;
					v[k][q] = sn * vkp + cs * vkq;
				}
			}
	}
}

/* projection onto the radius-k ball of the dual norm (group l2 for TV,
 * spectral for Schatten-1) */
static void project_dual(struct ctx *c, double *y, double k)
{
	const size_t N = c->np * c->nz;
	if (c->reg == C0_REG_TV) {
#pragma omp parallel for if (N > 100000)
		for (size_t i = 0; i < N; i++) {
			double n = sqrt(y[i] * y[i] + y[N + i] * y[N + i] + y[2 * N + i] * y[2 * N + i]);
			if (n > k) {
				double s = k / n;
				y[i] *= s, y[N + i] *= s, y[2 * N + i] *= s;
			}
		}
		return;
	}
	/* Schatten-1's dual is the spectral norm: clip the eigenvalues to [-kappa, kappa] */
	const double r2 = sqrt(2.0);
#pragma omp parallel for if (N > 20000)
	for (size_t i = 0; i < N; i++) {
		double a[3][3] = { { y[i], y[3 * N + i] / r2, y[4 * N + i] / r2 },
				   { y[3 * N + i] / r2, y[N + i], y[5 * N + i] / r2 },
				   { y[4 * N + i] / r2, y[5 * N + i] / r2, y[2 * N + i] } };
		if (fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]) + fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]) <= k)
			continue;   /* spectral norm <= sum of |entries| <= kappa: already inside */
		double v[3][3], e[3];
		eig3(a, v);
		int clip = 0;
		for (int j = 0; j < 3; j++) {
			e[j] = a[j][j];
			if (e[j] > k) e[j] = k, clip = 1;
			if (e[j] < -k) e[j] = -k, clip = 1;
		}
		if (!clip)
			continue;
		double m[3][3];
		for (int p = 0; p < 3; p++)
			for (int q = 0; q < 3; q++)
				m[p][q] = v[p][0] * e[0] * v[q][0] + v[p][1] * e[1] * v[q][1] + v[p][2] * e[2] * v[q][2];
		y[i] = m[0][0], y[N + i] = m[1][1], y[2 * N + i] = m[2][2];
		y[3 * N + i] = r2 * m[0][1], y[4 * N + i] = r2 * m[0][2], y[5 * N + i] = r2 * m[1][2];
	}
}

/* prox of (kappa/rho) R by Moreau: v - projection of v onto the kappa/rho ball */
static void prox_f(void *vc, double *v, double rho)
{
	struct ctx *c = vc;
	const size_t M = c->np * c->nz * (c->reg == C0_REG_TV ? 3 : 6);
	double *p = c->proj;
	memcpy(p, v, M * sizeof *p);
	project_dual(c, p, c->kappa / rho);
	for (size_t i = 0; i < M; i++)
		v[i] -= p[i];
}

/* inverse of a small SPD matrix by Gauss-Jordan (nz <= 512, once) */
static int invert(double *A, int n, double *inv)
{
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++)
			inv[i * n + j] = i == j;
	for (int c = 0; c < n; c++) {
		double piv = A[c * n + c];
		if (!(fabs(piv) > 0))
			return c0_fail(C0_EINVAL, "matirf: singular depth system");
		for (int j = 0; j < n; j++)
			A[c * n + j] /= piv, inv[c * n + j] /= piv;
		for (int r = 0; r < n; r++) {
			if (r == c)
				continue;
			double f = A[r * n + c];
			for (int j = 0; j < n; j++)
				A[r * n + j] -= f * A[c * n + j], inv[r * n + j] -= f * inv[c * n + j];
		}
	}
	return C0_OK;
}

int c0_matirf_solve(const struct c0_matirf_conf *c, int nq, const double *angles, const double *gain,
		    const float *const *x, int ny, int nx, struct c0_matirf_result *res)
{
	memset(res, 0, sizeof *res);
	double t0 = c0_now();
	int st = c0_matirf_check(c, nq, angles);
	if (st)
		return st;
	const int nz = (int)ceil((c->z1_nm - c->z0_nm) / c->dz_nm - 1e-9);
	const size_t np = (size_t)ny * nx, N = np * nz;
	double W[MAXQ * 512], col[512];
	if ((st = c0_tirf_weights(&c->tirf, nq, angles, gain, nz, c->z0_nm, c->dz_nm, W)))
		return st;
	for (int j = 0; j < nz; j++) {
		double s = 0;
		for (int q = 0; q < nq; q++)
			s += W[q * nz + j] * W[q * nz + j];
		col[j] = sqrt(s);
		for (int q = 0; q < nq; q++)
			W[q * nz + j] /= col[j];
	}
	double mx = 0;
	for (int q = 0; q < nq; q++)
		for (size_t p = 0; p < np; p++)
			mx = fmax(mx, x[q][p]);
	if (!(mx > 0))
		return c0_fail(C0_EINVAL, "the angle images are empty (no positive value)");
	res->scale = mx;
	double *y = c0_alloc((size_t)nq * np, sizeof *y), *u = c0_alloc(N, sizeof *u);
	int ncomp = c->reg == C0_REG_TV ? 3 : 6;
	res->f = c0_alloc(N, sizeof *res->f);
	res->z_nm = c0_alloc((size_t)nz, sizeof *res->z_nm);
	res->depth = c0_alloc(np, sizeof *res->depth);
	res->total = c0_alloc(np, sizeof *res->total);
	if (!y || !u || !res->f || !res->z_nm || !res->depth || !res->total) {
		st = C0_ENOMEM;
		goto out;
	}
	for (int q = 0; q < nq; q++)
		for (size_t p = 0; p < np; p++)
			y[q * np + p] = x[q][p] / mx;
	double *A = c0_alloc((size_t)nz * nz, sizeof *A), *Minv = c0_alloc((size_t)nz * nz, sizeof *Minv);
	double *MWty = c0_alloc(N, sizeof *MWty), *proj = c0_alloc(N * ncomp, sizeof *proj);
	if (!A || !Minv || !MWty || !proj) {
		free(A), free(Minv), free(MWty), free(proj);
		st = C0_ENOMEM;
		goto out;
	}
	const double rho = c->admm.rho;
	for (int j = 0; j < nz; j++)
		for (int k = 0; k < nz; k++) {
			double s = j == k ? rho : 0;
			for (int q = 0; q < nq; q++)
				s += W[q * nz + j] * W[q * nz + k];
			A[j * nz + k] = s;
		}
	st = invert(A, nz, Minv);
	for (size_t p = 0; !st && p < np; p++)
		for (int j = 0; j < nz; j++) {
			double s = 0;
			for (int k = 0; k < nz; k++) {
				double wty = 0;
				for (int q = 0; q < nq; q++)
					wty += W[q * nz + k] * y[q * np + p];
				s += Minv[j * nz + k] * wty;
			}
			MWty[j * np + p] = s;
		}
	struct ctx ctx = { nq, nz, np, W, y, { nx, ny, nz, 1, c->wz }, c->reg, c->kappa, rho, Minv, MWty, proj };
	struct c0_admm_problem pb = { N, N * ncomp, &ctx, prox_h, prox_f, K, KT };
	struct c0_admm_info info = { 0, 0, 0 };
	struct c0_progress pr;
	c0_progress_begin(&pr, "matirf", 1);
	if (!st)
		st = c0_admm_solve(&pb, &c->admm, u, &info);
	free(A), free(Minv), free(MWty), free(proj);
	c0_progress_end(&pr);
	if (st)
		goto out;
	res->nz = nz, res->ny = ny, res->nx = nx, res->iters = info.iters, res->converged = info.converged;
	for (int j = 0; j < nz; j++) {
		res->z_nm[j] = c->z0_nm + (j + 0.5) * c->dz_nm;
		for (size_t p = 0; p < np; p++)
			res->f[j * np + p] = (float)(u[j * np + p] / col[j] * mx);
	}
	for (size_t p = 0; p < np; p++) {
		double s = 0, sz = 0;
		for (int j = 0; j < nz; j++)
			s += res->f[j * np + p], sz += res->f[j * np + p] * res->z_nm[j];
		res->total[p] = (float)s;
		res->depth[p] = s > 0 ? (float)(sz / s) : 0;
	}
out:
	free(y), free(u);
	res->seconds = c0_now() - t0;
	return st;
}
