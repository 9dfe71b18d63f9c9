/* COL0RME support: every fast identity against explicitly built dense
 * matrices on a tiny grid, adjoint tests, the banded covariance against the
 * dense sample covariance, and accuracy on simulated data. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "check_adjoint.h"
#include "ops/covop.h"
#include "ops/covnormal.h"
#include "ops/covfit.h"
#include "ops/covariance.h"
#include "optics/psf.h"
#include "stages/support.h"
#include "stages/lambda.h"
#include "sim/sim.h"
#include "eval/metrics.h"
#include "io/outdir.h"
#include "io/tiff.h"
#include "core/band.h"
#include "solve/fista.h"
#include "core/rng.h"
#include "core/err.h"
#include "testkit/reference.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { NY = 6, NX = 5, R = 2, LY = NY * R, LX = NX * R, NP = NY * NX, NL = LY * LX };
static const double SIG = 0.9;
static struct c0_rng rng;

static double *rnd(size_t n, double lo)
{
	double *v = malloc(n * sizeof *v);
	for (size_t i = 0; i < n; i++)
		v[i] = lo + c0_rng_uniform(&rng);
	return v;
}

static double maxdiff(const double *a, const double *b, size_t n)
{
	double d = 0, m = 0;
	for (size_t i = 0; i < n; i++)
		d = fmax(d, fabs(a[i] - b[i])), m = fmax(m, fabs(b[i]));
	return d / fmax(m, 1e-300);
}

/* dense Psi (NP x NL): Psi[(i,j),(a,b)] = Gy[i][a] Gx[j][b] */
static double *dense_psi(struct c0_covop *op)
{
	double gy[NY * LY], gx[NX * LX];
	c0_band_to_dense(&op->Gy, gy);
	c0_band_to_dense(&op->Gx, gx);
	double *P = malloc(sizeof(double) * NP * NL);
	for (int i = 0; i < NY; i++)
		for (int j = 0; j < NX; j++)
			for (int a = 0; a < LY; a++)
				for (int b = 0; b < LX; b++)
					P[(size_t)(i * NX + j) * NL + a * LX + b] = gy[i * LY + a] * gx[j * LX + b];
	return P;
}

/* dense A^T v for a symmetric NP x NP matrix V: (A^T V)_k = psi_k^T V psi_k */
static void dense_At(const double *P, const double *V, double *out)
{
	for (int k = 0; k < NL; k++) {
		double s = 0;
		for (int p = 0; p < NP; p++)
			for (int q = 0; q < NP; q++)
				s += P[(size_t)p * NL + k] * V[p * NP + q] * P[(size_t)q * NL + k];
		out[k] = s;
	}
}

/* dense M(x) = Psi diag(x) Psi^T */
static void dense_M(const double *P, const double *x, double *M)
{
	for (int p = 0; p < NP; p++)
		for (int q = 0; q < NP; q++) {
			double s = 0;
			for (int k = 0; k < NL; k++)
				s += P[(size_t)p * NL + k] * x[k] * P[(size_t)q * NL + k];
			M[p * NP + q] = s;
		}
}

static void test_band_ops(void)
{
	struct c0_band b;
	c0_band_alloc(&b, 7, 11, 4);
	for (int i = 0; i < 7; i++) {
		b.start[i] = i < 3 ? 0 : i > 5 ? 7 : i;
		for (int k = 0; k < 4; k++)
			b.v[i * 4 + k] = c0_rng_uniform(&rng) - 0.5;
	}
	double D[77], *x = rnd(13 * 11, -0.5), yx[13 * 7], ref[13 * 7];
	c0_band_to_dense(&b, D);
	c0_band_apply_x(&b, 13, x, yx);
	for (int y = 0; y < 13; y++)
		for (int i = 0; i < 7; i++)
			ref[y * 7 + i] = dot(D + i * 11, x + y * 11, 11);
	CHECK(maxdiff(yx, ref, 13 * 7) < 1e-14);
	double *xy = rnd(11 * 3, -0.5), yy[7 * 3], ry[7 * 3];
	c0_band_apply_y(&b, 3, xy, yy);
	for (int i = 0; i < 7; i++)
		for (int c = 0; c < 3; c++) {
			double s = 0;
			for (int k = 0; k < 11; k++)
				s += D[i * 11 + k] * xy[k * 3 + c];
			ry[i * 3 + c] = s;
		}
	CHECK(maxdiff(yy, ry, 21) < 1e-14);
	/* 37 columns: two strips of 16 in vectors, then 5 one by one; every
	 * column sums the band in order, the same bits as a plain loop */
	double *xw = rnd(11 * 37, -0.5), yw[7 * 37];
	c0_band_apply_y(&b, 37, xw, yw);
	int bits = 1;
	for (int i = 0; i < 7; i++)
		for (int c = 0; c < 37; c++) {
			double s = 0;
			for (int k = 0; k < 4; k++)
				s += b.v[i * 4 + k] * xw[(b.start[i] + k) * 37 + c];
			bits &= s == yw[i * 37 + c];
		}
	CHECK(bits);
	free(xw);
	struct c0_band t;
	CHECK(c0_band_transpose(&b, &t) == C0_OK);
	double DT[77];
	c0_band_to_dense(&t, DT);
	int same = 1;
	for (int i = 0; i < 7; i++)
		for (int j = 0; j < 11; j++)
			same &= DT[j * 7 + i] == D[i * 11 + j];
	CHECK(same);
	c0_band_free(&t), c0_band_free(&b), free(x), free(xy);
}

/* A sparse image through X Bx and By (X Bx) with the occupancy of X Bx's
 * strips: the same bits as without it, the occupancy covers every non-zero,
 * and it is sparse enough that strips are skipped. */
static void test_band_occ(void)
{
	struct c0_band bx, by;
	c0_band_alloc(&bx, 40, 40, 5), c0_band_alloc(&by, 9, 9, 3);
	for (int i = 0; i < 40; i++) {
		bx.start[i] = i < 2 ? 0 : i > 37 ? 35 : i - 2;
		for (int k = 0; k < 5; k++)
			bx.v[i * 5 + k] = c0_rng_uniform(&rng);
	}
	for (int i = 0; i < 9; i++) {
		by.start[i] = i < 1 ? 0 : i > 7 ? 6 : i - 1;
		for (int k = 0; k < 3; k++)
			by.v[i * 3 + k] = c0_rng_uniform(&rng);
	}
	double x[9 * 40] = { 0 }, t1[9 * 40], t2[9 * 40], y1[9 * 40], y2[9 * 40];
	x[2 * 40 + 3] = 0.7, x[2 * 40 + 30] = -0.2, x[6 * 40 + 17] = 1.3;
	unsigned char occ[9 * C0_BAND_STRIPS(40)];
	c0_band_apply_x_sym_sparse(&bx, 9, x, t1);
	c0_band_apply_x_sym_sparse_occ(&bx, 9, x, t2, occ);
	CHECK(!memcmp(t1, t2, sizeof t1));
	int covered = 1, empty = 0;
	for (int y = 0; y < 9; y++)
		for (int c = 0; c < 40; c++)
			covered &= t2[y * 40 + c] == 0 || occ[y * C0_BAND_STRIPS(40) + c / C0_BAND_STRIP];
	for (int k = 0; k < 9 * C0_BAND_STRIPS(40); k++)
		empty += !occ[k];
	CHECK(covered);
	CHECK(empty >= 20);
	c0_band_apply_y(&by, 40, t2, y1);
	c0_band_apply_y_occ(&by, 40, t2, occ, y2);
	CHECK(!memcmp(y1, y2, sizeof y1));
	c0_band_free(&bx), c0_band_free(&by);
}

