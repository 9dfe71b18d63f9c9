/* Measures the automatic lambda against a sweep: for a simulated stack
 * (DIR/stack_q01.tif with DIR/truth_support.tif), the Jaccard index of the
 * support for each fixed lambda and for the automatic choice.
 *   lambda_sweep DIR FWHM_NM [l1|cel0] [lambda ...]       (docs/history/lambda-drift.md) */
#include "stages/support.h"
#include "ops/covpool.h"
#include "eval/metrics.h"
#include "io/frames.h"
#include "io/tiff.h"
#include "core/err.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double ji(const struct c0_support_result *r, const uint8_t *tm, int margin)
{
	struct c0_jaccard j;
	if (!tm)
		return -1;
	c0_jaccard_index(r->mask, tm, r->Ly, r->Lx, 25, 40, margin, &j);
	return j.index;
}

int main(int argc, char **argv)
{
	if (argc < 3) {
		fprintf(stderr, "usage: lambda_sweep DIR FWHM_NM [l1|cel0] [lambda ...]\n");
		return 2;
	}
	char p[1024];
	snprintf(p, sizeof p, "%s/stack_q01.tif", argv[1]);
	if (strstr(argv[1], ".tif"))
		snprintf(p, sizeof p, "%s", argv[1]);
	struct c0_frames rd;
	if (c0_frames_open(&rd, p))
		return fprintf(stderr, "%s\n", c0_errmsg()), 1;
	struct c0_support_conf c = C0_SUPPORT_DEFAULTS;
	c.grid.pixel_nm = getenv("PIXEL") ? atof(getenv("PIXEL")) : rd.pixel_nm, c.grid.fwhm_nm = atof(argv[2]);
	if (argc > 3 && !strcmp(argv[3], "cel0"))
		c.penalty = C0_PENALTY_CEL0;
	struct c0_cov half[2], cov;
	double tc;
	if (c0_stack_covariance_halves(&c, &rd, half, &tc) || c0_cov_pool(&half[0], &half[1], &cov))
		return fprintf(stderr, "%s\n", c0_errmsg()), 1;
	c0_frames_close(&rd);
	snprintf(p, sizeof p, "%s/truth_support.tif", argv[1]);
	struct c0_tiff_info in;
	float *t;
	uint8_t *tm = NULL;
	if (!c0_tiff_load_f32(p, &in, &t)) {
		tm = malloc(in.width * in.height);
		for (int64_t i = 0; i < in.width * in.height; i++)
			tm[i] = t[i] > 0;
	}
	const int margin = 3 * c.grid.srf;
	struct c0_lambda_result cv;
	if (c0_lambda_auto(&c, &half[0], &half[1], &cv))
		return fprintf(stderr, "%s\n", c0_errmsg()), 1;
	printf("# %s cov %.2fs, auto %.3fs, chosen %.3g, noise_rel %.3g\n", argv[1], tc, cv.seconds, cv.chosen_rel, cv.noise_rel);
	double e2 = 0, mxv = 0;
	size_t np = (size_t)cov.W * cov.H;
	for (size_t i = 0; i < np; i++)
		mxv = mxv > cov.r[i] ? mxv : cov.r[i];
	for (int l = 0; l < cov.nlag; l++)
		for (size_t i = 0; i < np; i++) {
			double d = (half[0].r[l * np + i] - half[1].r[l * np + i]) / mxv;
			e2 += c0_cov_weight(&cov, l) * d * d;
		}
	printf("# noise energy 1/2 ||R - E R||^2 ~ %.6g\n", 0.5 * e2 / 4);
	int nl = argc > 4 ? argc - 4 : 0;
	double lam[64];
	for (int k = 0; k < nl; k++)
		lam[k] = atof(argv[4 + k]);
	lam[nl++] = cv.chosen_rel;
	for (int k = 0; k < nl; k++) {
		struct c0_support_result r = { 0 };
		c.lambda_rel = lam[k];
		if (c0_support_solve(&c, &cov, &r))
			return fprintf(stderr, "%s\n", c0_errmsg()), 1;
		double l1 = 0;
		for (int i = 0; i < r.Ly * r.Lx; i++)
			l1 += r.rx[i] / r.norm;
		printf("%s lambda %.4g JI %.3f resid %.6g support %d iters %d solve %.2fs%s\n", argv[1], lam[k], ji(&r, tm, margin),
		       r.hist[r.nhist - 1] - r.lambda * l1, r.support_pixels, r.iters, r.t_solve, k == nl - 1 ? " (auto)" : "");
		fflush(stdout);
		c0_support_result_free(&r);
	}
	free(tm);
	if (tm)
		free(t);
	c0_cov_free(&half[0]), c0_cov_free(&half[1]), c0_cov_free(&cov);
	return 0;
}
