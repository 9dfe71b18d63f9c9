#include "stages/lambda.h"
#include "stages/support.h"
#include "ops/covop.h"
#include "optics/psf.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* docs/parameters.md: rel0 = 1e-2 was best (or within 0.03 of the best
 * Jaccard index) on every simulated stack of the panel; kappa = 4 keeps the
 * panel's choice (sigma_C <= 2e-3 lambda_max there) and takes the MusiJ
 * stacks' far-from-structure share below 10 %. */
static const double REL0 = 1e-2, KAPPA = 4;
/* CEL0 does not shrink what it keeps, and is best with a lower entry
 * threshold: 3e-6 lambda_max (l0 scale) on the panel, 0.03 of the square of
 * the l1 choice */
static const double CEL0_GAMMA = 0.03;

static int cmpd(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* sorts v */
static double median(double *v, size_t n)
{
	qsort(v, n, sizeof *v, cmpd);
	return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* C = A^T vec(R / norm) and tr(R / norm) */
static void correlate(struct c0_covop *op, const struct c0_cov *cov, double norm, double *R, double *C, double *trR)
{
	const size_t n = (size_t)cov->W * cov->H;
	*trR = 0;
	for (int l = 0; l < cov->nlag; l++)
		for (size_t i = 0; i < n; i++) {
			R[(size_t)l * n + i] = cov->r[(size_t)l * n + i] / norm;
			if (l == 0)
				*trR += R[i];
		}
	c0_covop_adjoint(op, cov, R, C);
}

int c0_lambda_auto(const struct c0_support_conf *c, const struct c0_cov *a, const struct c0_cov *b,
		   struct c0_lambda_result *out)
{
	double t0 = c0_now();
	memset(out, 0, sizeof *out);
	if (a->W != b->W || a->H != b->H || a->nlag != b->nlag)
		return c0_fail(C0_EINVAL, "lambda: the two halves differ in size");
	const int W = a->W, H = a->H, r = c->srf;
	const size_t n = (size_t)W * H, L = n * r * r;
	struct c0_covop op;
	int st = c0_covop_init(&op, H, W, r, c0_psf_sigma_px(c->fwhm_nm, c->pixel_nm), a->d);
	if (st)
		return st;
	double *R = c0_alloc((size_t)a->nlag * n, sizeof *R), *ca = c0_alloc(L, sizeof *ca);
	double *cb = c0_alloc(L, sizeof *cb), *d = c0_alloc(L, sizeof *d);
	if (!R || !ca || !cb || !d) {
		st = C0_ENOMEM;
		goto out;
	}
	double norm = 0, tra, trb;
	for (size_t i = 0; i < n; i++)
		norm = fmax(norm, 0.5 * (a->r[i] + b->r[i]));
	if (!(norm > 0)) {
		st = c0_fail(C0_EINVAL, "the stack does not fluctuate (zero temporal variance everywhere)");
		goto out;
	}
	correlate(&op, a, norm, R, ca, &tra);
	correlate(&op, b, norm, R, cb, &trb);
	/* lambda_max of the mean of the halves, on both scales (as in support.c) */
	const double s0 = fmax(0, 0.5 * (tra + trb) / (double)n);
	double lmax = 0, lmax0 = 0;
	for (size_t i = 0; i < L; i++) {
		double g = 0.5 * (ca[i] + cb[i]) - s0 * op.n[i];
		lmax = fmax(lmax, g);
		if (g > 0)
			lmax0 = fmax(lmax0, g * g / (2 * op.n[i] * op.n[i]));
		d[i] = fabs(ca[i] - cb[i]) / 2;
	}
	if (!(lmax > 0)) {
		st = c0_fail(C0_EINVAL, "the stack's covariance correlates with no emitter position (lambda_max = 0)");
		goto out;
	}
	const double sig = 1.4826 * median(d, L);
	out->noise_rel = sig / lmax, out->floor_rel = REL0, out->kappa = KAPPA;
	out->noise_bound = KAPPA * sig > REL0 * lmax;
	const double t = fmax(REL0 * lmax, KAPPA * sig);
	if (c->penalty == C0_PENALTY_L1) {
		out->chosen_rel = t / lmax;
	} else {
		memcpy(d, op.n, L * sizeof *d);
		double nm = median(d, L);
		out->chosen_rel = fmin(CEL0_GAMMA * t * t / (2 * nm * nm) / lmax0, 0.5);
	}
out:
	free(R), free(ca), free(cb), free(d);
	c0_covop_free(&op);
	out->seconds = c0_now() - t0;
	return st;
}
