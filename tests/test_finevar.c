/* ops/finevar: the fine grid's predicted pixel variance against the model's
 * own lag 0, sum_k x_k G[i][k]^2 (optics/psf's factors), at the fine pixels
 * that sit on camera pixel centres (r odd), also for a PSF wider than the
 * field (its kernel cut at the field); and its crest between two equal
 * columns of x lies half way. */
#include "check.h"
#include "ops/finevar.h"
#include "ops/ridge.h"
#include "optics/psf.h"
#include "core/band.h"
#include "core/rng.h"
#include "core/err.h"

#include <stdlib.h>

enum { NY = 12, NX = 14, R = 3 };
static const double SIG = 0.97;   /* 229 nm FWHM on 100 nm pixels */

static void lag0(double sig)
{
	const int Ly = NY * R, Lx = NX * R;
	double *x = calloc((size_t)Ly * Lx, sizeof *x), *v = malloc(sizeof(double) * Ly * Lx);
	struct c0_rng g;
	c0_rng_init(&g, 7, 0);
	for (int k = 0; k < 60; k++)   /* a sparse x, as a support */
		x[(size_t)(c0_rng_uniform(&g) * Ly) * Lx + (int)(c0_rng_uniform(&g) * Lx)] = 0.5 + c0_rng_uniform(&g);
	CHECK(c0_finevar(x, Ly, Lx, R, sig, v) == C0_OK);
	struct c0_band Gy = { 0 }, Gx = { 0 };
	CHECK(c0_psf_factor(NY, R, sig, &Gy) == C0_OK && c0_psf_factor(NX, R, sig, &Gx) == C0_OK);
	double worst = 0, top = 0;
	for (int i = 0; i < NY; i++)
		for (int j = 0; j < NX; j++) {
			double m = 0;
			for (int a = 0; a < Ly; a++)
				for (int b = 0; b < Lx; b++) {
					const double gy = c0_band_get(&Gy, i, a), gx = c0_band_get(&Gx, j, b);
					m += x[(size_t)a * Lx + b] * gy * gy * gx * gx;
				}
			worst = fmax(worst, fabs(v[(size_t)(i * R + R / 2) * Lx + j * R + R / 2] - m));
			top = fmax(top, m);
		}
	CHECK_MSG(top > 0 && worst <= 1e-6 * top, "sd %g px: worst %g of %g", sig, worst, top);
	c0_band_free(&Gy), c0_band_free(&Gx);
	free(x), free(v);
}

static void test_lag0(void)
{
	lag0(SIG);
	lag0(12);   /* 4 sd reach 144 fine pixels, the field 42 */
}

static void test_crest(void)
{
	const int L = 40;
	double *x = calloc((size_t)L * L, sizeof *x), *v = malloc(sizeof(double) * L * L);
	for (int y = 0; y < L; y++)
		x[y * L + 19] = x[y * L + 20] = 1;
	CHECK(c0_finevar(x, L, L, 4, SIG, v) == C0_OK);
	CHECK_CLOSE(c0_ridge_dist(v, L, L, 20, 19), 0.5, 0.01);
	CHECK_CLOSE(c0_ridge_dist(v, L, L, 20, 20), 0.5, 0.01);
	CHECK(c0_ridge_dist(v, L, L, 20, 22) > 2);
	free(x), free(v);
}

int main(void)
{
	RUN(test_lag0);
	RUN(test_crest);
	return CHECK_DONE();
}
