/* MA-TIRF: adjoints of the difference operators, TIRF intensity ratios, and
 * depth recovery on synthetic volumes. */
#include "check.h"
#include "check_adjoint.h"
#include "ops/diff3.h"
#include "ops/grad3m.h"
#include "ops/tirfop.h"
#include "optics/tirf.h"
#include "stages/matirf.h"
#include "core/rng.h"
#include "core/err.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static struct c0_rng rng;

static void test_adjoints(void)
{
	size_t N = 7 * 5 * 4;
	float work[2 * 7 * 5 * 4];
	struct c0_diff3 d = { 7, 5, 4, 1.3, 0.7, work };
	float *v = malloc(N * sizeof *v), *g = malloc(6 * N * sizeof *g);
	const struct c0_linopf grad = c0_grad3_linop(&d), hess = c0_hess3_linop(&d);
	CHECK_ADJOINTF(&grad, 1e-5);
	CHECK_ADJOINTF(&hess, 1e-5);
	/* the Hessian of a linear ramp vanishes away from the borders */
	for (int z = 0; z < 4; z++)
		for (int y = 0; y < 5; y++)
			for (int x = 0; x < 7; x++)
				v[(z * 5 + y) * 7 + x] = 2 * x - y + 3 * z;
	c0_hess3(&d, v, g);
	double mx = 0;
	for (int c = 0; c < 6; c++)
		for (int z = 1; z < 3; z++)
			for (int y = 1; y < 4; y++)
				for (int x = 1; x < 6; x++)
					mx = fmax(mx, fabs(g[c * N + (z * 5 + y) * 7 + x]));
	CHECK(mx < 1e-12);
	free(v), free(g);
}

/* the gradient over mask columns: adjoint on a ragged mask, and the plain 3D
 * gradient when the mask is full */
static void test_grad3m(void)
{
	const int nx = 7, ny = 5, nz = 4, np = nx * ny;
	uint8_t mask[35];
	for (int p = 0; p < np; p++)
		mask[p] = (p * 7 + 3) % 5 != 0;
	struct c0_grad3m g;
	CHECK(c0_grad3m_init(&g, mask, ny, nx, nz, 1.3, 0.7) == C0_OK);
	size_t N = (size_t)g.M * nz;
	float v[140], va[140], d[420], e[420];
	for (size_t i = 0; i < 420; i++)   /* all of them: the full mask below uses more */
		e[i] = (float)c0_rng_normal(&rng);
	for (size_t i = 0; i < 140; i++)
		v[i] = (float)c0_rng_normal(&rng);
	const struct c0_linopf G = c0_grad3m_linop(&g);
	CHECK(g.M > 0 && g.M < np && G.nout == 3 * N);
	CHECK_ADJOINTF(&G, 1e-5);
	c0_grad3m_free(&g);
	/* no axial weight: the axial component is dropped, not stored as zeros */
	CHECK(c0_grad3m_init(&g, mask, ny, nx, nz, 1.3, 0) == C0_OK);
	const struct c0_linopf G2 = c0_grad3m_linop(&g);
	CHECK(g.nc == 2 && G2.nout == 2 * N);
	CHECK_ADJOINTF(&G2, 1e-5);
	c0_grad3m_free(&g);
	memset(mask, 1, sizeof mask);
	CHECK(c0_grad3m_init(&g, mask, ny, nx, nz, 1.3, 0.7) == C0_OK);
	float work[2 * 140];
	struct c0_diff3 full = { nx, ny, nz, 1.3, 0.7, work };
	N = (size_t)np * nz;
	c0_grad3m_forward(&g, v, d);
	c0_grad3(&full, v, e);
	double mx = 0;
	for (size_t i = 0; i < 3 * N; i++)
		mx = fmax(mx, fabs(d[i] - e[i]));
	CHECK(mx < 1e-6);
	c0_grad3m_adjoint(&g, d, va);
	c0_grad3_adjoint(&full, d, v);
	mx = 0;
	for (size_t i = 0; i < N; i++)
		mx = fmax(mx, fabs(va[i] - v[i]));
	CHECK(mx < 1e-5);
	c0_grad3m_free(&g);
}

