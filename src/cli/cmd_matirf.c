/* col0rme matirf: axial reconstruction from one image per TIRF angle. */
#include "cli/commands.h"
#include "cli/cmdkit.h"

static const char *const params[] = { "pixel_nm", C0_MATIRF_PARAMS, "offset", "matirf_background", "estimate_background",
				      "background_smooth", "psf_fwhm_nm", NULL };

int cmd_matirf(int argc, char **argv)
{
	struct c0_cmd_spec spec = { "matirf", "--angles DEG,... [options] -o OUTDIR IMAGE...",
		"Multi-angle TIRF axial reconstruction from one 2D image per angle (e.g. the\n"
		"intensity_qNN.tif of 'col0rme intensity', or background-corrected means). Writes\n"
		"OUTDIR/volume.tif (float32, depth bins x H x W, z spacing = bin width),\n"
		"OUTDIR/depth.tif (intensity-weighted mean depth, nm), OUTDIR/depth.png (depth colour\n"
		"code with colour bar) and OUTDIR/report.json (\"z_nm\": bin centres).",
		NULL, 0, 2, C0_MAX_STACKS, 1 };
	struct c0_cli k;
	int rc = c0_cli_start(&k, &spec, params, NULL, 0, argc, argv);
	if (rc)
		return rc == 1 ? 0 : 2;
	struct c0_result *r = NULL;
	int st = c0_cli_open(&k);   /* refuse a bad output directory before the work */
	if (!st)
		st = c0_run_matirf_files(&k.m.c, k.paths, k.n, &r);
	return c0_cli_end(&k, "matirf", r, st, argc, argv);
}