static void test_psf_factor(void)
{
	/* columns of G integrate the whole Gaussian when it lies inside the field */
	struct c0_band G;
	CHECK(c0_psf_factor(20, 4, 1.0, &G) == C0_OK);
	double col = 0;
	for (int i = 0; i < 20; i++)
		col += c0_band_get(&G, i, 40);
	CHECK_CLOSE(col, 1, 1e-6);
	/* fine pixel a is centred at (a + 1/2)/r: pixel 41 is centred at 10.375 */
	double v;
	c0_psf_pixel_weights(41.5 / 4, 1.0, 10, 1, &v);
	CHECK_CLOSE(c0_band_get(&G, 10, 41), v, 1e-15);
	CHECK_CLOSE(c0_band_get(&G, 10, 41), 0.5 * (erf(0.625 / sqrt(2)) - erf(-0.375 / sqrt(2))), 1e-12);
	c0_band_free(&G);
}

static void test_dense_identities(void)
{
	struct c0_covop op;
	CHECK(c0_covop_init(&op, NY, NX, R, SIG, 5) == C0_OK);
	double *P = dense_psi(&op);
	/* A^T A x = H_y X H_x */
	double *x = rnd(NL, 0), *fast = malloc(sizeof(double) * NL), *slow = malloc(sizeof(double) * NL);
	double *M = malloc(sizeof(double) * NP * NP);
	dense_M(P, x, M);
	dense_At(P, M, slow);
	c0_covop_normal(&op, x, fast);
	/* the bands of A^T A drop their tails below C0_COVOP_TRIM */
	CHECK_MSG(maxdiff(fast, slow, NL) < C0_COVOP_TRIM, "normal operator off by %g", maxdiff(fast, slow, NL));
	/* column norms: ||psi_k||^2, and ||a_k||^2 = (A^T A)_kk */
	double *e = calloc(NL, sizeof(double));
	int ok = 1;
	for (int k = 0; k < NL; k++) {
		double s = 0;
		for (int p = 0; p < NP; p++)
			s += P[(size_t)p * NL + k] * P[(size_t)p * NL + k];
		ok &= fabs(s - op.n[k]) <= 1e-12 * s;
		e[k] = 1;
		c0_covop_normal(&op, e, fast);
		ok &= fabs(fast[k] - op.n[k] * op.n[k]) <= 1e-10 * fast[k];
		e[k] = 0;
	}
	CHECK(ok);
	/* Lipschitz constant = largest eigenvalue of the dense A^T A (power iteration, long) */
	double *AtA = malloc(sizeof(double) * NL * NL);
	for (int k = 0; k < NL; k++) {
		e[k] = 1;
		dense_M(P, e, M);
		dense_At(P, M, AtA + (size_t)k * NL);
		e[k] = 0;
	}
	double *v = rnd(NL, 0), lam = 0;
	for (int it = 0; it < 20000; it++) {
		for (int i = 0; i < NL; i++)
			fast[i] = dot(AtA + (size_t)i * NL, v, NL);
		double nn = sqrt(dot(fast, fast, NL));
		lam = dot(fast, v, NL);
		for (int i = 0; i < NL; i++)
			v[i] = fast[i] / nn;
	}
	CHECK_REL(op.lip, lam, C0_COVOP_TRIM);
	/* Psi and Psi^T against the dense matrix, and their adjointness */
	double psix[NP];
	c0_covop_psi(&op, x, psix);
	for (int p = 0; p < NP; p++)
		slow[p] = dot(P + (size_t)p * NL, x, NL);
	CHECK(maxdiff(psix, slow, NP) < 1e-12);
	const struct c0_linop Psi = c0_covop_psi_linop(&op);
	CHECK_ADJOINT(&Psi, NULL, 1e-12);
	/* one PSF factor alone, along the rows of an image */
	struct c0_band_rows gx = { &op.Gx, 3 };
	const struct c0_linop Gx = c0_band_linop(&gx);
	CHECK_ADJOINT(&Gx, NULL, 1e-12);
	free(P), free(x), free(fast), free(slow), free(M), free(e), free(AtA), free(v);
	c0_covop_free(&op);
}

/* a covariance with random entries on its band, from a random stack */
static int random_cov(int d, int T, struct c0_cov *cov, double *dense, int dense_ref)
{
	struct c0_cov_acc *a;
	c0_cov_acc_new(NX, NY, d, &a);
	float *frames = malloc(sizeof(float) * NP * T);
	for (int i = 0; i < NP * T; i++)   /* with a per-pixel trend, which the covariance removes */
		frames[i] = (float)(100 + 20 * c0_rng_normal(&rng) + (i / NP) * ((i % NP) % 3 - 1.0));
	for (int t = 0; t < T; t++)
		c0_cov_acc_add(a, frames + t * NP);
	int st = c0_cov_acc_finish(a, cov);
	if (dense_ref) {
		/* dense sample covariance of the residuals of a least-squares line in t
		 * per pixel, 1/(T-2) */
		double *res = malloc(sizeof(double) * NP * T);
		for (int p = 0; p < NP; p++) {
			double m = 0, tm = (T - 1) / 2.0, sty = 0, stt = 0;
			for (int t = 0; t < T; t++)
				m += frames[t * NP + p] / T;
			for (int t = 0; t < T; t++)
				sty += (t - tm) * (frames[t * NP + p] - m), stt += (t - tm) * (t - tm);
			for (int t = 0; t < T; t++)
				res[t * NP + p] = frames[t * NP + p] - m - sty / stt * (t - tm);
		}
		for (int p = 0; p < NP; p++)
			for (int q = 0; q < NP; q++) {
				double s = 0;
				for (int t = 0; t < T; t++)
					s += res[t * NP + p] * res[t * NP + q];
				dense[p * NP + q] = s / (T - 2);
			}
		free(res);
	} else      /* the band's own numbers, to check the operators alone (the sums are float) */
		for (int l = 0; !st && l < cov->nlag; l++)
			for (int y = 0; y + cov->dy[l] < NY; y++)
				for (int x = 0; x < NX; x++) {
					int xx = x + cov->dx[l], p = y * NX + x, q = (y + cov->dy[l]) * NX + xx;
					if (xx >= 0 && xx < NX)
						dense[p * NP + q] = dense[q * NP + p] = cov->r[(size_t)l * NP + p];
				}
	free(frames);
	return st;
}

