/* The solvers alone, on small problems whose solution is known in closed
 * form: CG on an SPD system, FISTA on a non-negative lasso built to have a
 * given solution, PDHG on pairwise total variation denoising, the root
 * finder on a monotone function. Also: the adjoint checker catches a wrong
 * adjoint. */
#include "check.h"
#include "check_adjoint.h"
#include "solve/cg.h"
#include "solve/fista.h"
#include "solve/pdhg.h"
#include "solve/root.h"
#include "core/err.h"
#include "core/rng.h"

#include <stdlib.h>
#include <string.h>

static struct c0_rng rng;

/* a dense m x n matrix as an operator */
struct dense { int m, n; const double *a; };

static void dense_fw(void *c, const double *x, double *y)
{
	const struct dense *d = c;
	for (int i = 0; i < d->m; i++) {
		y[i] = 0;
		for (int j = 0; j < d->n; j++)
			y[i] += d->a[i * d->n + j] * x[j];
	}
}

static void dense_ad(void *c, const double *y, double *x)
{
	const struct dense *d = c;
	for (int j = 0; j < d->n; j++) {
		x[j] = 0;
		for (int i = 0; i < d->m; i++)
			x[j] += d->a[i * d->n + j] * y[i];
	}
}

/* the forward operator again as its own "adjoint": wrong unless symmetric */
static void dense_bad(void *c, const double *y, double *x) { dense_fw(c, y, x); }

static void test_adjoint_checker(void)
{
	enum { M = 6, N = 6 };
	double a[M * N];
	for (int i = 0; i < M * N; i++)
		a[i] = c0_rng_normal(&rng);
	struct dense d = { M, N, a };
	const struct c0_linop good = { N, M, &d, dense_fw, dense_ad }, bad = { N, M, &d, dense_fw, dense_bad };
	CHECK_ADJOINT(&good, NULL, 1e-12);
	CHECK(adjoint_gap(&bad, NULL, 1) > 1e-3);
}

/* CG on A = B^T B + I (SPD, n = 40) against x* with b = A x* */
enum { NCG = 40 };
static void spd_apply(void *c, const double *x, double *y)
{
	const double *a = c;
	for (int i = 0; i < NCG; i++) {
		y[i] = 0;
		for (int j = 0; j < NCG; j++)
			y[i] += a[i * NCG + j] * x[j];
	}
}

static void test_cg(void)
{
	double *B = malloc(sizeof(double) * NCG * NCG), *A = calloc(NCG * NCG, sizeof(double));
	double xs[NCG], b[NCG], x[NCG], dinv[NCG];
	for (int i = 0; i < NCG * NCG; i++)
		B[i] = c0_rng_normal(&rng);
	for (int i = 0; i < NCG; i++)
		for (int j = 0; j < NCG; j++) {
			for (int k = 0; k < NCG; k++)
				A[i * NCG + j] += B[k * NCG + i] * B[k * NCG + j];
			A[i * NCG + j] += (i == j) * (1 + 10.0 * i);   /* a spread diagonal: preconditioning helps */
		}
	for (int i = 0; i < NCG; i++)
		xs[i] = c0_rng_normal(&rng), dinv[i] = 1 / A[i * NCG + i];
	spd_apply(A, xs, b);
	for (int pre = 0; pre < 2; pre++) {
		struct c0_cg_info info;
		memset(x, 0, sizeof x);
		CHECK(c0_cg(spd_apply, A, NCG, b, pre ? dinv : NULL, x, 1e-12, 500, &info) == C0_OK);
		double e = 0, n = 0;
		for (int i = 0; i < NCG; i++)
			e += (x[i] - xs[i]) * (x[i] - xs[i]), n += xs[i] * xs[i];
		CHECK_MSG(info.converged && sqrt(e / n) < 1e-8, "cg (precond %d): %d iterations, error %g", pre, info.iters, sqrt(e / n));
	}
	/* b = 0 gives x = 0 at once */
	struct c0_cg_info info;
	double z[NCG] = { 0 };
	for (int i = 0; i < NCG; i++)
		x[i] = 1;
	CHECK(c0_cg(spd_apply, A, NCG, z, NULL, x, 1e-12, 500, &info) == C0_OK);
	CHECK(x[0] == 0 && x[NCG - 1] == 0 && info.iters == 0);
	free(A), free(B);
}

