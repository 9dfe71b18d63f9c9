/* col0rme intensity: per-angle intensity and background on a known support. */
#include "cli/commands.h"
#include "cli/opts.h"
#include "cli/common.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/mem.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cmd_intensity(int argc, char **argv)
{
	struct c0_intensity_conf ic = C0_INTENSITY_DEFAULTS;
	const char *outdir = NULL, *support = NULL, *bg = "smooth";
	int force = 0, verbose = 0, ns2 = 0;
	double s2[64] = { 0 };
	const struct c0_opt opts[] = {
		{ "output", 'o', C0_OPT_STRING, &outdir, "DIR", "output directory (created; must be empty unless --force)", NULL, 0, NULL },
		{ "support", 0, C0_OPT_STRING, &support, "TIF", "support mask from 'col0rme support' (required)", "none", 0, NULL },
		{ "pixel-size", 0, C0_OPT_DOUBLE, &ic.pixel_nm, "NM", "camera pixel size in the sample", "from the TIFF calibration", 0, NULL },
		{ "fwhm", 0, C0_OPT_DOUBLE, &ic.fwhm_nm, "NM", "PSF full width at half maximum (required)", "none", 0, NULL },
		{ "srf", 0, C0_OPT_INT, &ic.srf, "R", "super-resolution factor of the support", NULL, 0, NULL },
		{ "background", 0, C0_OPT_STRING, &bg, "MODE", "none, constant or smooth", NULL, 0, NULL },
		{ "beta", 0, C0_OPT_DOUBLE, &ic.beta, "B", "background smoothness weight", NULL, 0, NULL },
		{ "nu", 0, C0_OPT_DOUBLE, &ic.nu, "F", "discrepancy factor: residual^2 = nu^2 HW sigma2 / T (0: sqrt(T))", NULL, 0, NULL },
		{ "mu", 0, C0_OPT_DOUBLE, &ic.mu, "M", "fixed smoothness weight instead of the discrepancy principle", "0 (discrepancy)", 0, NULL },
		{ "tol", 0, C0_OPT_DOUBLE, &ic.tol, "F", "CG stopping tolerance (relative residual)", NULL, 0, NULL },
		{ "graph-radius", 0, C0_OPT_DOUBLE, &ic.graph_radius, "PX", "smoothness couples support pixels up to this far apart (fine pixels)", NULL, 0, NULL },
		{ "noise-variance", 0, C0_OPT_DOUBLES, s2, "V,...", "per-stack noise variance (camera units^2)", "estimated on the support", 64, &ns2 },
		{ "force", 0, C0_OPT_FLAG, &force, NULL, "write into a non-empty output directory", NULL, 0, NULL },
		{ "verbose", 0, C0_OPT_FLAG, &verbose, NULL, "show progress even when not on a terminal", NULL, 0, NULL },
	};
	const struct c0_cmd_spec spec = { "intensity", "--support TIF --fwhm NM [options] -o OUTDIR STACK...",
		"Estimate each stack's mean intensity on the support (fine grid) and its smooth background\n"
		"(coarse grid), with the smoothness weight set by the discrepancy principle. Writes\n"
		"OUTDIR/intensity_qNN.tif, OUTDIR/background_qNN.tif and OUTDIR/report.json.",
		opts, C0_NOPTS(opts), 1, 64, 1 };
	char **stacks = malloc(sizeof(char *) * (size_t)argc);
	int ns, rc = c0_opts_parse(&spec, argc, argv, &ns, stacks);
	if (rc) {
		free(stacks);
		return rc == 1 ? 0 : 2;
	}
	ic.background = !strcmp(bg, "none") ? C0_BG_NONE : !strcmp(bg, "constant") ? C0_BG_CONSTANT : C0_BG_SMOOTH;
	int st = strcmp(bg, "none") && strcmp(bg, "constant") && strcmp(bg, "smooth")
		 ? c0_fail(C0_EINVAL, "--background %s: expected none, constant or smooth", bg) : C0_OK;
	if (!st && ns2 && ns2 != ns)
		st = c0_fail(C0_EINVAL, "--noise-variance: %d values for %d stacks", ns2, ns);
	if (!st && !support)
		st = c0_fail(C0_EINVAL, "--support: a support mask is required");
	if (!st)
		st = c0_check_inputs(stacks, ns, outdir);
	struct c0_tiff_info si, s0;
	float *sm = NULL;
	uint8_t *mask = NULL;
	if (!st)
		st = c0_tiff_load_f32(support, &si, &sm);
	if (!st) {
		struct c0_tiff_reader *r;
		st = c0_tiff_open(stacks[0], &r);
		if (!st) {
			s0 = *c0_tiff_get_info(r);
			c0_tiff_close(r);
			if (!(ic.pixel_nm > 0))
				ic.pixel_nm = s0.pixel_size_nm;
			if (si.width != s0.width * ic.srf || si.height != s0.height * ic.srf)
				st = c0_fail(C0_EINVAL, "--support %s: %lldx%lld does not cover the %lldx%lld stack at --srf %d (expected %lldx%lld)",
					     support, (long long)si.width, (long long)si.height, (long long)s0.width,
					     (long long)s0.height, ic.srf, (long long)s0.width * ic.srf, (long long)s0.height * ic.srf);
		}
	}
	if (!st) {
		mask = c0_alloc((size_t)si.width * si.height, 1);
		int any = 0;
		for (int64_t i = 0; mask && i < si.width * si.height; i++)
			any |= mask[i] = sm[i] > 0;
		st = !mask ? C0_ENOMEM : !any ? c0_fail(C0_EINVAL, "--support %s: the support is empty", support) : C0_OK;
	}
	free(sm);
	struct c0_support_conf sc = C0_SUPPORT_DEFAULTS;
	sc.pixel_nm = ic.pixel_nm, sc.fwhm_nm = ic.fwhm_nm, sc.srf = ic.srf;
	if (!st)
		st = c0_intensity_check(&ic);
	struct c0_outdir out;
	if (!st)
		st = c0_outdir_open(&out, outdir, force);
	if (st) {
		free(stacks), free(mask);
		return c0_cli_error("intensity");
	}
	struct c0_intensity_result *res = c0_alloc((size_t)ns, sizeof *res);
	cJSON *rep = c0_report_new("intensity", argc, argv);
	st = res ? c0_run_intensity(&out, &ic, &sc, stacks, ns, mask, ns2 ? s2 : NULL, NULL, res, NULL, rep) : C0_ENOMEM;
	if (!st)
		st = c0_report_write(rep, c0_outdir_file(&out, "report.json"));
	for (int i = 0; res && i < ns; i++)
		c0_intensity_result_free(&res[i]);
	free(res), free(mask), free(stacks);
	cJSON_Delete(rep);
	if (st) {
		c0_outdir_rollback(&out);
		return c0_cli_error("intensity");
	}
	return 0;
}