static void test_covariance(void)
{
	struct c0_cov cov;
	double *D = malloc(sizeof(double) * NP * NP);
	CHECK(random_cov(2, 20, &cov, D, 1) == C0_OK);
	/* radius 2: half of the 13 lags of the disk, (0, 0) first */
	int indisk = cov.nlag == 7 && cov.dy[0] == 0 && cov.dx[0] == 0;
	for (int l = 0; l < cov.nlag; l++)
		indisk &= cov.dy[l] * cov.dy[l] + cov.dx[l] * cov.dx[l] <= 4 && (cov.dy[l] > 0 || cov.dx[l] >= 0);
	CHECK(indisk && c0_cov_lag_count(6) == 57);
	double err = 0;
	int inband = 0;
	for (int l = 0; l < cov.nlag; l++)
		for (int y = 0; y < NY; y++)
			for (int x = 0; x < NX; x++) {
				int yy = y + cov.dy[l], xx = x + cov.dx[l];
				double v = cov.r[(size_t)l * NP + y * NX + x];
				if (yy >= NY || xx < 0 || xx >= NX) {
					err = fmax(err, fabs(v));
					continue;
				}
				inband++;
				err = fmax(err, fabs(v - D[(y * NX + x) * NP + yy * NX + xx]) / D[0]);
			}
	/* the sums are float, added in double a block at a time */
	CHECK_MSG(err < 2e-6, "banded vs dense covariance: %g", err);
	CHECK(inband > 60);
	c0_cov_free(&cov);
	/* fewer than 3 frames is refused */
	struct c0_cov_acc *a;
	c0_cov_acc_new(NX, NY, 1, &a);
	float f[NP] = { 0 };
	c0_cov_acc_add(a, f), c0_cov_acc_add(a, f);
	CHECK(c0_cov_acc_finish(a, &cov) == C0_EINVAL && strstr(c0_errmsg(), "3 frames"));
	free(D);
}

/* c0_cov_acc_set_noise: a window's lag 0 is the plain window's less the map
 * at the window's place in the image (an accumulator with an origin, a
 * window inside it, and the even half), the other lags untouched */
static void test_noise_map(void)
{
	enum { W = 12, H = 10, T = 40, OX = 3, OY = 2, AW = 8, AH = 7 };
	float map[W * H], fr[AW * AH];
	for (int i = 0; i < W * H; i++)
		map[i] = (float)(0.1 * i);
	struct c0_cov_acc *a, *b, *ao, *bo;
	CHECK(c0_cov_acc_new(AW, AH, 2, &a) == C0_OK && c0_cov_acc_new(AW, AH, 2, &b) == C0_OK);
	CHECK(c0_cov_acc_new(AW, AH, 2, &ao) == C0_OK && c0_cov_acc_new(AW, AH, 2, &bo) == C0_OK);
	c0_cov_acc_set_noise(b, map, W, OX, OY), c0_cov_acc_set_noise(bo, map, W, OX, OY);
	for (int t = 0; t < T; t++) {
		for (int i = 0; i < AW * AH; i++)
			fr[i] = (float)(10 + c0_rng_normal(&rng));
		c0_cov_acc_add(a, fr), c0_cov_acc_add(b, fr);
		if (t % 2)
			c0_cov_acc_add(ao, fr), c0_cov_acc_add(bo, fr);
	}
	struct c0_cov p, q, pe, qe;
	CHECK(c0_cov_acc_window(a, 1, 2, 5, 4, &p) == C0_OK && c0_cov_acc_window(b, 1, 2, 5, 4, &q) == C0_OK);
	CHECK(c0_cov_acc_window_even(a, ao, 0, 0, &pe) == C0_OK && c0_cov_acc_window_even(b, bo, 0, 0, &qe) == C0_OK);
	double err = 0, erre = 0;
	for (int l = 0; l < p.nlag; l++)
		for (int i = 0; i < 5 * 4; i++) {
			double m = l ? 0 : map[(OY + 1 + i / 4) * W + OX + 2 + i % 4];   /* 4 wide, 5 high */
			err = fmax(err, fabs(p.r[(size_t)l * 20 + i] - m - q.r[(size_t)l * 20 + i]));
		}
	for (int l = 0; l < pe.nlag; l++)
		for (int i = 0; i < AW * AH; i++) {
			double m = l ? 0 : map[(OY + i / AW) * W + OX + i % AW];
			erre = fmax(erre, fabs(pe.r[(size_t)l * AW * AH + i] - m - qe.r[(size_t)l * AW * AH + i]));
		}
	CHECK_MSG(err < 1e-9 && erre < 1e-9, "noise map: window %g, even half %g", err, erre);
	c0_cov_free(&p), c0_cov_free(&q), c0_cov_free(&pe), c0_cov_free(&qe);
	c0_cov_acc_free(a), c0_cov_acc_free(b), c0_cov_acc_free(ao), c0_cov_acc_free(bo);
}

static void test_covariance_operator(void)
{
	struct c0_covop op;
	c0_covop_init(&op, NY, NX, R, SIG, 7);
	double *D = malloc(sizeof(double) * NP * NP), *P = dense_psi(&op);
	struct c0_cov cov;
	/* lag radius 7 covers every pixel pair of the 6x5 grid (5^2 + 4^2 <= 7^2): banded = dense */
	random_cov(7, 30, &cov, D, 0);
	double *C = malloc(sizeof(double) * NL), *Cd = malloc(sizeof(double) * NL);
	c0_covop_adjoint(&op, &cov, cov.r, C);
	dense_At(P, D, Cd);
	CHECK_MSG(maxdiff(C, Cd, NL) < 1e-10, "C = A^T vec(R): %g", maxdiff(C, Cd, NL));
	/* banded forward equals the dense model covariance on the band */
	double *x = rnd(NL, 0), *m = malloc(sizeof(double) * cov.nlag * NP), *M = malloc(sizeof(double) * NP * NP);
	c0_covop_forward(&op, &cov, x, m);
	dense_M(P, x, M);
	double err = 0;
	for (int l = 0; l < cov.nlag; l++)
		for (int y = 0; y + cov.dy[l] < NY; y++)
			for (int xx = 0; xx < NX; xx++) {
				int x2 = xx + cov.dx[l];
				if (x2 < 0 || x2 >= NX)
					continue;
				err = fmax(err, fabs(m[(size_t)l * NP + y * NX + xx] - M[(y * NX + xx) * NP + (y + cov.dy[l]) * NX + x2]));
			}
	CHECK(err < 1e-12 * M[0]);
	/* adjoint test in the band's Frobenius product, with a narrower band */
	c0_cov_free(&cov);
	random_cov(2, 10, &cov, D, 0);
	struct c0_covop_band band = { &op, &cov };
	const struct c0_linop A = c0_covop_linop(&band);
	double *w = malloc(sizeof *w * A.nout);
	for (size_t i = 0; i < A.nout; i++)
		w[i] = c0_cov_weight(&cov, (int)(i / NP));
	CHECK_ADJOINT(&A, w, 1e-12);
	free(w);
	/* gradient of 1/2||R - M(x) - sI||^2 in x at fixed s, and the closed-form s */
	c0_cov_free(&cov);
	random_cov(7, 30, &cov, D, 0);
	c0_covop_adjoint(&op, &cov, cov.r, C);
	double trR = 0, xn = 0;
	for (int p = 0; p < NP; p++)
		trR += D[p * NP + p];
	for (int k = 0; k < NL; k++)
		xn += x[k] * op.n[k];
	for (int k = 0; k < NL; k++)
		x[k] *= 0.2 * trR / xn;     /* keep s > 0 */
	xn *= 0.2 * trR / xn;
	dense_M(P, x, M);
	double trM = 0;
	for (int p = 0; p < NP; p++)
		trM += M[p * NP + p];
	double s = (trR - xn) / NP;
	CHECK_REL(s, (trR - trM) / NP, 1e-12);       /* s = mean diagonal residual */
	double *V = malloc(sizeof(double) * NP * NP), *gd = malloc(sizeof(double) * NL), *g = malloc(sizeof(double) * NL);
	for (int i = 0; i < NP * NP; i++)
		V[i] = M[i] - D[i] + (i % (NP + 1) == 0 ? s : 0);
	dense_At(P, V, gd);
	c0_covop_normal(&op, x, g);
	for (int k = 0; k < NL; k++)
		g[k] += s * op.n[k] - C[k];
	CHECK_MSG(maxdiff(g, gd, NL) < C0_COVOP_TRIM, "gradient: %g", maxdiff(g, gd, NL));
	/* a sparse x goes through its non-zeros only (the band of A^T A is
	 * symmetric): the same numbers as the dense products */
	for (int k = 0; k < NL; k++)
		x[k] = k % 7 ? 0 : x[k];
	c0_covop_normal(&op, x, g);
	double *t = malloc(sizeof(double) * NL);
	c0_band_apply_x(&op.Hx, op.Ly, x, t);
	c0_band_apply_y(&op.Hy, op.Lx, t, gd);
	CHECK(memcmp(g, gd, sizeof(double) * NL) == 0);
	free(t);
	free(D), free(P), free(C), free(Cd), free(x), free(m), free(M), free(V), free(gd), free(g);
	c0_cov_free(&cov);
	c0_covop_free(&op);
}

