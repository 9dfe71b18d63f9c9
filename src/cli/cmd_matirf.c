/* col0rme matirf: axial reconstruction from one image per TIRF angle. */
#include "cli/commands.h"
#include "cli/confopts.h"
#include "stages/pipeline.h"
#include "io/tiff.h"
#include "core/err.h"

#include <stdlib.h>

static const char *const params[] = { "pixel_nm", C0_MATIRF_PARAMS, NULL };
enum { NPARAMS = sizeof params / sizeof *params - 1 };

int cmd_matirf(int argc, char **argv)
{
	struct c0_conf_cli m;
	c0_conf_cli_init(&m);
	const char *outdir = NULL;
	int force = 0, verbose = 0;
	struct c0_opt opts[NPARAMS + 3];
	int no = c0_conf_cli_table(&m, params, &outdir, &force, &verbose, opts);
	opts[1].help = "pixel size of the images (calibration of the outputs)";
	const struct c0_cmd_spec spec = { "matirf", "--angles DEG,... [options] -o OUTDIR IMAGE...",
		"Multi-angle TIRF axial reconstruction from one 2D image per angle (e.g. the\n"
		"intensity_qNN.tif of 'col0rme intensity', or background-corrected means). Writes\n"
		"OUTDIR/volume.tif (float32, depth bins x H x W, z spacing = bin width),\n"
		"OUTDIR/depth.tif (intensity-weighted mean depth, nm), OUTDIR/depth.png (depth colour\n"
		"code with colour bar) and OUTDIR/report.json (\"z_nm\": bin centres).",
		opts, no, 2, C0_MAX_STACKS };
	char *imgs[C0_MAX_STACKS];
	int ni, rc = c0_opts_parse(&spec, argc, argv, &ni, imgs);
	if (rc)
		return rc == 1 ? 0 : 2;
	struct c0_matirf_conf mc;
	int st = c0_conf_cli_finish(&m), is_file[C0_MAX_STACKS];
	if (!st)
		c0_run_conf_matirf(&m.c, &mc), st = c0_run_conf_matirf_check(&m.c, &mc, ni);
	float *data[C0_MAX_STACKS] = { 0 };
	struct c0_tiff_info in[C0_MAX_STACKS];
	for (int q = 0; !st && q < ni; q++) {
		is_file[q] = 1;
		st = c0_tiff_load_f32(imgs[q], &in[q], &data[q]);
		if (!st && in[q].pages != 1)
			st = c0_fail(C0_EINVAL, "%s: %lld planes; expected one 2D image per angle", imgs[q], (long long)in[q].pages);
		if (!st && (in[q].width != in[0].width || in[q].height != in[0].height))
			st = c0_fail(C0_EINVAL, "%s: %lldx%lld pixels differs from %s", imgs[q], (long long)in[q].width,
				     (long long)in[q].height, imgs[0]);
	}
	struct c0_result *r = NULL;
	struct c0_outdir out;
	if (!st)
		st = c0_result_new("matirf", ni, (const char *const *)imgs, is_file, &r);
	if (!st)
		st = c0_outdir_check_inputs(outdir, (const char *const *)imgs, ni);
	if (!st && !(st = c0_outdir_open(&out, outdir, force))) {
		c0_result_set_argv(r, argc, argv);
		st = c0_step_matirf(r, &m.c, &mc, (const float *const *)data, NULL, (int)in[0].height, (int)in[0].width,
				    m.c.pixel_nm > 0 ? m.c.pixel_nm : in[0].pixel_size_nm, 0);
		if (!st)
			st = c0_result_write_to(r, &out);
		if (st)
			c0_outdir_rollback(&out);
	}
	c0_result_free(r);
	for (int q = 0; q < ni; q++)
		free(data[q]);
	return st ? c0_cli_error("matirf") : 0;
}
