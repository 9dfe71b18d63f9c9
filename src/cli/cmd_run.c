/* col0rme run: the whole method (support, intensity and background per
 * stack, MA-TIRF volume) in one command: options, c0_run, the files. */
#include "cli/commands.h"
#include "cli/cmdkit.h"

static const char *const params[] = { "pixel_nm", "channel", "fwhm_nm", "psf_image", "emission_nm", "na", "srf", "support_stacks", "support_pool", "label_radius_nm",
				      "penalty", "lambda", "lambda_rule", "fwhm_rule", "support_solver", "tile", "drift", "no_drift", "pixel_guard", "frc", "beta", "nu", "discrepancy", "mu", "graph_radius", "graph_orient", "depth_pool_nm", "depth_pool_range_nm", "depth_noise_block",
				      "bleach", "bleach_factors", "acquisition", "acquisition_order", "gaps_frames", "baseline",
				      "offset_map", "variance_map", "gain_map", "common_pattern",
				      C0_MATIRF_PARAMS, NULL };

int cmd_run(int argc, char **argv)
{
	struct c0_cmd_spec spec = { "run", "[options] -o OUTDIR STACK1.tif [STACK2.tif ...]",
		"3D-COL0RME: the support (from the --support-angles stacks), each stack's intensity\n"
		"and background, and with --angles the MA-TIRF volume. Without --angles: 2D COL0RME.\n"
		"A stack at or below the critical angle (epi) only joins the support. With --angles\n"
		"the fade from photobleaching across the stacks (recorded in the given order unless\n"
		"--acquisition-order/--gaps/--acquisition say otherwise) is estimated and corrected.\n"
		"Writes OUTDIR/support.tif (uint8 0/1, fine grid; fine pixel (i, j) covers\n"
		"[i p/r, (i+1) p/r) nm from the top-left corner), rx.tif, intensity_qNN.tif (fine),\n"
		"background_qNN.tif (coarse), volume.tif (depth bins x fine grid), depth.tif,\n"
		"depth.png, render.tif (the intensities splatted with a Gaussian of the localisation\n"
		"precision, one plane per stack), drift.csv, drift.png and report.json (every\n"
		"parameter and estimate; \"z_nm\": bin centres).",
		NULL, 0, 1, C0_MAX_STACKS, 1 };
	struct c0_cli k;
	int rc = c0_cli_start(&k, &spec, params, NULL, 0, argc, argv);
	if (rc)
		return rc == 1 ? 0 : 2;
	struct c0_result *r = NULL;
	int st = c0_cli_open(&k);   /* refuse a bad output directory before the work */
	if (!st)
		st = c0_run(&k.m.c, k.stacks, k.n, &r);
	return c0_cli_end(&k, "run", r, st, argc, argv);
}