/* N = A^T A on a working set (ops/covnormal.h) as a linear operator on the
 * set's pixels: self-adjoint, so forward and adjoint are the same */
static void covnormal_apply(void *ctx, const double *x, double *y)
{
	c0_covnormal_apply(ctx, x, y);
}

/* P A^T A P v through the plain operators, v and out on the whole grid:
 * forward then adjoint on cov's band (every pixel pair when its lag covers
 * the grid), or the trimmed product c0_covop_normal when cov is NULL */
static void plain_normal(struct c0_covop *op, const struct c0_cov *cov, const uint8_t *in, const double *v, double *out)
{
	const size_t L = (size_t)op->Ly * op->Lx;
	double *x = malloc(sizeof *x * L);
	for (size_t i = 0; i < L; i++)
		x[i] = in[i] ? v[i] : 0;
	if (cov) {
		double *m = malloc(sizeof *m * cov->nlag * op->Ny * op->Nx);
		c0_covop_forward(op, cov, x, m);
		c0_covop_adjoint(op, cov, m, out);
		free(m);
	} else
		c0_covop_normal(op, x, out);
	for (size_t i = 0; i < L; i++)
		out[i] = in[i] ? out[i] : 0;
	free(x);
}

/* The working set's normal operator against the plain one on a random set:
 * on the tiny grid with a PSF wide enough that its bands drop nothing
 * (C0_COVOP_TRIM), against forward then adjoint over every pixel pair; on a
 * grid large enough for several threads and sliding row buffers, against
 * c0_covop_normal; and <N x, y> = <x, N y>. */
static void test_covnormal(void)
{
	struct c0_covop op;
	struct c0_cov cov;
	double D[NP * NP];
	CHECK(c0_covop_init(&op, NY, NX, R, 2.0, 7) == C0_OK);
	CHECK(random_cov(7, 10, &cov, D, 0) == C0_OK);     /* its lags only: every pixel pair */
	for (int big = 0; big < 2; big++) {
		if (big) {
			c0_covop_free(&op);
			CHECK(c0_covop_init(&op, 48, 40, 4, SIG, 6) == C0_OK);
		}
		const size_t L = (size_t)op.Ly * op.Lx;
		uint8_t *in = malloc(L);
		double *v = rnd(L, 0), *ref = malloc(sizeof *ref * L), *vw = malloc(sizeof *vw * L);
		double *nw = malloc(sizeof *nw * L), *got = calloc(L, sizeof *got);
		for (size_t i = 0; i < L; i++)
			in[i] = c0_rng_uniform(&rng) < 0.7;
		struct c0_covnormal N;
		CHECK(c0_covnormal_init(&N, &op) == C0_OK);
		c0_covnormal_set(&N, in);
		CHECK(N.nws > (big ? 20000 : 0) && N.nws < L);
		for (size_t k = 0; k < N.nws; k++)
			vw[k] = v[N.ws[k]];
		c0_covnormal_apply(&N, vw, nw);
		for (size_t k = 0; k < N.nws; k++)
			got[N.ws[k]] = nw[k];
		plain_normal(&op, big ? NULL : &cov, in, v, ref);
		CHECK_MSG(maxdiff(got, ref, L) < 1e-10, "N v on %zu of %zu pixels: %g", N.nws, L, maxdiff(got, ref, L));
		const struct c0_linop A = { N.nws, N.nws, &N, covnormal_apply, covnormal_apply };
		CHECK_ADJOINT(&A, NULL, 1e-12);
		c0_covnormal_free(&N);
		free(in), free(v), free(ref), free(vw), free(nw), free(got);
	}
	c0_cov_free(&cov);
	c0_covop_free(&op);
}

/* The covariance fit on a working set gives the whole grid's objective and
 * gradient (at its pixels) when x is 0 elsewhere, and a gap >= 0 */
static void test_covfit(void)
{
	struct c0_covop op;
	struct c0_cov cov;
	double D[NP * NP];
	CHECK(c0_covop_init(&op, NY, NX, R, SIG, 7) == C0_OK);
	CHECK(random_cov(7, 30, &cov, D, 0) == C0_OK);
	double *C = malloc(sizeof *C * NL), *Ax = malloc(sizeof *Ax * NL), part[4], *x = rnd(NL, 0);
	double *g = malloc(sizeof *g * NL), *xw = malloc(sizeof *xw * NL), *gw = malloc(sizeof *gw * NL);
	c0_covop_adjoint(&op, &cov, cov.r, C);
	struct c0_covfit f = { &op, C, 0, 0, NP, Ax, 1e-3, part };
	for (int p = 0; p < NP; p++)
		f.trR += D[p * NP + p];
	for (int p = 0; p < NP * NP; p++)
		f.R2 += D[p] * D[p];
	uint8_t in[NL];
	for (int k = 0; k < NL; k++)
		in[k] = k % 3 != 0, x[k] = in[k] ? 1e-3 * x[k] : 0;
	const double fg = c0_covfit_smooth(&f, x, g);
	struct c0_covfit_ws w;
	CHECK(c0_covfit_ws_init(&w, &f) == C0_OK && c0_covfit_ws_set(&w, in, x, xw) == C0_OK);
	CHECK(w.N.nws == (size_t)NL - (NL + 2) / 3);
	const double fw = c0_covfit_ws_smooth(&w, xw, gw);
	CHECK_REL(fw, fg, 1e-12);
	double e = 0, m = 0;
	for (size_t k = 0; k < w.N.nws; k++)
		e = fmax(e, fabs(gw[k] - g[w.N.ws[k]])), m = fmax(m, fabs(g[w.N.ws[k]]));
	CHECK_MSG(e < 1e-10 * m, "gradient on the set: %g of %g", e, m);
	CHECK(c0_covfit_gap(&f, x) >= 0);
	c0_covfit_ws_free(&w);
	free(C), free(Ax), free(x), free(g), free(xw), free(gw);
	c0_cov_free(&cov);
	c0_covop_free(&op);
}

/* A failure inside a parallel loop reaches the caller with its own message
 * (the message is per thread; the tiles' loops rely on this). */
static void test_first_fail(void)
{
	struct c0_first_fail f = { 0 };
#pragma omp parallel for schedule(dynamic, 1)
	for (int i = 0; i < 64; i++)
		c0_first_fail_note(&f, i == 37 ? c0_fail(C0_EINVAL, "tile %d: no luck", i) : C0_OK);
	c0_clear_error();
	CHECK(c0_first_fail_raise(&f) == C0_EINVAL && !strcmp(c0_errmsg(), "tile 37: no luck"));
	struct c0_first_fail none = { 0 };
	CHECK(c0_first_fail_raise(&none) == C0_OK);
}