/* FISTA: min_{x >= 0} 1/2 ||A x - b||^2 + lam sum w_i x_i with A upper
 * triangular; b is chosen so that a given x* with zeros satisfies the KKT
 * conditions: g = A^T (A x* - b) = -lam w on the support of x*, and
 * > -lam w off it. Then r = A x* - b solves A^T r = g (forward substitution). */
enum { NF = 30 };
struct lsq { const double *a, *b; };
static double lsq_f(void *c, const double *x, double *grad)
{
	const struct lsq *l = c;
	double r[NF], f = 0;
	for (int i = 0; i < NF; i++) {
		r[i] = -l->b[i];
		for (int j = i; j < NF; j++)
			r[i] += l->a[i * NF + j] * x[j];
		f += 0.5 * r[i] * r[i];
	}
	for (int j = 0; j < NF; j++) {
		grad[j] = 0;
		for (int i = 0; i <= j; i++)
			grad[j] += l->a[i * NF + j] * r[i];
	}
	return f;
}

static void test_fista(void)
{
	double A[NF * NF] = { 0 }, xs[NF], g[NF], r[NF], b[NF], w[NF], x[NF], lip = 0;
	const double lam = 0.3;
	for (int i = 0; i < NF; i++) {
		A[i * NF + i] = 2 + c0_rng_uniform(&rng);
		for (int j = i + 1; j < NF; j++)
			A[i * NF + j] = 0.3 * c0_rng_normal(&rng);
	}
	for (int i = 0; i < NF * NF; i++)
		lip += A[i] * A[i];               /* ||A||_F^2 >= ||A||_2^2 */
	for (int i = 0; i < NF; i++) {
		w[i] = 0.5 + c0_rng_uniform(&rng);
		xs[i] = i % 3 ? 1 + c0_rng_uniform(&rng) : 0;
		g[i] = -lam * w[i] + (i % 3 ? 0 : 0.2 + c0_rng_uniform(&rng));
	}
	for (int j = 0; j < NF; j++) {            /* A^T r = g, A^T lower triangular */
		double s = g[j];
		for (int i = 0; i < j; i++)
			s -= A[i * NF + j] * r[i];
		r[j] = s / A[j * NF + j];
	}
	for (int i = 0; i < NF; i++) {
		b[i] = -r[i];
		for (int j = i; j < NF; j++)
			b[i] += A[i * NF + j] * xs[j];
	}
	struct lsq l = { A, b };
	struct c0_fista_conf conf = { 20000, 1e-12 };
	struct c0_fista_info info = { 0 };
	memset(x, 0, sizeof x);
	CHECK(c0_fista_nn(lsq_f, &l, NF, lip, w, lam, x, &conf, &info) == C0_OK);
	double e = 0;
	int zeros = 1;
	for (int i = 0; i < NF; i++)
		e = fmax(e, fabs(x[i] - xs[i])), zeros &= i % 3 || x[i] == 0;
	CHECK_MSG(info.converged && e < 1e-6, "fista: %d iterations, max error %g", info.iters, e);
	CHECK(zeros);                              /* exact zeros, not small values */
}

/* PDHG on pairs: min 1/2 ||x - a||^2 + lam sum_i |x_{2i+1} - x_{2i}|, whose
 * solution per pair is the mean when |a_2 - a_1| <= 2 lam, else both move
 * lam towards each other. */
