#include "stages/depthfit.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>

#define MAXQ_FIT 64

/* the best of the candidates' scores for projections y, refined */
static float fit_one(const double *Wc, const double *nrm, int nq, int nc, double z0, double step, const double *y,
		     double *score)
{
	int best = -1;
	for (int c = 0; c < nc; c++) {
		double s = 0;
		for (int q = 0; q < nq; q++)
			s += Wc[(size_t)c * nq + q] * y[q];
		score[c] = s > 0 ? s * s / nrm[c] : 0;
		if (score[c] > 0 && (best < 0 || score[c] > score[best]))
			best = c;
	}
	if (best < 0)
		return 0;
	double off = 0;
	if (best > 0 && best < nc - 1) {
		const double s0 = score[best - 1], s1 = score[best], s2 = score[best + 1], den = s0 - 2 * s1 + s2;
		if (den < 0)
			off = fmin(0.5, fmax(-0.5, 0.5 * (s0 - s2) / den));
	}
	return (float)(z0 + (best + off) * step);
}

int c0_depth_fit(const struct c0_tirf *t, int nq, const double *angles, const double *gain, int nz, double z0,
		 double dz, const float *f, size_t np, float *depth)
{
	if (nq < 1 || nq > MAXQ_FIT || nz < 1 || !(dz > 0))
		return c0_fail(C0_EINVAL, "depth fit: %d angles, %d bins of %g nm", nq, nz, dz);
	const double range = nz * dz;
	const int nc = 1 + (int)fmin(4096, ceil(range / fmin(1.0, dz / 4)));   /* candidates, ends included */
	const double step = range / (nc - 1);
	double *W = c0_alloc((size_t)nq * nz, sizeof *W), *Wc = c0_alloc((size_t)nq * nc, sizeof *Wc);
	double *nrm = c0_alloc((size_t)nc, sizeof *nrm);
	int st = W && Wc && nrm ? c0_tirf_weights(t, nq, angles, gain, nz, z0, dz, W) : C0_ENOMEM;
	for (int q = 0; !st && q < nq; q++) {
		double p;
		if ((st = c0_tirf_p(t, angles[q], &p)))
			break;
		const double g = c0_tirf_i0(t, angles[q]) * (gain ? gain[q] : 1);
		for (int c = 0; c < nc; c++)
			Wc[(size_t)c * nq + q] = g * exp(-p * (z0 + c * step));
	}
	for (int c = 0; !st && c < nc; c++) {
		nrm[c] = 0;
		for (int q = 0; q < nq; q++)
			nrm[c] += Wc[(size_t)c * nq + q] * Wc[(size_t)c * nq + q];
	}
	int fail = 0;
	if (!st) {
#pragma omp parallel
		{
			double *score = malloc(sizeof *score * (size_t)nc), y[MAXQ_FIT];
			if (!score)
#pragma omp atomic write
				fail = 1;
#pragma omp for schedule(static)
			for (size_t p = 0; p < np; p++) {
				double tot = 0;
				for (int q = 0; q < nq; q++)
					y[q] = 0;
				for (int j = 0; j < nz; j++) {
					const double v = f[(size_t)j * np + p];
					tot += v;
					for (int q = 0; q < nq && v != 0; q++)
						y[q] += W[q * nz + j] * v;
				}
				depth[p] = tot > 0 && score ? fit_one(Wc, nrm, nq, nc, z0, step, y, score) : 0;
			}
			free(score);
		}
	}
	free(W), free(Wc), free(nrm);
	return st ? st : fail ? C0_ENOMEM : C0_OK;
}