static void test_wrong_inputs(void)
{
	struct c0_support_conf c = C0_SUPPORT_DEFAULTS;
	c.grid.pixel_nm = 100, c.grid.fwhm_nm = 229;
	CHECK(c0_support_check(&c, 64, 64, 500, "s.tif") == C0_OK);
	/* the grid: sigma 0.972 camera pixels, lag ceil(6 sigma) = 6 unless given, fine pixel 25 nm */
	CHECK(fabs(c0_grid_sigma_px(&c.grid) - 0.9725) < 1e-4 && c0_grid_fine_nm(&c.grid) == 25);
	CHECK(c0_support_lag(&c) == 6 && c0_grid_lag(&c.grid, 3) == 3);
	CHECK(c0_grid_check(&(struct c0_grid){ 100, 5, 4 }) == C0_EINVAL && strstr(c0_errmsg(), "camera pixels"));
	CHECK(c0_support_check(&c, 10, 64, 500, "s.tif") == C0_EINVAL && strstr(c0_errmsg(), "smaller than the PSF band"));
	CHECK(c0_support_check(&c, 64, 64, 2, "s.tif") == C0_EINVAL && strstr(c0_errmsg(), "at least 3"));
	c.grid.pixel_nm = 0;
	CHECK(c0_support_check(&c, 64, 64, 500, "s.tif") == C0_EINVAL && strstr(c0_errmsg(), "pixel_nm"));
	c.grid.pixel_nm = 100, c.grid.fwhm_nm = -1;
	CHECK(c0_support_check(&c, 64, 64, 500, "s.tif") == C0_EINVAL && strstr(c0_errmsg(), "fwhm_nm"));
	c.grid.fwhm_nm = 229, c.grid.srf = 0;
	CHECK(c0_support_check(&c, 64, 64, 500, "s.tif") == C0_EINVAL && strstr(c0_errmsg(), "srf"));
}

/* Gaussian read noise only (no Poisson): the estimated noise variance is the read noise's */
/* The obvious form of the noise fit on a given support: FISTA on the whole
 * grid with the gradient zeroed off the mask, f as in DESIGN (s in closed
 * form). */
struct mctx { struct c0_covop *op; const double *C; const uint8_t *m; double R2, trR, HW, *Ax; };

static double masked_f(void *v, const double *x, double *g)
{
	struct mctx *c = v;
	const size_t L = (size_t)c->op->Ly * c->op->Lx;
	c0_covop_normal(c->op, x, c->Ax);
	double xc = 0, xax = 0, xn = 0;
	for (size_t i = 0; i < L; i++)
		xc += x[i] * c->C[i], xax += x[i] * c->Ax[i], xn += x[i] * c->op->n[i];
	const double s = fmax(0, (c->trR - xn) / c->HW);
	for (size_t i = 0; i < L; i++)
		g[i] = c->m[i] ? c->Ax[i] + s * c->op->n[i] - c->C[i] : 0;
	return 0.5 * c->R2 - xc - s * c->trR + 0.5 * xax + s * xn + 0.5 * s * s * c->HW;
}

static double masked_sigma2(const struct c0_support_conf *c, const struct c0_cov *cov, const uint8_t *m)
{
	const size_t n = (size_t)cov->W * cov->H, L = n * c->grid.srf * c->grid.srf;
	struct c0_covop op;
	CHECK(c0_covop_init(&op, cov->H, cov->W, c->grid.srf, c0_grid_sigma_px(&c->grid), cov->d) == C0_OK);
	double mx = 0, *C = calloc(L, sizeof *C), *x = calloc(L, sizeof *x), *Ax = calloc(L, sizeof *Ax);
	for (size_t i = 0; i < n; i++)
		mx = fmax(mx, cov->r[i]);
	struct mctx ctx = { &op, C, m, 0, 0, (double)n, Ax };
	for (int l = 0; l < cov->nlag; l++)
		for (size_t i = 0; i < n; i++) {
			const double v = cov->r[(size_t)l * n + i] / mx;
			ctx.R2 += c0_cov_weight(cov, l) * v * v;
			ctx.trR += l == 0 ? v : 0;
		}
	c0_covop_adjoint(&op, cov, cov->r, C);
	for (size_t i = 0; i < L; i++)
		C[i] /= mx;
	struct c0_fista_info info = { 0 };
	CHECK(c0_fista_nn(masked_f, &ctx, L, op.lip, NULL, 0, x, &c->fista, &info) == C0_OK);
	double xn = 0;
	for (size_t i = 0; i < L; i++)
		xn += x[i] * op.n[i];
	free(C), free(x), free(Ax);
	c0_covop_free(&op);
	return fmax(0, (ctx.trR - xn) / ctx.HW) * mx;
}

static void test_noise_variance(void)
{
	struct c0_sim_conf s;
	c0_sim_defaults(&s);
	s.width = s.height = 32, s.frames = 400, s.nangles = 1, s.background = 0, s.filaments = 3;
	/* lines at 60 a um, as this bar was set: on the default's 4x denser tubes the
	 * l1 iterate's shrinkage leaves 20 % more in the residual (173 against 144),
	 * which the masked fit below takes out */
	c0_sim_lines(&s);
	struct c0_emitter *em;
	int ne;
	CHECK(c0_sim_structure(&s, &em, &ne) == C0_OK);
	struct c0_sim_scene *sc;
	c0_sim_scene_new(&s, em, ne, 0, &sc);
	struct c0_support_conf c = C0_SUPPORT_DEFAULTS;
	c.grid.pixel_nm = 100, c.grid.fwhm_nm = 229;
	struct c0_cov_acc *a;
	c0_cov_acc_new(32, 32, c0_support_lag(&c), &a);
	double ph[32 * 32];
	float fr[32 * 32];
	const double sd = 12;
	struct c0_rng r;
	c0_rng_init(&r, 99, 1);
	for (int t = 0; t < s.frames; t++) {
		c0_sim_render(sc, t, ph);
		for (int i = 0; i < 32 * 32; i++)
			fr[i] = (float)(100 + ph[i] + sd * c0_rng_normal(&r));
		c0_cov_acc_add(a, fr);
	}
	struct c0_cov cov;
	c0_cov_acc_finish(a, &cov);
	struct c0_support_result res;
	memset(&res, 0, sizeof res);
	CHECK(c0_support_solve(&c, &cov, &res) == C0_OK);
	CHECK_MSG(fabs(res.sigma2 - sd * sd) <= 0.1 * sd * sd, "sigma2 %g vs %g", res.sigma2, sd * sd);
	CHECK(res.support_pixels > 0);
	/* on that support: the working-set fit against the whole-grid one */
	struct c0_support_result nr;
	memset(&nr, 0, sizeof nr);
	c.fista.maxit = 100;
	CHECK(c0_support_noise_solve(&c, &cov, res.mask, &nr) == C0_OK);
	const double s2 = masked_sigma2(&c, &cov, res.mask);
	CHECK_MSG(fabs(nr.sigma2 / s2 - 1) < 1e-9 && fabs(nr.sigma2 - sd * sd) <= 0.1 * sd * sd,
		  "masked sigma2 %.12g, whole grid %.12g", nr.sigma2, s2);
	c0_support_result_free(&nr);
	c0_support_result_free(&res);
	c0_cov_free(&cov);
	c0_sim_scene_free(sc);
	free(em);
}

