/* col0rme support: COL0RME support estimation from one or more stacks. */
#include "cli/commands.h"
#include "cli/confopts.h"
#include "stages/pipeline.h"
#include "core/err.h"

#include <stdlib.h>

static const char *const params[] = { "pixel_nm", "channel", "fwhm_nm", "emission_nm", "na", "srf", "penalty", "lambda",
				      "iterations", "tol", "reweightings", "lag", NULL };
enum { NPARAMS = sizeof params / sizeof *params - 1 };

int cmd_support(int argc, char **argv)
{
	struct c0_conf_cli m;
	c0_conf_cli_init(&m);
	const char *outdir = NULL;
	int force = 0, verbose = 0;
	struct c0_opt opts[NPARAMS + 3];
	int no = c0_conf_cli_table(&m, params, &outdir, &force, &verbose, opts);
	const struct c0_cmd_spec spec = { "support", "--fwhm NM [options] -o OUTDIR STACK...",
		"Estimate the emitters' support on the fine grid from each stack's spatial covariance\n"
		"(COL0RME); with several stacks the support is the union. Writes OUTDIR/support.tif\n"
		"(uint8 0/1; fine pixel (i, j) covers [i p/r, (i+1) p/r) nm from the top-left corner),\n"
		"OUTDIR/rx.tif (float32 emitter variance, one plane per stack) and OUTDIR/report.json.",
		opts, no, 1, C0_MAX_STACKS };
	char *args[C0_MAX_STACKS], **paths = NULL;
	int na, ns = 0, rc = c0_opts_parse(&spec, argc, argv, &na, args);
	if (rc)
		return rc == 1 ? 0 : 2;
	int st = c0_conf_cli_finish(&m);
	if (!st)   /* a multi-channel file: one stack per channel */
		st = c0_frames_expand(args, na, m.channel, C0_MAX_STACKS, &paths, &ns);
	struct c0_stack stacks[C0_MAX_STACKS] = { 0 };
	struct c0_frames f[C0_MAX_STACKS];
	int is_file[C0_MAX_STACKS];
	for (int i = 0; i < ns; i++)
		stacks[i].path = paths[i], is_file[i] = 1;
	struct c0_outdir out;
	struct c0_result *r = NULL;
	struct c0_stage_confs sc;
	double pixel_nm;
	if (!st)
		st = c0_stacks_open(stacks, ns, f);
	if (st) {
		c0_frames_expand_free(paths, ns);
		return c0_cli_error("support");
	}
	st = c0_stacks_pixel(&m.c, f, ns, &pixel_nm);
	if (!st)
		st = c0_run_conf_stages(&m.c, pixel_nm, &sc);
	if (!st)   /* every stack, before the first one's work */
		st = c0_stacks_check(&sc.support, f, ns);
	if (!st)
		st = c0_result_new("support", ns, (const char *const *)paths, is_file, &r);
	if (!st)
		st = c0_outdir_check_inputs(outdir, (const char *const *)paths, ns);
	if (!st && !(st = c0_outdir_open(&out, outdir, force))) {
		c0_result_set_argv(r, argc, argv);
		r->nsup = ns;
		for (int i = 0; i < ns; i++)
			r->sup[i] = i;
		st = c0_step_support(r, &sc.support, f);
		if (!st)
			st = c0_result_write_to(r, &out);
		st = c0_outdir_finish(&out, st);
	}
	c0_stacks_close(f, ns);
	c0_result_free(r);
	c0_frames_expand_free(paths, ns);
	return st ? c0_cli_error("support") : 0;
}
