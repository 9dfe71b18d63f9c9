/* The solvers alone, on small problems whose solution is known in closed
 * form: CG on an SPD system, FISTA on a non-negative lasso built to have a
 * given solution, PDHG on pairwise total variation denoising, the root
 * finder on a monotone function; the Schatten pieces (eig3, the spectral
 * clip) against the closed-form eigenvalues of a symmetric 3x3 matrix; the
 * batched NNQP steps against one column at a time and the active-set NNQP.
 * Also: the adjoint checker catches a wrong adjoint. */
#include "check.h"
#include "check_adjoint.h"
#include "solve/cg.h"
#include "solve/fista.h"
#include "solve/nnqp.h"
#include "solve/pdhg.h"
#include "solve/prox_schatten.h"
#include "solve/root.h"
#include "core/err.h"
#include "core/rng.h"

#include <math.h>
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

static void diag_apply(void *c, const double *x, double *y)
{
	const double *d = c;
	for (int i = 0; i < NCG; i++)
		y[i] = d[i] * x[i];
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
	/* c0_pcg with the diagonal as a callback is c0_cg, to the bit */
	double x2[NCG];
	struct c0_cg_info i1, i2;
	memset(x, 0, sizeof x), memset(x2, 0, sizeof x2);
	CHECK(c0_cg(spd_apply, A, NCG, b, dinv, x, 1e-9, 500, &i1) == C0_OK);
	CHECK(c0_pcg(spd_apply, A, NCG, b, diag_apply, dinv, x2, 1e-9, 500, &i2) == C0_OK);
	CHECK(i1.iters == i2.iters && !memcmp(x, x2, sizeof x));
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

static double flat_below(void *c, double t) { (void)c; return -1 - exp(-t); }
static double line3(void *c, double t) { (void)c; return 0.7 * (t - 3); }

static void test_root(void)
{
	double v = 5, t;
	int evals;
	CHECK(c0_root_increasing(exp_minus, &v, 0, 0, -30, 30, 1e-10, 100, &t, &evals) == C0_ROOT_FOUND);
	CHECK_CLOSE(t, log(5), 1e-9);
	CHECK(evals < 40);
	v = 1e-6;                                    /* root far below the start: found by walking down */
	CHECK(c0_root_increasing(exp_minus, &v, 3, 0, -30, 30, 1e-14, 200, &t, &evals) == C0_ROOT_FOUND);
	CHECK_CLOSE(t, log(1e-6), 1e-6);
	v = -1;                                      /* g > 0 everywhere: the smallest t */
	CHECK(c0_root_increasing(exp_minus, &v, 0, 0, -5, 5, 1e-10, 100, &t, &evals) == C0_ROOT_BELOW);
	CHECK(t >= -5 && t < -4);
	v = 1e30;                                    /* g < 0 everywhere in range: the largest t */
	CHECK(c0_root_increasing(exp_minus, &v, 0, 0, -5, 5, 1e-10, 100, &t, &evals) == C0_ROOT_ABOVE);
	CHECK(t <= 5 && t > 4);
	/* the expected slope: a straight g in two evaluations; a g flattening
	 * below zero at the range's end in four (by decades: 14) */
	CHECK(c0_root_increasing(line3, NULL, 0, 0.7, -30, 30, 1e-12, 100, &t, &evals) == C0_ROOT_FOUND);
	CHECK(evals == 2 && fabs(t - 3) < 1e-12);
	CHECK(c0_root_increasing(flat_below, NULL, 0, 0.7, -5, 30, 1e-10, 100, &t, &evals) == C0_ROOT_ABOVE);
	CHECK_MSG(t == 30 && evals <= 4, "flat below zero: t %g after %d evaluations", t, evals);
}

/* The eigenvalues of a symmetric 3x3 matrix, ascending, by the
 * trigonometric closed form (Smith 1961): the slow obvious reference */
static void eig3_closed(const double a[3][3], double e[3])
{
	const double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
	const double q = (a[0][0] + a[1][1] + a[2][2]) / 3;
	const double p2 = (a[0][0] - q) * (a[0][0] - q) + (a[1][1] - q) * (a[1][1] - q) + (a[2][2] - q) * (a[2][2] - q) + 2 * p1;
	const double p = sqrt(p2 / 6);
	if (p == 0) {
		e[0] = e[1] = e[2] = q;
		return;
	}
	double b[3][3];
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			b[i][j] = (a[i][j] - (i == j) * q) / p;
	double r = (b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
		    b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0])) / 2;
	r = fmin(fmax(r, -1), 1);
	const double phi = acos(r) / 3, pi = acos(-1.0);
	e[2] = q + 2 * p * cos(phi);
	e[0] = q + 2 * p * cos(phi + 2 * pi / 3);
	e[1] = 3 * q - e[0] - e[2];
}

