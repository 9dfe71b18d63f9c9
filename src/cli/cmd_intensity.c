/* col0rme intensity: per-angle intensity and background on a known support. */
#include "cli/commands.h"
#include "cli/cmdkit.h"

static const char *const params[] = { "pixel_nm", "channel", "fwhm_nm", "psf_image", "emission_nm", "na", "srf", "background", "beta", "nu", "discrepancy",
				      "mu", "cg_tol", "graph_radius", "graph_orient", "noise_variance", "offset_map", "variance_map", "gain_map", NULL };

int cmd_intensity(int argc, char **argv)
{
	const char *support = NULL;
	const struct c0_opt extra[] = {
		{ "support", 0, C0_OPT_STRING, &support, "TIF", "support mask from 'col0rme support' (required)", "none", 0, NULL },
	};
	struct c0_cmd_spec spec = { "intensity", "--support TIF --fwhm NM [options] -o OUTDIR STACK...",
		"Estimate each stack's mean intensity on the support (fine grid) and its smooth background\n"
		"(coarse grid), with the smoothness weight set by the discrepancy principle. Writes\n"
		"OUTDIR/intensity_qNN.tif, OUTDIR/background_qNN.tif and OUTDIR/report.json.",
		NULL, 0, 1, C0_MAX_STACKS, 1 };
	struct c0_cli k;
	int rc = c0_cli_start(&k, &spec, params, extra, 1, argc, argv);
	if (rc)
		return rc == 1 ? 0 : 2;
	struct c0_result *r = NULL;
	int st = c0_cli_open(&k);   /* refuse a bad output directory before the work */
	if (!st)
		st = c0_run_intensity_files(&k.m.c, k.stacks, k.n, support, &r);
	return c0_cli_end(&k, "intensity", r, st, argc, argv);
}