/* A simulated covariance (W x W, 400 frames, Gaussian read noise) in memory. */
static void sim_cov(int W, int filaments, const struct c0_support_conf *c, struct c0_cov *cov)
{
	struct c0_sim_conf s;
	c0_sim_defaults(&s);
	s.width = s.height = W, s.frames = 400, s.nangles = 1, s.background = 0, s.filaments = filaments;
	struct c0_emitter *em;
	int ne;
	CHECK(c0_sim_structure(&s, &em, &ne) == C0_OK);
	struct c0_sim_scene *sc;
	c0_sim_scene_new(&s, em, ne, 0, &sc);
	struct c0_cov_acc *a;
	c0_cov_acc_new(W, W, c0_support_lag(c), &a);
	double *ph = malloc(sizeof *ph * W * W);
	float *fr = malloc(sizeof *fr * W * W);
	struct c0_rng r;
	c0_rng_init(&r, 99, 1);
	for (int t = 0; t < s.frames; t++) {
		c0_sim_render(sc, t, ph);
		for (int i = 0; i < W * W; i++)
			fr[i] = (float)(100 + ph[i] + 12 * c0_rng_normal(&r));
		c0_cov_acc_add(a, fr);
	}
	c0_cov_acc_finish(a, cov);
	free(ph), free(fr);
	c0_sim_scene_free(sc);
	free(em);
}

static double solve_obj(const struct c0_support_conf *c, const struct c0_cov *cov, struct c0_support_result *res)
{
	memset(res, 0, sizeof *res);
	CHECK(c0_support_solve(c, cov, res) == C0_OK);
	return res->nhist ? res->hist[res->nhist - 1] : NAN;
}

/* Both working-set solvers reach their tolerance before 2000 iterations;
 * pruned (its own step) is the lower at 1e-5, and at 1e-6 within 1e-5 of a
 * long (40000 iterations) FISTA run, whose gap is below 1e-3; the default
 * (every one of 2000 iterations) ends with a gap below 2e-2. With the set
 * kept until FISTA converged on it (before 2026-12), the tolerance was
 * never met, and the gaps were 6.4e-2 (default) and 6.8e-2 (long run). */
static void test_solver_converges(void)
{
	struct c0_support_conf c = C0_SUPPORT_DEFAULTS;
	c.grid.pixel_nm = 100, c.grid.fwhm_nm = 229, c.lambda_rel = 1e-2, c.solver = C0_SUPPORT_PRUNED, c.fista.maxit = 5000;
	struct c0_cov cov;
	sim_cov(48, 4, &c, &cov);
	struct c0_support_result p, t, f, d, lg;
	const double Fp = solve_obj(&c, &cov, &p);
	c.fista.tol = 1e-6, c.fista.maxit = 20000;
	const double Ft = solve_obj(&c, &cov, &t);
	c.solver = C0_SUPPORT_FISTA, c.fista.maxit = 2000, c.fista.tol = 1e-5;
	const double Ff = solve_obj(&c, &cov, &f);
	c.fista.tol = -1;
	const double Fd = solve_obj(&c, &cov, &d);
	c.fista.maxit = 40000, c.fista.tol = 1e-8;
	const double Fl = solve_obj(&c, &cov, &lg);
	fprintf(stderr, "pruned: %d its, converged %d, gap %.2e, F %.10g, %d pixels; tol 1e-6: %d its, F %.10g; fista: %d its,"
		" converged %d, gap %.2e, F %.10g; default: %d its, gap %.2e, F %.10g; long fista: %d its, converged %d, gap %.2e,"
		" F %.10g, %d pixels\n", p.iters, p.converged, p.gap, Fp, p.support_pixels, t.iters, Ft, f.iters, f.converged, f.gap,
		Ff, d.iters, d.gap, Fd, lg.iters, lg.converged, lg.gap, Fl, lg.support_pixels);
	/* measured: pruned 2075 its, gap 1.5e-3; with tol 1e-6, 7273 its and
	 * 3e-6 above the long run (gap 3.5e-4); fista 1383 its, gap 3.9e-3;
	 * the default gap 6.4e-3 */
	CHECK(p.converged && p.gap < 5e-3 && t.converged);
	CHECK(f.converged && f.iters < 2000 && d.iters == 2000 && d.gap < 2e-2 && lg.gap < 1e-3);
	CHECK_MSG(Fp < Ff && Fd < Ff && fabs(Ft - Fl) <= 1e-5 * fabs(Fl), "objective %.10g (tol 1e-6: %.10g) vs long FISTA %.10g, "
		  "tol 1e-5 %.10g, default %.10g", Fp, Ft, Fl, Ff, Fd);
	c0_support_result_free(&p), c0_support_result_free(&t), c0_support_result_free(&f), c0_support_result_free(&d);
	c0_support_result_free(&lg);
	c0_cov_free(&cov);
}

/* The pixel guard (ops/covariance.h): a model covariance Psi diag(x) Psi^T
 * plus noise on the diagonal, for sparse and for dense emitters, keeps every
 * variance; a pixel with noise of its own is set to the slow formula's
 * S + N, inside, on the edge and at a corner. */
static void test_pixel_guard(void)
{
	enum { W = 16, H = 12, RR = 4 };
	struct c0_support_conf sc = C0_SUPPORT_DEFAULTS;
	sc.grid.pixel_nm = 100, sc.grid.fwhm_nm = 229, sc.grid.srf = RR;
	const double g = c0_support_guard_ratio(&sc), s2 = 50;
	CHECK(g > 0.5 && g < 0.7);
	struct c0_covop op;
	CHECK(c0_covop_init(&op, H, W, RR, c0_grid_sigma_px(&sc.grid), 3) == C0_OK);
	const size_t n = (size_t)W * H, L = n * RR * RR;
	double *x = calloc(L, sizeof *x), *v0 = malloc(n * sizeof *v0);
	for (int dense = 0; dense < 2; dense++) {
		for (size_t a = 0; a < L; a++)
			x[a] = dense || c0_rng_uniform(&rng) < 0.02 ? 1e4 * c0_rng_uniform(&rng) : 0;
		struct c0_cov_acc *acc;
		struct c0_cov cov;
		c0_cov_acc_new(W, H, 3, &acc);
		float f[W * H];
		for (int t = 0; t < 3; t++) {
			for (size_t i = 0; i < n; i++)
				f[i] = (float)c0_rng_uniform(&rng);
			c0_cov_acc_add(acc, f);
		}
		CHECK(c0_cov_acc_finish(acc, &cov) == C0_OK);
		cov.frames = 500;
		c0_covop_forward(&op, &cov, x, cov.r);
		for (size_t i = 0; i < n; i++)
			cov.r[i] += s2;
		memcpy(v0, cov.r, n * sizeof *v0);
		size_t set;
		CHECK(c0_cov_guard(&cov, g, &set) == C0_OK);
		CHECK_MSG(set == 0 && !memcmp(v0, cov.r, n * sizeof *v0), "%s emitters: %zu variances set", dense ? "dense" : "sparse", set);
		/* noise of their own: inside, on the top edge, at the bottom-right corner */
		const size_t hot[3] = { 5 * W + 7, 4, n - 1 };
		for (int k = 0; k < 3; k++)
			cov.r[hot[k]] += 5 * cov.r[hot[k]] + 40 * s2;
		memcpy(v0, cov.r, n * sizeof *v0);
		CHECK(c0_cov_guard(&cov, g, &set) == C0_OK && set == 3);
		for (int k = 0; k < 3; k++) {
			const int y = (int)(hot[k] / W), xx = (int)(hot[k] % W);
			/* the slow way: each neighbour's covariance read at its own lag */
			double S = 0, nb[4];
			int m = 0;
			for (int l = 0; l < cov.nlag; l++)
				for (int sgn = -1; sgn <= 1; sgn += 2) {
					const int dy = sgn * cov.dy[l], dx = sgn * cov.dx[l];
					if (dy * dy + dx * dx != 1 || y + dy < 0 || y + dy >= H || xx + dx < 0 || xx + dx >= W)
						continue;
					/* the pair is stored at the upper-left pixel of the two */
					const size_t at = sgn > 0 ? hot[k] : (size_t)(y + dy) * W + xx + dx;
					S += cov.r[(size_t)l * n + at], nb[m++] = v0[(size_t)(y + dy) * W + xx + dx];
				}
			for (int i = 0; i < m; i++)
				for (int j = i + 1; j < m; j++)
					if (nb[j] < nb[i]) {
						double t = nb[i];
						nb[i] = nb[j], nb[j] = t;
					}
			const double N = m % 2 ? nb[m / 2] : (nb[m / 2 - 1] + nb[m / 2]) / 2;
			CHECK_REL(cov.r[hot[k]], S / m / g + N, 1e-12);
			CHECK(m == (k == 0 ? 4 : k == 1 ? 3 : 2));
		}
		c0_cov_free(&cov);
	}
	free(x), free(v0);
	c0_covop_free(&op);
}