/* h packed as in prox_schatten.h <-> the matrix */
static void unpack3(const double h[6], double a[3][3])
{
	const double r2 = sqrt(2.0);
	a[0][0] = h[0], a[1][1] = h[1], a[2][2] = h[2];
	a[0][1] = a[1][0] = h[3] / r2, a[0][2] = a[2][0] = h[4] / r2, a[1][2] = a[2][1] = h[5] / r2;
}

/* a random symmetric matrix of the kind the Hessian's dual step sees, with
 * some repeated eigenvalues and diagonal ones among them (case % 4) */
static void random_sym(int kase, double scale, double h[6])
{
	for (int e = 0; e < 6; e++)
		h[e] = scale * c0_rng_normal(&rng);
	if (kase % 4 == 1)
		h[3] = h[4] = h[5] = 0;               /* diagonal: no rotation */
	if (kase % 4 == 2) {                       /* s I + t v v^T: a double eigenvalue */
		double v[3] = { c0_rng_normal(&rng), c0_rng_normal(&rng), c0_rng_normal(&rng) }, s = h[0], t = h[1];
		const double r2 = sqrt(2.0);
		h[0] = s + t * v[0] * v[0], h[1] = s + t * v[1] * v[1], h[2] = s + t * v[2] * v[2];
		h[3] = r2 * t * v[0] * v[1], h[4] = r2 * t * v[0] * v[2], h[5] = r2 * t * v[1] * v[2];
	}
}

static int cmp_d(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static void test_schatten(void)
{
	double worst_rec = 0, worst_orth = 0, worst_eig = 0, worst_clip = 0, worst_comm = 0, worst_proj = -1;
	int clipped = 0, kept = 0;
	for (int t = 0; t < 400; t++) {
		double h[6], a[3][3], a0[3][3], v[3][3], ref[3], e[3];
		const double scale = t % 3 == 0 ? 1e-3 : t % 3 == 1 ? 1 : 50;
		random_sym(t, scale, h);
		unpack3(h, a0);
		unpack3(h, a);
		c0_eig3(a, v);                             /* a0 = v diag(a) v^T, v orthonormal */
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 3; j++) {
				double r = 0, o = 0;
				for (int l = 0; l < 3; l++)
					r += v[i][l] * a[l][l] * v[j][l], o += v[l][i] * v[l][j];
				worst_rec = fmax(worst_rec, fabs(r - a0[i][j]) / scale);
				worst_orth = fmax(worst_orth, fabs(o - (i == j)));
			}
		eig3_closed(a0, ref);
		for (int i = 0; i < 3; i++)
			e[i] = a[i][i];
		qsort(e, 3, sizeof *e, cmp_d);
		for (int i = 0; i < 3; i++)
			worst_eig = fmax(worst_eig, fabs(e[i] - ref[i]) / scale);
		/* the clip: eigenvalues clip(ref), the same eigenvectors (it commutes
		 * with a0), and the projection's variational inequality
		 * <h - P h, b - P h> <= 0 for b in the ball */
		const double k = scale * (0.2 + 2 * c0_rng_uniform(&rng));
		double p[6], pm[3][3], pe[3];
		memcpy(p, h, sizeof p);
		c0_spectral_clip(p, k);
		unpack3(p, pm);
		eig3_closed(pm, pe);
		int any = 0;
		for (int i = 0; i < 3; i++) {
			any |= fabs(ref[i]) > k;
			worst_clip = fmax(worst_clip, fabs(pe[i] - fmin(fmax(ref[i], -k), k)) / scale);
		}
		if (!any)
			kept += memcmp(p, h, sizeof p) == 0;
		clipped += any;
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 3; j++) {
				double c = 0;
				for (int l = 0; l < 3; l++)
					c += pm[i][l] * a0[l][j] - a0[i][l] * pm[l][j];
				worst_comm = fmax(worst_comm, fabs(c) / (scale * scale));
			}
		for (int s = 0; s < 8; s++) {
			double b[6], bm[3][3], be[3];
			random_sym(s, scale, b);
			unpack3(b, bm);
			eig3_closed(bm, be);
			const double n = fmax(fabs(be[0]), fabs(be[2])), f = k * c0_rng_uniform(&rng) / n;
			double ip = 0;
			for (int l = 0; l < 6; l++)
				ip += (h[l] - p[l]) * (f * b[l] - p[l]);
			worst_proj = fmax(worst_proj, ip / (scale * scale));
		}
	}
	CHECK_MSG(worst_rec < 1e-12 && worst_orth < 1e-12, "eig3: reconstruction %g, orthogonality %g", worst_rec, worst_orth);
	/* the closed form loses half the digits at a double eigenvalue (acos
	 * near +-1): the reference is the coarser one there */
	CHECK_MSG(worst_eig < 1e-6, "eig3: eigenvalues off the closed form by %g", worst_eig);
	CHECK_MSG(worst_clip < 1e-6 && worst_comm < 1e-10, "clip: eigenvalues %g, commutator %g", worst_clip, worst_comm);
	CHECK_MSG(worst_proj < 1e-10, "clip: not the projection, <h - Ph, b - Ph> = %g", worst_proj);
	CHECK(clipped > 100 && clipped < 390);       /* both cases occur */
	CHECK(kept == 400 - clipped);                /* inside the ball: untouched */
}

