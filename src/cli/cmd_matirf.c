/* col0rme matirf: axial reconstruction from one image per TIRF angle. */
#include "cli/commands.h"
#include "cli/cmdkit.h"
#include "io/tiff.h"
#include "core/err.h"

#include <stdlib.h>

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
	const int ni = k.n;
	struct c0_matirf_conf mc;
	c0_run_conf_matirf(&k.m.c, &mc);
	int st = c0_run_conf_matirf_check(&k.m.c, &mc, ni), is_file[C0_MAX_STACKS];
	float *data[C0_MAX_STACKS] = { 0 };
	struct c0_tiff_info in[C0_MAX_STACKS];
	for (int q = 0; !st && q < ni; q++) {
		is_file[q] = 1;
		st = c0_tiff_load_f32(k.paths[q], &in[q], &data[q]);
		if (!st && in[q].pages != 1)
			st = c0_fail(C0_EINVAL, "%s: %lld planes; expected one 2D image per angle", k.paths[q], (long long)in[q].pages);
		if (!st && (in[q].width != in[0].width || in[q].height != in[0].height))
			st = c0_fail(C0_EINVAL, "%s: %lldx%lld pixels differs from %s", k.paths[q], (long long)in[q].width,
				     (long long)in[q].height, k.paths[0]);
	}
	struct c0_result *r = NULL;
	if (!st)
		st = c0_result_new("matirf", ni, (const char *const *)k.paths, is_file, &r);
	if (!st)
		st = c0_cli_open(&k);
	if (!st)
		st = c0_step_matirf_raw(r, &k.m.c, &mc, (const float *const *)data, (int)in[0].height, (int)in[0].width,
					k.m.c.pixel_nm > 0 ? k.m.c.pixel_nm : in[0].pixel_size_nm);
	for (int q = 0; q < ni; q++)
		free(data[q]);
	return c0_cli_end(&k, "matirf", r, st, argc, argv);
}
