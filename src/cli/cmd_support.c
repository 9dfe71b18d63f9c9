/* col0rme support: COL0RME support estimation from one or more stacks. */
#include "cli/commands.h"
#include "cli/cmdkit.h"

static const char *const params[] = { "pixel_nm", "channel", "fwhm_nm", "psf_image", "emission_nm", "na", "srf", "support_pool", "label_radius_nm", "penalty", "lambda", "lambda_rule", "fwhm_rule",
				      "iterations", "support_solver", "tol", "reweightings", "lag", "tile", "drift", "no_drift", "pixel_guard", "frc",
				      "offset_map", "variance_map", "gain_map", NULL };

int cmd_support(int argc, char **argv)
{
	struct c0_cmd_spec spec = { "support", "--fwhm NM [options] -o OUTDIR STACK...",
		"Estimate the emitters' support on the fine grid from each stack's spatial covariance\n"
		"(COL0RME); several stacks of one sample are pooled into one support (--support-pool 0:\n"
		"each stack's, joined). Writes OUTDIR/support.tif\n"
		"(uint8 0/1; fine pixel (i, j) covers [i p/r, (i+1) p/r) nm from the top-left corner),\n"
		"OUTDIR/rx.tif (float32 emitter variance, one plane per support) and OUTDIR/report.json.",
		NULL, 0, 1, C0_MAX_STACKS, 1 };
	struct c0_cli k;
	int rc = c0_cli_start(&k, &spec, params, NULL, 0, argc, argv);
	if (rc)
		return rc == 1 ? 0 : 2;
	struct c0_result *r = NULL;
	int st = c0_cli_open(&k);
	if (!st)
		st = c0_run_support(&k.m.c, k.stacks, k.n, &r);
	return c0_cli_end(&k, "support", r, st, argc, argv);
}
