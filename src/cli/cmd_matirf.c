/* col0rme matirf: axial reconstruction from one image per TIRF angle. */
#include "cli/commands.h"
#include "cli/common.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/mem.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cmd_matirf(int argc, char **argv)
{
	struct c0_matirf_cli m = { .c = C0_MATIRF_DEFAULTS };
	const char *outdir = NULL;
	double pixel_nm = 0;
	int force = 0, verbose = 0;
	const struct c0_opt own[] = {
		{ "output", 'o', C0_OPT_STRING, &outdir, "DIR", "output directory (created; must be empty unless --force)", NULL, 0, NULL },
		{ "pixel-size", 0, C0_OPT_DOUBLE, &pixel_nm, "NM", "pixel size of the images (calibration of the outputs)", "from the TIFF calibration", 0, NULL },
		{ "force", 0, C0_OPT_FLAG, &force, NULL, "write into a non-empty output directory", NULL, 0, NULL },
		{ "verbose", 0, C0_OPT_FLAG, &verbose, NULL, "show progress even when not on a terminal", NULL, 0, NULL },
	};
	enum { NOWN = sizeof own / sizeof *own };   /* its own rows, then the MA-TIRF ones */
	struct c0_opt opts[NOWN + C0_MATIRF_CLI_OPTS];
	memcpy(opts, own, sizeof own);
	c0_matirf_cli_opts(&m, opts + NOWN);
	const struct c0_cmd_spec spec = { "matirf", "--angles DEG,... [options] -o OUTDIR IMAGE...",
		"Multi-angle TIRF axial reconstruction from one 2D image per angle (e.g. the\n"
		"intensity_qNN.tif of 'col0rme intensity', or background-corrected means). Writes\n"
		"OUTDIR/volume.tif (float32, depth bins x H x W, z spacing = bin width),\n"
		"OUTDIR/depth.tif (intensity-weighted mean depth, nm), OUTDIR/depth.png (depth colour\n"
		"code with colour bar) and OUTDIR/report.json (\"z_nm\": bin centres).",
		opts, C0_NOPTS(opts), 2, 64, 1 };
	char *imgs[64];
	int ni, rc = c0_opts_parse(&spec, argc, argv, &ni, imgs);
	if (rc)
		return rc == 1 ? 0 : 2;
	int st = c0_matirf_cli_finish(&m, ni);
	if (!st)
		st = c0_check_inputs(imgs, ni, outdir);
	float *data[64] = { 0 };
	struct c0_tiff_info in[64];
	for (int q = 0; !st && q < ni; q++) {
		st = c0_tiff_load_f32(imgs[q], &in[q], &data[q]);
		if (!st && in[q].pages != 1)
			st = c0_fail(C0_EINVAL, "%s: %lld planes; expected one 2D image per angle", imgs[q], (long long)in[q].pages);
		if (!st && (in[q].width != in[0].width || in[q].height != in[0].height))
			st = c0_fail(C0_EINVAL, "%s: %lldx%lld pixels differs from %s", imgs[q], (long long)in[q].width,
				     (long long)in[q].height, imgs[0]);
	}
	if (!st && !(pixel_nm > 0))
		pixel_nm = in[0].pixel_size_nm;
	struct c0_outdir out;
	if (!st)
		st = c0_outdir_open(&out, outdir, force);
	if (st) {
		for (int q = 0; q < ni; q++)
			free(data[q]);
		return c0_cli_error("matirf");
	}
	cJSON *rep = c0_report_new("matirf", argc, argv);
	struct c0_matirf_result res;
	st = c0_run_matirf(&out, &m, (const float *const *)data, NULL, (int)in[0].height, (int)in[0].width, pixel_nm, "",
			   "matirf", &res, rep);
	if (!st)
		st = c0_report_write(rep, c0_outdir_file(&out, "report.json"));
	c0_matirf_result_free(&res);
	cJSON_Delete(rep);
	for (int q = 0; q < ni; q++)
		free(data[q]);
	if (st) {
		c0_outdir_rollback(&out);
		return c0_cli_error("matirf");
	}
	return 0;
}
