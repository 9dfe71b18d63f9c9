/* Automatic lambda for the support, from the noise of the data itself.
 *
 * The frames split into two interleaved halves whose covariances R_A, R_B
 * come from the same streaming pass. Their noise is independent, so
 * D = (A^T R_A - A^T R_B) / 2 has the noise of C = A^T R (all frames) and no
 * signal: its robust sd (1.4826 MAD over the fine pixels) is sigma_C. A
 * pixel enters the l1 support where its correlation exceeds the threshold
 *   t = max(rel0 * lambda_max, kappa * sigma_C),
 * i.e. lambda relative to lambda_max as measured best on our simulations
 * (rel0), but never within kappa noise sds of zero, where pure noise would
 * enter (the background specks of real, noisier stacks). CEL0 gets the same
 * threshold on its l0 scale, lowered as measured: lambda = 0.03 t^2 / (2 ||a||^2)
 * (median column norm).
 * Measured in docs/parameters.md, with why held-out cross-validation and
 * the discrepancy principle were not kept. */
#pragma once
#include "ops/covariance.h"

struct c0_lambda_result {
	double chosen_rel;    /* lambda / lambda_max for the solve on all frames */
	double noise_rel;     /* sigma_C / lambda_max (l1 scale) */
	double floor_rel;     /* rel0 */
	double kappa;
	int noise_bound;      /* 1 when kappa sigma_C set the threshold */
	double seconds;
};

struct c0_support_conf;
/* Uses c's optics, lag and penalty. */
int c0_lambda_auto(const struct c0_support_conf *c, const struct c0_cov *a, const struct c0_cov *b,
		   struct c0_lambda_result *out);
