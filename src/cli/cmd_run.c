/* col0rme run: the whole method (support, intensity and background per
 * stack, MA-TIRF volume) in one command: options, c0_run, the files. */
#include "cli/commands.h"
#include "cli/confopts.h"
#include "stages/pipeline.h"
#include "core/err.h"

#include <string.h>

static const char *const params[] = { "pixel_nm", "channel", "fwhm_nm", "emission_nm", "na", "srf", "support_stacks", "penalty",
				      "lambda", "nu", "graph_radius", "depth_pool_nm", "baseline", C0_MATIRF_PARAMS, NULL };
enum { NPARAMS = sizeof params / sizeof *params - 1 };

int cmd_run(int argc, char **argv)
{
	struct c0_conf_cli m;
	c0_conf_cli_init(&m);
	const char *outdir = NULL;
	int force = 0, verbose = 0;
	struct c0_opt opts[NPARAMS + 3];
	int no = c0_conf_cli_table(&m, params, &outdir, &force, &verbose, opts);
	const struct c0_cmd_spec spec = { "run", "[options] -o OUTDIR STACK1.tif [STACK2.tif ...]",
		"3D-COL0RME: the support (from the --support-angles stacks), each stack's intensity\n"
		"and background, and with --angles the MA-TIRF volume. Without --angles: 2D COL0RME.\n"
		"Writes OUTDIR/support.tif (uint8 0/1, fine grid; fine pixel (i, j) covers\n"
		"[i p/r, (i+1) p/r) nm from the top-left corner), rx.tif, intensity_qNN.tif (fine),\n"
		"background_qNN.tif (coarse), volume.tif (depth bins x fine grid), depth.tif,\n"
		"depth.png and report.json (every parameter and estimate; \"z_nm\": bin centres).",
		opts, no, 1, C0_MAX_STACKS };
	char *args[C0_MAX_STACKS], **paths = NULL;
	int na, ns = 0, rc = c0_opts_parse(&spec, argc, argv, &na, args);
	if (rc)
		return rc == 1 ? 0 : 2;
	/* refuse a bad output directory before the work, and keep it to write into */
	struct c0_outdir out;
	struct c0_result *r = NULL;
	int st = c0_conf_cli_finish(&m);
	if (!st)   /* a multi-channel file: one stack per channel */
		st = c0_frames_expand(args, na, m.channel, C0_MAX_STACKS, &paths, &ns);
	struct c0_stack stacks[C0_MAX_STACKS] = { 0 };
	for (int i = 0; i < ns; i++)
		stacks[i].path = paths[i];
	if (!st)
		st = c0_outdir_check_inputs(outdir, (const char *const *)paths, ns);
	if (!st)
		st = c0_outdir_open(&out, outdir, force);
	if (st) {
		c0_frames_expand_free(paths, ns);
		return c0_cli_error("run");
	}
	st = c0_run(&m.c, stacks, ns, &r);
	if (!st) {
		c0_result_set_argv(r, argc, argv);
		st = c0_result_write_to(r, &out);
	}
	c0_result_free(r);
	c0_frames_expand_free(paths, ns);
	if ((st = c0_outdir_finish(&out, st)))
		return c0_cli_error("run");
	return 0;
}