/* c0_nnqp_batch against the same steps one column at a time, written the
 * plain way (the same numbers, bit for bit), and, run long, against the
 * active-set solver's exact answers */
static void test_nnqp_batch(void)
{
	enum { N = 15, B = C0_NNQP_BATCH };
	double A[N * N], H[N * N], Hi[N * N];
	float Hf[N * N];
	for (int i = 0; i < N * N; i++)
		A[i] = c0_rng_normal(&rng);
	double L = 0;
	for (int i = 0; i < N; i++) {
		double row = 0;
		for (int j = 0; j < N; j++) {
			double h = i == j ? 2 : 0;   /* smallest eigenvalue >= 2 */
			for (int k = 0; k < N; k++)
				h += A[k * N + i] * A[k * N + j];
			H[i * N + j] = h, Hf[i * N + j] = (float)h, row += fabs(h);
		}
		L = fmax(L, row);   /* Gershgorin: >= the largest eigenvalue */
	}
	CHECK(c0_spd_inverse(N, H, Hi) == 0);
	const float step = (float)(1 / L), q = (float)sqrt(2 / L), beta = (1 - q) / (1 + q);
	float *g = malloc(sizeof *g * N * B), *u = calloc(N * B, sizeof *u), *r = calloc(N * B, sizeof *r);
	for (int i = 0; i < N * B; i++)
		g[i] = (float)(10 * c0_rng_normal(&rng));   /* about half the bounds active */
	c0_nnqp_batch(N, Hf, step, beta, 7, g, u);
	for (int i = 0; i < B; i++) {   /* column i alone */
		float v[N], w[N];
		for (int l = 0; l < N; l++)
			v[l] = 0;
		for (int it = 0; it < 7; it++) {
			for (int l = 0; l < N; l++) {
				float acc = -g[l * B + i];
				for (int m = 0; m < N; m++)
					acc += Hf[l * N + m] * v[m];
				float p = v[l] - step * acc;
				w[l] = 0.5f * (p + fabsf(p));
			}
			for (int l = 0; l < N; l++)
				v[l] = w[l] + beta * (w[l] - r[l * B + i]), r[l * B + i] = w[l];
		}
	}
	CHECK_MSG(!memcmp(u, r, sizeof *u * N * B), "batched steps differ from one column at a time");
	c0_nnqp_batch(N, Hf, step, beta, 3000, g, u);
	double worst = 0;
	for (int i = 0; i < B; i++) {
		double gi[N], x[N] = { 0 }, d = 0, n2 = 0;
		for (int l = 0; l < N; l++)
			gi[l] = g[l * B + i];
		CHECK(c0_nnqp(N, H, Hi, gi, x) >= 0);
		for (int l = 0; l < N; l++)
			d += (u[l * B + i] - x[l]) * (u[l * B + i] - x[l]), n2 += x[l] * x[l];
		worst = fmax(worst, sqrt(d / fmax(n2, 1e-30)));
	}
	CHECK_MSG(worst < 1e-4, "batched steps, run long: %.2g from the exact answer (relative)", worst);
	free(g), free(u), free(r);
}

int main(void)
{
	c0_rng_init(&rng, 7, 0);
	RUN(test_adjoint_checker);
	RUN(test_cg);
	RUN(test_fista);
	RUN(test_pdhg);
	RUN(test_root);
	RUN(test_schatten);
	RUN(test_nnqp_batch);
	return CHECK_DONE();
}