/* one angle, 500 frames, fixed seed: the support matches the truth */
static void test_accuracy(void)
{
	char dir[] = "/tmp/c0_test_support_XXXXXX";
	CHECK(mkdtemp(dir) != NULL);
	struct c0_sim_conf s;
	c0_sim_defaults(&s);
	s.seed = 11, s.nangles = 1;
	struct c0_outdir out;
	c0_outdir_open(&out, dir, 1);
	struct c0_sim_result sr;
	CHECK(c0_simulate(&s, &out, &sr) == C0_OK);
	CHECK(c0_outdir_commit(&out) == C0_OK);
	c0_sim_result_free(&sr);
	char p[256];
	snprintf(p, sizeof p, "%s/stack_q01.tif", dir);
	struct c0_frames fr;
	CHECK(c0_frames_open(&fr, p) == C0_OK);
	struct c0_support_conf c = C0_SUPPORT_DEFAULTS;
	c.grid.pixel_nm = 100, c.grid.fwhm_nm = 229;
	struct c0_support_result res, thin;
	CHECK(c0_support_stack(&c, &fr, &res) == C0_OK);
	/* the l1 support alone, one pixel across the tubes, at the same lambda
	 * (without a radius the rule has no width's share) */
	c.label_radius_nm = 0, c.lambda_rel = res.cv.chosen_rel;
	CHECK(c0_support_stack(&c, &fr, &thin) == C0_OK);
	c0_frames_close(&fr);
	snprintf(p, sizeof p, "%s/truth_support.tif", dir);
	int tw, th;
	uint8_t *tm = c0_truth_mask(p, &tw, &th);
	CHECK(tm && tw == res.Lx && th == res.Ly);
	struct c0_jaccard ji = { 0 }, j0 = { 0 };
	CHECK(tm && c0_jaccard_index(res.mask, tm, res.Ly, res.Lx, 25, 40, 3 * 4, &ji) == C0_OK);
	CHECK(tm && c0_jaccard_index(thin.mask, tm, res.Ly, res.Lx, 25, 40, 3 * 4, &j0) == C0_OK);
	fprintf(stderr, "support: JI %.3f (tp %d fp %d fn %d), %d iterations, %.2fs; without the label radius %.3f (%d pixels "
		"against %d)\n", ji.index, ji.tp, ji.fp, ji.fn, res.iters, res.t_solve, j0.index, thin.support_pixels,
		res.support_pixels);
	CHECK(ji.index >= 0.65);
	/* the growth adds pixels and no variance: the l1 pixels are the same */
	int same = thin.support_pixels < res.support_pixels;
	for (size_t i = 0; i < (size_t)res.Ly * res.Lx; i++)
		same &= res.rx[i] == thin.rx[i] && (!thin.mask[i] || res.mask[i]);
	CHECK(same);
	CHECK_MSG(ji.index >= j0.index + 0.08, "labelled tubes: JI %.3f grown, %.3f without", ji.index, j0.index);
	c0_support_result_free(&res), c0_support_result_free(&thin);
	free(tm);
	snprintf(p, sizeof p, "rm -rf %s", dir);
	if (system(p)) {}
}

/* The noise pass's fast paths against the plain ones, bit for bit: an
 * accumulator with a region (the lags other than the guard's summed only
 * there, 0 elsewhere) and C = A^T R at a mask's pixels alone. */
static void test_noise_fast(void)
{
	enum { W = 23, H = 19, T = 45, D = 3 };
	uint8_t keep[W * H];
	for (int i = 0; i < W * H; i++)
		keep[i] = (i % W) / 4 % 2 == (i / W) / 5 % 2;   /* spans of 4 columns, shifted every 5 rows */
	struct c0_cov_acc *a, *b;
	CHECK(c0_cov_acc_new(W, H, D, &a) == C0_OK && c0_cov_acc_new(W, H, D, &b) == C0_OK);
	CHECK(c0_cov_acc_set_region(b, keep) == C0_OK);
	c0_cov_acc_set_guard(a, 0.5), c0_cov_acc_set_guard(b, 0.5);
	float fr[W * H];
	for (int t = 0; t < T; t++) {
		for (int i = 0; i < W * H; i++)
			fr[i] = (float)(100 + 10 * c0_rng_normal(&rng) + (i % 7 == 0 ? 30 * c0_rng_uniform(&rng) : 0));
		c0_cov_acc_add(a, fr), c0_cov_acc_add(b, fr);
	}
	CHECK(c0_cov_acc_set_region(b, keep) == C0_EINVAL);   /* after the first frame */
	const int y0 = 2, x0 = 3, h = 15, w = 17;
	struct c0_cov p, q;
	CHECK(c0_cov_acc_window(a, y0, x0, h, w, &p) == C0_OK && c0_cov_acc_window(b, y0, x0, h, w, &q) == C0_OK);
	int same = 1, zero = 1, kept = 0;
	for (int l = 0; l < p.nlag; l++) {
		const int whole = (p.dy[l] == 0 && p.dx[l] <= 1) || (p.dy[l] == 1 && p.dx[l] == 0);
		for (int i = 0; i < w * h; i++) {
			const double u = p.r[(size_t)l * w * h + i], v = q.r[(size_t)l * w * h + i];
			if (whole || keep[(y0 + i / w) * W + x0 + i % w])
				same &= memcmp(&u, &v, sizeof u) == 0, kept += !whole;
			else
				zero &= v == 0;
		}
	}
	CHECK_MSG(same && zero && kept > 100, "region: kept values equal %d, others 0 %d (%d kept)", same, zero, kept);
	same = 1;
	for (int i = 0; i < w * h; i++)
		same &= memcmp(&p.mean[i], &q.mean[i], sizeof *p.mean) == 0;
	CHECK(same);
	/* A^T R on a mask of the window's fine grid */
	struct c0_covop op;
	CHECK(c0_covop_init(&op, h, w, R, SIG, D) == C0_OK);
	const size_t L = (size_t)h * w * R * R;
	uint8_t *on = malloc(L);
	double *C = malloc(sizeof *C * L), *Co = malloc(sizeof *Co * L);
	for (size_t i = 0; i < L; i++)
		on[i] = c0_rng_uniform(&rng) < 0.1;
	c0_covop_adjoint(&op, &p, p.r, C);
	c0_covop_adjoint_on(&op, &p, p.r, on, Co);
	same = 1, zero = 1;
	for (size_t i = 0; i < L; i++)
		if (on[i])
			same &= memcmp(&C[i], &Co[i], sizeof *C) == 0;
		else
			zero &= Co[i] == 0;
	CHECK_MSG(same && zero, "A^T R on a mask: equal %d, 0 elsewhere %d", same, zero);
	free(on), free(C), free(Co);
	c0_covop_free(&op);
	c0_cov_free(&p), c0_cov_free(&q);
	c0_cov_acc_free(a), c0_cov_acc_free(b);
}