/* W per column and its adjoint, against the weights it is built from */
static void test_tirfop(void)
{
	struct c0_tirf t = C0_TIRF_DEFAULTS;
	enum { NQ = 5, NZ = 7, M = 11 };
	double W[NQ * NZ];
	float u[NZ * M], y[NQ * M];
	const double ang[NQ] = { 61.48, 63.37, 65.39, 67.58, 70.0 };
	CHECK(c0_tirf_weights(&t, NQ, ang, NULL, NZ, 0, 30, W) == C0_OK);
	for (int i = 0; i < NZ * M; i++)
		u[i] = (float)c0_rng_normal(&rng);
	const struct c0_tirfop o = { NQ, NZ, M, W };
	const struct c0_linopf T = c0_tirfop_linop(&o);
	CHECK_ADJOINTF(&T, 1e-5);
	c0_tirfop_forward(&o, u, y);
	double s = 0;            /* angle 3, column 4, by hand */
	for (int j = 0; j < NZ; j++)
		s += W[3 * NZ + j] * u[j * M + 4];
	CHECK_REL(y[3 * M + 4], s, 1e-5);
	CHECK(W[3 * NZ + 6] / W[0 * NZ + 6] < W[3 * NZ] / W[0]);   /* deeper = dimmer at high angles */
}

static void test_i0_ratios(void)
{
	/* reference/matirf.md 1.3: I0(69.8)/I0(62.6) = 0.565 (s), 0.550 (p), 0.560 (0.75 s mix), n_t 1.34 */
	struct c0_tirf t = C0_TIRF_DEFAULTS;
	t.n_sample = 1.34;
	double s1, p1, s2, p2;
	c0_tirf_i0_sp(&t, 62.605, &s1, &p1);
	c0_tirf_i0_sp(&t, 69.772, &s2, &p2);
	CHECK_CLOSE(s2 / s1, 0.565, 0.003);
	CHECK_CLOSE(p2 / p1, 0.550, 0.003);
	CHECK_CLOSE(c0_tirf_i0(&t, 69.772) / c0_tirf_i0(&t, 62.605), 0.560, 0.003);
}

static const double ANG[5] = { 61.48, 63.37, 65.39, 67.58, 70.0 };

/* a thin layer and a filament whose depth varies, on a 40 x 40 grid */
static void phantom(int n, double *depth, double *amp)
{
	for (int y = 0; y < n; y++)
		for (int x = 0; x < n; x++) {
			int i = y * n + x;
			depth[i] = -1, amp[i] = 0;
			if (x >= 4 && x < 16 && y >= 4 && y < 36)
				depth[i] = 110, amp[i] = 1;                  /* layer */
			if (abs(y - x) <= 1 && x >= 18)
				depth[i] = 40 + 260.0 * (x - 18) / (n - 19), amp[i] = 0.8;   /* filament */
		}
}

static double depth_error(const struct c0_matirf_conf *c, double noise, double *resid)
{
	const int n = 40, nq = 5;
	double depth[40 * 40], amp[40 * 40];
	phantom(n, depth, amp);
	float *img[5];
	double p[5], i0[5];
	for (int q = 0; q < nq; q++) {
		c0_tirf_p(&c->tirf, ANG[q], &p[q]);
		i0[q] = c0_tirf_i0(&c->tirf, ANG[q]);
		img[q] = malloc(sizeof(float) * n * n);
		for (int i = 0; i < n * n; i++)
			img[q][i] = amp[i] > 0 ? (float)(1000 * amp[i] * i0[q] * exp(-p[q] * depth[i]) * (1 + noise * c0_rng_normal(&rng))) : 0;
	}
	struct c0_matirf_result r;
	int st = c0_matirf_solve(c, nq, ANG, NULL, (const float *const *)img, n, n, &r);
	CHECK(st == C0_OK);
	double err[40 * 40];
	int k = 0;
	double rs = 0, ds = 0;
	for (int i = 0; i < n * n; i++) {
		if (amp[i] > 0)
			err[k++] = fabs(r.depth[i] - depth[i]);
		for (int q = 0; q < nq; q++) {   /* data residual of the reconstruction */
			double m = 0;
			for (int j = 0; j < r.nz; j++) {
				double a = c->z0_nm + j * c->dz_nm;
				m += r.f[(size_t)j * n * n + i] * i0[q] * exp(-p[q] * a) * (-expm1(-p[q] * c->dz_nm)) / (p[q] * c->dz_nm);
			}
			rs += (m - img[q][i]) * (m - img[q][i]);
			ds += (double)img[q][i] * img[q][i];
		}
	}
	*resid = sqrt(rs / ds);
	fprintf(stderr, "  (%d iterations, %.1f s)\n", r.iters, r.seconds);
	/* median absolute depth error over the structure */
	for (int a = 0; a < k; a++)
		for (int b = a + 1; b < k; b++)
			if (err[b] < err[a]) {
				double t = err[a]; err[a] = err[b]; err[b] = t;
			}
	for (int q = 0; q < nq; q++)
		free(img[q]);
	c0_matirf_result_free(&r);
	return err[k / 2];
}