enum { NP2 = 50 };
struct tvp { const float *a; float lam, tau, sigma; };
static void tv_K(void *c, const float *x, float *y)
{
	(void)c;
	for (int i = 0; i < NP2; i++)
		y[i] = x[2 * i + 1] - x[2 * i];
}
static void tv_KT(void *c, const float *y, float *x)
{
	(void)c;
	for (int i = 0; i < NP2; i++)
		x[2 * i] = -y[i], x[2 * i + 1] = y[i];
}
static void tv_primal(void *c, float *x, float *t, float rho, double sums[2])
{
	const struct tvp *p = c;
	float d2 = 0, n2 = 0;
	for (int j = 0; j < 2 * NP2; j++)
		c0_pdhg_primal_entry(&x[j], &t[j], (x[j] - p->tau * t[j] + p->tau * p->a[j]) / (1 + p->tau), rho, &d2, &n2);
	sums[0] += d2, sums[1] += n2;
}
static void tv_dual(void *c, float *y, const float *s, float rho, double sums[2])
{
	const struct tvp *p = c;
	float d2 = 0, n2 = 0;
	for (int i = 0; i < NP2; i++)
		c0_pdhg_dual_entry(&y[i], fminf(p->lam, fmaxf(-p->lam, y[i] + p->sigma * s[i])), rho, &d2, &n2);
	sums[0] += d2, sums[1] += n2;
}

static void test_pdhg(void)
{
	float a[2 * NP2], x[2 * NP2] = { 0 }, y[NP2] = { 0 };
	struct tvp p = { a, 0.5f, 0.5f, 0.5f };    /* tau sigma ||K||^2 = 0.5 < 1 */
	for (int j = 0; j < 2 * NP2; j++)
		a[j] = (float)(2 * c0_rng_normal(&rng));
	struct c0_pdhg_problem pr = { 2 * NP2, NP2, &p, tv_K, tv_KT, tv_primal, tv_dual, NULL, NULL, NULL };
	struct c0_pdhg_conf conf = { 20000, 1e-6, 1.8 };
	struct c0_pdhg_info info;
	CHECK(c0_pdhg_solve(&pr, &conf, x, y, &info) == C0_OK);
	double e = 0;
	int merged = 0;
	for (int i = 0; i < NP2; i++) {
		const double a1 = a[2 * i], a2 = a[2 * i + 1], d = a2 - a1, s = d > 0 ? p.lam : -p.lam;
		double x1 = a1 + s, x2 = a2 - s;
		if (fabs(d) <= 2 * p.lam)
			x1 = x2 = 0.5 * (a1 + a2), merged++;
		e = fmax(e, fmax(fabs(x[2 * i] - x1), fabs(x[2 * i + 1] - x2)));
	}
	CHECK_MSG(info.converged && e < 1e-4, "pdhg: %d iterations, max error %g", info.iters, e);
	CHECK(merged > 3 && merged < NP2 - 3);     /* both cases occur */
}

static double exp_minus(void *c, double t) { return exp(t) - *(const double *)c; }

static void test_root(void)
{
	double v = 5, t;
	int evals;
	CHECK(c0_root_increasing(exp_minus, &v, 0, -30, 30, 1e-10, 100, &t, &evals) == C0_ROOT_FOUND);
	CHECK_CLOSE(t, log(5), 1e-9);
	CHECK(evals < 40);
	v = 1e-6;                                    /* root far below the start: found by walking down */
	CHECK(c0_root_increasing(exp_minus, &v, 3, -30, 30, 1e-14, 200, &t, &evals) == C0_ROOT_FOUND);
	CHECK_CLOSE(t, log(1e-6), 1e-6);
	v = -1;                                      /* g > 0 everywhere: the smallest t */
	CHECK(c0_root_increasing(exp_minus, &v, 0, -5, 5, 1e-10, 100, &t, &evals) == C0_ROOT_BELOW);
	CHECK(t >= -5 && t < -4);
	v = 1e30;                                    /* g < 0 everywhere in range: the largest t */
	CHECK(c0_root_increasing(exp_minus, &v, 0, -5, 5, 1e-10, 100, &t, &evals) == C0_ROOT_ABOVE);
	CHECK(t <= 5 && t > 4);
}

int main(void)
{
	c0_rng_init(&rng, 7, 0);
	RUN(test_adjoint_checker);
	RUN(test_cg);
	RUN(test_fista);
	RUN(test_pdhg);
	RUN(test_root);
	return CHECK_DONE();
}
