/* The PSF width from the covariance's lags (stages/lambda_psf.c): the
 * simulator's Gaussian read back at its FWHM whatever the pixel size, the
 * Airy disk of the same FWHM read as a narrower Gaussian (its core), and a
 * band without lag 2 refused. Small stacks: 48 x 48 x 300 frames. */
#include "check.h"
#include "ops/covariance.h"
#include "stages/lambda.h"
#include "sim/sim.h"
#include "core/err.h"

#include <math.h>
#include <string.h>

/* the FWHM the covariance of a simulated single-angle stack says */
static double fwhm_of(int psf, double pixel_nm, int d)
{
	struct c0_sim_conf s;
	c0_sim_defaults(&s);
	s.width = s.height = 48, s.frames = 300, s.nangles = 1, s.angles[0] = 65, s.z_max_nm = 200;
	s.seed = 5, s.psf = psf, s.pixel_nm = pixel_nm;
	struct c0_sim_result res;
	CHECK(c0_simulate(&s, NULL, &res) == C0_OK);
	struct c0_cov_acc *a;
	struct c0_cov cov;
	double f = NAN;
	CHECK(c0_cov_acc_new(48, 48, d, &a) == C0_OK);
	for (int t = 0; t < s.frames; t++)
		c0_cov_acc_add(a, res.stack[0] + (size_t)t * 48 * 48);
	CHECK(c0_cov_acc_finish(a, &cov) == C0_OK);
	if (c0_lambda_psf_fwhm(&cov, NULL, pixel_nm, &f))
		f = -1;
	c0_cov_free(&cov);
	c0_sim_result_free(&res);
	return f;
}

static void test_gauss(void)
{
	const double f100 = fwhm_of(C0_SIM_PSF_GAUSS, 100, 3), f160 = fwhm_of(C0_SIM_PSF_GAUSS, 160, 3);
	CHECK_MSG(fabs(f100 / 229 - 1) < 0.03, "Gaussian 229 nm at 100 nm pixels read as %.1f nm", f100);
	CHECK_MSG(fabs(f160 / 229 - 1) < 0.03, "Gaussian 229 nm at 160 nm pixels read as %.1f nm", f160);
}

static void test_airy(void)
{
	const double f = fwhm_of(C0_SIM_PSF_AIRY, 100, 3);
	CHECK_MSG(f > 0.88 * 229 && f < 0.97 * 229, "Airy 229 nm read as %.1f nm (a narrower Gaussian)", f);
}

static void test_refused(void)
{
	CHECK(fwhm_of(C0_SIM_PSF_GAUSS, 100, 1) < 0 && strstr(c0_errmsg(), "lags 1 and 2"));
}

int main(void)
{
	RUN(test_gauss);
	RUN(test_airy);
	RUN(test_refused);
	return CHECK_DONE();
}
