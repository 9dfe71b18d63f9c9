/* col0rme support: COL0RME support estimation from one or more stacks. */
#include "cli/commands.h"
#include "cli/opts.h"
#include "cli/common.h"
#include "stages/support.h"
#include "io/outdir.h"
#include "io/report.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/comm.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cmd_support(int argc, char **argv)
{
	struct c0_support_conf c = C0_SUPPORT_DEFAULTS;
	const char *outdir = NULL, *pen = "l1";
	int force = 0, verbose = 0;
	const struct c0_opt opts[] = {
		{ "output", 'o', C0_OPT_STRING, &outdir, "DIR", "output directory (created; must be empty unless --force)", NULL, 0, NULL },
		{ "pixel-size", 0, C0_OPT_DOUBLE, &c.pixel_nm, "NM", "camera pixel size in the sample", "from the TIFF calibration", 0, NULL },
		{ "fwhm", 0, C0_OPT_DOUBLE, &c.fwhm_nm, "NM", "PSF full width at half maximum (required)", "none", 0, NULL },
		{ "srf", 0, C0_OPT_INT, &c.srf, "R", "super-resolution factor: fine pixel = pixel size / R", NULL, 0, NULL },
		{ "penalty", 0, C0_OPT_STRING, &pen, "l1|cel0", "sparsity penalty", NULL, 0, NULL },
		{ "lambda", 0, C0_OPT_DOUBLE, &c.lambda_rel, "F", "regularisation relative to lambda_max (the smallest that gives an empty support)", "1e-2 for l1, 3e-5 for cel0", 0, NULL },
		{ "iterations", 0, C0_OPT_INT, &c.fista.maxit, "N", "maximum FISTA iterations (per reweighting for cel0)", NULL, 0, NULL },
		{ "tol", 0, C0_OPT_DOUBLE, &c.fista.tol, "F", "stop when the relative change of the iterate falls below this", NULL, 0, NULL },
		{ "reweightings", 0, C0_OPT_INT, &c.cel0_outer, "N", "CEL0 reweighting steps", NULL, 0, NULL },
		{ "tile", 0, C0_OPT_INT, &c.tile, "PX", "tile side in camera pixels (tiles overlap by two lags)", "256, or the image when smaller", 0, NULL },
		{ "lag", 0, C0_OPT_INT, &c.lag, "PX", "covariance lag radius in pixels", "ceil(6 sigma / pixel)", 0, NULL },
		{ "force", 0, C0_OPT_FLAG, &force, NULL, "write into a non-empty output directory", NULL, 0, NULL },
		{ "verbose", 0, C0_OPT_FLAG, &verbose, NULL, "show progress even when not on a terminal", NULL, 0, NULL },
	};
	const struct c0_cmd_spec spec = { "support", "--fwhm NM [options] -o OUTDIR STACK...",
		"Estimate the emitters' support on the fine grid from each stack's spatial covariance\n"
		"(COL0RME); with several stacks the support is the union. Writes OUTDIR/support.tif\n"
		"(uint8 0/1; fine pixel (i, j) covers [i p/r, (i+1) p/r) nm from the top-left corner),\n"
		"OUTDIR/rx.tif (float32 emitter variance, one plane per stack) and OUTDIR/report.json.",
		opts, C0_NOPTS(opts), 1, -1, 1 };
	char **stacks = malloc(sizeof(char *) * (size_t)argc);
	int ns, rc = c0_opts_parse(&spec, argc, argv, &ns, stacks);
	if (rc) {
		free(stacks);
		return rc == 1 ? 0 : 2;
	}
	if (!strcmp(pen, "l1"))
		c.penalty = C0_PENALTY_L1;
	else if (!strcmp(pen, "cel0"))
		c.penalty = C0_PENALTY_CEL0;
	else {
		fprintf(stderr, "col0rme support: error: --penalty %s: expected l1 or cel0\n", pen);
		free(stacks);
		return 2;
	}
	struct c0_outdir out;
	struct c0_support_result *res = c0_alloc((size_t)ns, sizeof *res);
	cJSON *rep = c0_report_new("support", argc, argv);
	/* with MPI every rank takes part in the solve; rank 0 writes */
	const int root = c0_comm_rank() == 0;
	int st = c0_check_inputs(stacks, ns, outdir);
	if (!st && root)
		st = c0_outdir_open(&out, outdir, force);
	if ((st = c0_comm_status(st))) {
		free(stacks), free(res), cJSON_Delete(rep);
		return c0_cli_error("support");
	}
	st = c0_run_support(&c, stacks, ns, res, rep);
	if (!st && root)
		st = c0_write_support(&out, &c, res, ns, rep);
	if (!st && root)
		st = c0_report_write(rep, c0_outdir_file(&out, "report.json"));
	for (int i = 0; i < ns; i++)
		c0_support_result_free(&res[i]);
	free(res), cJSON_Delete(rep);
	free(stacks);
	if (st) {
		if (root)
			c0_outdir_rollback(&out);
		return c0_cli_error("support");
	}
	return 0;
}