static int double_frame(void *ctx, int64_t t, float *frame, int H, int W)
{
	(void)ctx, (void)t;
	for (int i = 0; i < H * W; i++)
		frame[i] *= 2;
	return C0_OK;
}

/* The two block halves' means against the frames' own sums: frame t holds
 * t + pixel / 100, blocks of 3 over 14 frames (even blocks: 0-2, 6-8,
 * 12-13; odd: 3-5, 9-11); under 2 blocks, none */
static void test_block_means(void)
{
	enum { T = 14, H = 3, W = 4, B = 3 };
	static float fr[T * H * W];
	for (int t = 0; t < T; t++)
		for (int p = 0; p < H * W; p++)
			fr[(size_t)t * H * W + p] = (float)(t + p / 100.0);
	struct c0_frames f;
	CHECK(c0_frames_wrap(&f, fr, T, H, W, 100, "halves") == C0_OK);
	struct c0_support_conf c = C0_SUPPORT_DEFAULTS;
	c.grid = (struct c0_grid){ 100, 229, 4 };
	float *half[2];
	int64_t n[2];
	double sec;
	CHECK(c0_stack_block_means(&c, &f, B, half, n, &sec) == C0_OK);
	CHECK(half[0] && half[1] && n[0] == 8 && n[1] == 6);
	double err = 0;
	for (int p = 0; half[0] && half[1] && p < H * W; p++) {
		double s[2] = { 0, 0 };
		for (int t = 0; t < T; t++)
			s[(t / B) % 2] += t + p / 100.0;
		err = fmax(err, fmax(fabs(half[0][p] - s[0] / 8), fabs(half[1][p] - s[1] / 6)));
	}
	CHECK_MSG(err < 1e-5, "block means: %g off", err);
	free(half[0]), free(half[1]);
	CHECK(c0_stack_block_means(&c, &f, 8, half, n, &sec) == C0_OK && !half[0] && !half[1] && n[0] == 0);
	/* the halves wrap the conf's own hook: they see its frames */
	c.frame_fn = double_frame;
	CHECK(c0_stack_block_means(&c, &f, B, half, n, &sec) == C0_OK && half[0] && half[1]);
	CHECK(half[0] && half[1] && fabs(half[0][5] - 2 * (49 / 8.0 + 0.05)) < 1e-4 && fabs(half[1][5] - 2 * (42 / 6.0 + 0.05)) < 1e-4);
	free(half[0]), free(half[1]);
	c0_frames_close(&f);
}

/* c0_lambda_width_share: on a straight tube three fine pixels wide (the
 * model's exact covariance, no noise) the l1 support puts the tube on one
 * column of fine pixels where lambda is 1.2 times the share of the axis's
 * correlation, and on its three at 0.8 times (measured: one at 1.0, three
 * at 0.8, 0.65, 0.5). Along the tube l1 keeps every few rows: adjacent
 * pixels have nearly the same PSF either way. */
static void test_width_share(void)
{
	enum { W = 16, F = 4, LW = W * F };
	struct c0_support_conf c = C0_SUPPORT_DEFAULTS;
	c.grid.pixel_nm = 100, c.grid.fwhm_nm = 229, c.grid.srf = F, c.solver = C0_SUPPORT_PRUNED;
	c.fista.maxit = 10000, c.fista.tol = 1e-8;
	/* weights b, 1, b across: w^2 = 2 b / (1 + 2 b) fine pixels^2, a ring of radius sqrt(2) w */
	const double b = 0.35, fine = 25, w2 = 2 * b / (1 + 2 * b) * fine * fine;
	c.label_radius_nm = sqrt(2 * w2);
	const double share = c0_lambda_width_share(&c);
	struct c0_covop op;
	CHECK(c0_covop_init(&op, W, W, F, c0_grid_sigma_px(&c.grid), c0_support_lag(&c)) == C0_OK);
	struct c0_cov_acc *a;
	CHECK(c0_cov_acc_new(W, W, c0_support_lag(&c), &a) == C0_OK);
	float fr[W * W];
	for (int t = 0; t < 3; t++) {
		for (int i = 0; i < W * W; i++)
			fr[i] = (float)c0_rng_normal(&rng);
		c0_cov_acc_add(a, fr);
	}
	struct c0_cov cov;
	CHECK(c0_cov_acc_finish(a, &cov) == C0_OK);
	double *x = calloc(LW * LW, sizeof *x);
	for (int y = 0; y < LW; y++)
		x[y * LW + LW / 2 - 1] = x[y * LW + LW / 2 + 1] = b, x[y * LW + LW / 2] = 1;
	c0_covop_forward(&op, &cov, x, cov.r);
	int width[2];
	const double f[2] = { 1.2, 0.8 };
	for (int k = 0; k < 2; k++) {
		struct c0_support_result res = { 0 };
		c.lambda_rel = f[k] * share;   /* lambda_max is the axis's correlation, away from the ends */
		c.label_radius_nm = 0;         /* the l1 support alone */
		CHECK(c0_support_solve(&c, &cov, &res) == C0_OK);
		c.label_radius_nm = sqrt(2 * w2);
		int n = 0;   /* columns used, away from the ends */
		for (int xx = 0; xx < LW; xx++) {
			int used = 0;
			for (int y = LW / 4; y < 3 * LW / 4; y++)
				used |= res.rx[y * LW + xx] > 0;
			n += used;
		}
		width[k] = n;
		fprintf(stderr, "lambda %.2f x share (%.4f): %d columns, %d pixels, converged %d\n", f[k], share, n,
			res.support_pixels, res.converged);
		c0_support_result_free(&res);
	}
	CHECK_MSG(width[0] == 1 && width[1] == 3, "a tube's l1 support is %d and %d columns wide at 1.2 and 0.8 times "
		  "the width share", width[0], width[1]);
	free(x);
	c0_cov_free(&cov);
	c0_covop_free(&op);
}

int main(void)
{
	c0_rng_init(&rng, 42, 0);
	RUN(test_band_ops);
	RUN(test_band_occ);
	RUN(test_psf_factor);
	RUN(test_dense_identities);
	RUN(test_covariance);
	RUN(test_noise_map);
	RUN(test_noise_fast);
	RUN(test_covariance_operator);
	RUN(test_covnormal);
	RUN(test_covfit);
	RUN(test_pixel_guard);
	RUN(test_first_fail);
	RUN(test_wrong_inputs);
	RUN(test_block_means);
	RUN(test_noise_variance);
	RUN(test_solver_converges);
	RUN(test_width_share);
	RUN(test_accuracy);
	return CHECK_DONE();
}