/* the one-pass TV steps against the operator sequence they fuse: the same
 * iterates (to float rounding) after a fixed number of iterations, on a
 * ragged mask (the phantom) with its chunk boundaries inside the rows */
static void test_fused(void)
{
	const int n = 40, nq = 5;
	double depth[40 * 40], amp[40 * 40];
	phantom(n, depth, amp);
	struct c0_matirf_conf c = C0_MATIRF_DEFAULTS;
	float *img[5];
	for (int q = 0; q < nq; q++) {
		double p;
		c0_tirf_p(&c.tirf, ANG[q], &p);
		img[q] = malloc(sizeof(float) * n * n);
		for (int i = 0; i < n * n; i++)
			img[q][i] = amp[i] > 0 ? (float)(1000 * amp[i] * exp(-p * depth[i]) * (1 + 0.1 * c0_rng_normal(&rng))) : 0;
	}
	c.pdhg.maxit = 300, c.pdhg.tol = 0;
	struct c0_matirf_result a, b;
	CHECK(c0_matirf_solve(&c, nq, ANG, NULL, (const float *const *)img, n, n, &a) == C0_OK);
	c.fused = 0;
	CHECK(c0_matirf_solve(&c, nq, ANG, NULL, (const float *const *)img, n, n, &b) == C0_OK);
	double mx = 0, d = 0;
	for (size_t i = 0; i < (size_t)a.nz * n * n; i++)
		mx = fmax(mx, fabs(b.f[i])), d = fmax(d, fabs(a.f[i] - b.f[i]));
	CHECK_MSG(a.iters == 300 && b.iters == 300 && d <= 1e-4 * mx, "fused vs plain: max difference %g of %g", d, mx);
	c0_matirf_result_free(&a), c0_matirf_result_free(&b);
	for (int q = 0; q < nq; q++)
		free(img[q]);
}

static void test_depth(void)
{
	struct c0_matirf_conf c = C0_MATIRF_DEFAULTS;
	double res;
	double e = depth_error(&c, 0.10, &res);
	fprintf(stderr, "matirf TV, 10 %% noise: median depth error %.1f nm, relative residual %.3f\n", e, res);
	CHECK(e <= 20);
	c.reg = C0_REG_HESSIAN;
	e = depth_error(&c, 0.10, &res);
	fprintf(stderr, "matirf Hessian, 10 %% noise: median depth error %.1f nm, relative residual %.3f\n", e, res);
	CHECK(e <= 20);
	/* no noise, tiny regularisation: the data residual goes to the floor */
	c = (struct c0_matirf_conf)C0_MATIRF_DEFAULTS;
	c.kappa = 1e-6;
	c.sparsity = 0;
	c.pdhg.maxit = 5000;
	c.pdhg.tol = 1e-7;
	e = depth_error(&c, 0, &res);
	fprintf(stderr, "matirf noiseless: relative residual %.2e, median depth error %.1f nm\n", res, e);
	CHECK(res < 1e-2);
}

static void test_refusals(void)
{
	struct c0_matirf_conf c = C0_MATIRF_DEFAULTS;
	double bad[2] = { 55, 65 };
	CHECK(c0_matirf_check(&c, 2, bad) == C0_EINVAL && strstr(c0_errmsg(), "critical"));
	CHECK(c0_matirf_check(&c, 1, ANG) == C0_EINVAL && strstr(c0_errmsg(), "angles"));
	c.dz_nm = 0;
	CHECK(c0_matirf_check(&c, 5, ANG) == C0_EINVAL && strstr(c0_errmsg(), "z_range_nm"));
}

int main(void)
{
	c0_rng_init(&rng, 17, 0);
	RUN(test_adjoints);
	RUN(test_grad3m);
	RUN(test_tirfop);
	RUN(test_i0_ratios);
	RUN(test_fused);
	RUN(test_depth);
	RUN(test_refusals);
	return CHECK_DONE();
}
