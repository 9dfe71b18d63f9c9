/* col0rme run: the whole method (support, intensity and background per
 * stack, MA-TIRF volume) in one command. */
#include "cli/commands.h"
#include "cli/common.h"
#include "io/tiff.h"
#include "stages/depthpool.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/comm.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAXS 64

/* The support stacks: 1-based numbers, or the smallest angle (the deepest
 * penetration sees every emitter), or the first stack in 2D mode. */
static int support_stacks(const int *sel, int nsel, const struct c0_matirf_cli *m, int ns, int *out, int *nout)
{
	if (!nsel) {
		int best = 0;
		for (int i = 1; i < m->nangles; i++)
			if (m->angles[i] < m->angles[best])
				best = i;
		out[0] = best, *nout = 1;
		return C0_OK;
	}
	for (int k = 0; k < nsel; k++) {
		if (sel[k] < 1 || sel[k] > ns)
			return c0_fail(C0_EINVAL, "--support-angles: %d is not a stack number (1..%d)", sel[k], ns);
		out[k] = sel[k] - 1;
	}
	*nout = nsel;
	return C0_OK;
}

int cmd_run(int argc, char **argv)
{
	struct c0_support_conf sc = C0_SUPPORT_DEFAULTS;
	struct c0_intensity_conf ic = C0_INTENSITY_DEFAULTS;
	struct c0_matirf_cli m = { .c = C0_MATIRF_DEFAULTS };
	const char *outdir = NULL, *pen = "l1";
	double emission = 0, na = 0, pool_nm = -1;
	int force = 0, verbose = 0, baseline = 0, sel[MAXS], nsel = 0;
	const struct c0_opt own[] = {
		{ "output", 'o', C0_OPT_STRING, &outdir, "DIR", "output directory (created; must be empty unless --force)", NULL, 0, NULL },
		{ "pixel-size", 0, C0_OPT_DOUBLE, &sc.pixel_nm, "NM", "camera pixel size in the sample", "from the TIFF calibration", 0, NULL },
		{ "fwhm", 0, C0_OPT_DOUBLE, &sc.fwhm_nm, "NM", "PSF full width at half maximum", "0.51 emission / NA", 0, NULL },
		{ "emission", 0, C0_OPT_DOUBLE, &emission, "NM", "emission wavelength (with --na, instead of --fwhm)", "none", 0, NULL },
		{ "na", 0, C0_OPT_DOUBLE, &na, "NA", "numerical aperture of the objective (with --emission)", "none", 0, NULL },
		{ "srf", 0, C0_OPT_INT, &sc.srf, "R", "super-resolution factor: fine pixel = pixel size / R", NULL, 0, NULL },
		{ "support-angles", 0, C0_OPT_INTS, sel, "I,J", "1-based stack numbers whose supports are joined", "the smallest angle", MAXS, &nsel },
		{ "penalty", 0, C0_OPT_STRING, &pen, "l1|cel0", "support sparsity penalty", NULL, 0, NULL },
		{ "lambda", 0, C0_OPT_DOUBLE, &sc.lambda_rel, "F", "support regularisation relative to lambda_max", "1e-2 for l1, 3e-5 for cel0", 0, NULL },
		{ "tile", 0, C0_OPT_INT, &sc.tile, "PX", "support tile side in camera pixels (tiles overlap by two lags)", "256, or the image when smaller", 0, NULL },
		{ "nu", 0, C0_OPT_DOUBLE, &ic.nu, "F", "intensity discrepancy factor (0: sqrt(T))", NULL, 0, NULL },
		{ "graph-radius", 0, C0_OPT_DOUBLE, &ic.graph_radius, "PX", "intensity smoothness couples support pixels up to this far apart (fine pixels)", NULL, 0, NULL },
		{ "depth-pool", 0, C0_OPT_DOUBLE, &pool_nm, "NM", "window over which intensities are summed for each pixel's depth (0: off)", "the FWHM", 0, NULL },
		{ "baseline", 0, C0_OPT_FLAG, &baseline, NULL, "also reconstruct the standard MA-TIRF volume from the background-corrected means (baseline_*)", NULL, 0, NULL },
		{ "force", 0, C0_OPT_FLAG, &force, NULL, "write into a non-empty output directory", NULL, 0, NULL },
		{ "verbose", 0, C0_OPT_FLAG, &verbose, NULL, "show progress even when not on a terminal", NULL, 0, NULL },
	};
	enum { NOWN = sizeof own / sizeof *own };   /* its own rows, then the MA-TIRF ones */
	struct c0_opt opts[NOWN + C0_MATIRF_CLI_OPTS];
	memcpy(opts, own, sizeof own);
	c0_matirf_cli_opts(&m, opts + NOWN);
	const struct c0_cmd_spec spec = { "run", "[options] -o OUTDIR STACK1.tif [STACK2.tif ...]",
		"3D-COL0RME: the support (from the --support-angles stacks), each stack's intensity\n"
		"and background, and with --angles the MA-TIRF volume. Without --angles: 2D COL0RME.\n"
		"Writes OUTDIR/support.tif (uint8 0/1, fine grid; fine pixel (i, j) covers\n"
		"[i p/r, (i+1) p/r) nm from the top-left corner), rx.tif, intensity_qNN.tif (fine),\n"
		"background_qNN.tif (coarse), volume.tif (depth bins x fine grid), depth.tif,\n"
		"depth.png and report.json (every parameter and estimate; \"z_nm\": bin centres).",
		opts, C0_NOPTS(opts), 1, MAXS, 1 };
	char *stacks[MAXS];
	int ns, rc = c0_opts_parse(&spec, argc, argv, &ns, stacks);
	if (rc)
		return rc == 1 ? 0 : 2;
	int st = C0_OK, three_d = m.nangles > 0;
	if (!strcmp(pen, "l1") || !strcmp(pen, "cel0"))
		sc.penalty = !strcmp(pen, "l1") ? C0_PENALTY_L1 : C0_PENALTY_CEL0;
	else
		st = c0_fail(C0_EINVAL, "--penalty %s: expected l1 or cel0", pen);
	if (!st && !(sc.fwhm_nm > 0)) {
		if (emission > 0 && na > 0)
			sc.fwhm_nm = 0.51 * emission / na;
		else
			st = c0_fail(C0_EINVAL, "--fwhm: give the PSF FWHM, or --emission and --na");
	}
	if (!st && three_d)
		st = c0_matirf_cli_finish(&m, ns);
	if (pool_nm < 0)
		pool_nm = sc.fwhm_nm;
	int sup[MAXS], nsup = 0;
	if (!st)
		st = support_stacks(sel, nsel, &m, ns, sup, &nsup);
	if (!st)
		st = c0_check_inputs(stacks, ns, outdir);
	if (!st && !(sc.pixel_nm > 0)) {
		struct c0_tiff_reader *r;
		if (!(st = c0_tiff_open(stacks[0], &r))) {
			sc.pixel_nm = c0_tiff_get_info(r)->pixel_size_nm;
			c0_tiff_close(r);
			if (!(sc.pixel_nm > 0))
				st = c0_fail(C0_EINVAL, "--pixel-size: %s has no pixel calibration; give the camera pixel size in nm", stacks[0]);
		}
	}
	ic.pixel_nm = sc.pixel_nm, ic.fwhm_nm = sc.fwhm_nm, ic.srf = sc.srf;
	if (!st)
		st = c0_intensity_check(&ic);
	/* with MPI every rank takes part in the support step; rank 0 does the rest */
	const int root = c0_comm_rank() == 0;
	struct c0_outdir out;
	if (!st && root)
		st = c0_outdir_open(&out, outdir, force);
	if ((st = c0_comm_status(st)))
		return c0_cli_error("run");

	cJSON *rep = c0_report_new("run", argc, argv);
	cJSON *times = cJSON_AddObjectToObject(rep, "timings_s");
	char *sstacks[MAXS];
	for (int k = 0; k < nsup; k++)
		sstacks[k] = stacks[sup[k]];
	struct c0_support_result sres[MAXS];
	struct c0_intensity_result ires[MAXS];
	float *corr[MAXS] = { 0 }, *pooled[MAXS] = { 0 };
	struct c0_matirf_result vres = { 0 }, bres = { 0 };
	memset(sres, 0, sizeof sres), memset(ires, 0, sizeof ires);
	uint8_t *mask = NULL;
	const struct c0_support_result *known[MAXS] = { 0 };
	double t = c0_now();
	st = c0_run_support(&sc, sstacks, nsup, sres, rep);
	if (!root) {
		for (int k = 0; k < nsup; k++)
			c0_support_result_free(&sres[k]);
		cJSON_Delete(rep);
		return st ? c0_cli_error("run") : 0;
	}
	if (!st)
		st = c0_write_support(&out, &sc, sres, nsup, rep);
	const size_t L = (size_t)sres[0].Ly * sres[0].Lx;
	if (!st && !(mask = c0_alloc(L, 1)))
		st = C0_ENOMEM;
	int any = 0;
	for (size_t i = 0; !st && i < L; i++)
		for (int k = 0; k < nsup; k++)
			any |= mask[i] |= sres[k].mask[i];
	if (!st && !any)
		st = c0_fail(C0_EINVAL, "the support is empty: no emitter found (try a smaller --lambda)");
	for (int k = 0; !st && k < nsup; k++)
		known[sup[k]] = &sres[k];
	cJSON_AddNumberToObject(times, "support", c0_now() - t);
	t = c0_now();
	if (!st)
		st = c0_run_intensity(&out, &ic, &sc, stacks, ns, mask, NULL, known, ires, baseline && three_d ? corr : NULL, rep);
	cJSON_AddNumberToObject(times, "intensity", c0_now() - t);
	if (!st && three_d) {
		const float *img[MAXS];
		const int Ly = ires[0].Ly, Lx = ires[0].Lx;
		/* window of about pool_nm fine pixels, odd */
		int h = (int)lround((pool_nm / (sc.pixel_nm / sc.srf) - 1) / 2);
		t = c0_now();
		for (int q = 0; !st && q < ns; q++) {
			img[q] = ires[q].x;
			if (h <= 0)
				continue;
			pooled[q] = malloc((size_t)Ly * Lx * sizeof(float));
			st = pooled[q] ? c0_pool_window(ires[q].x, mask, Ly, Lx, h, pooled[q]) : C0_ENOMEM;
		}
		if (!st)
			st = c0_run_matirf(&out, &m, h > 0 ? (const float *const *)pooled : img, h > 0 ? img : NULL, Ly, Lx,
					   sc.pixel_nm / sc.srf, "", "matirf", &vres, rep);
		if (!st)
			cJSON_AddNumberToObject(cJSON_GetObjectItem(rep, "matirf"), "depth_pool_window_px", h > 0 ? 2 * h + 1 : 0);
		cJSON_AddNumberToObject(times, "matirf", c0_now() - t);
		if (!st && baseline) {
			t = c0_now();
			st = c0_run_matirf(&out, &m, (const float *const *)corr, NULL, ires[0].Ny, ires[0].Nx, sc.pixel_nm, "baseline_",
					   "baseline_matirf", &bres, rep);
			cJSON_AddNumberToObject(times, "baseline_matirf", c0_now() - t);
		}
	}
	if (!st) {
		cJSON *p = cJSON_AddObjectToObject(rep, "parameters");
		cJSON_AddStringToObject(p, "mode", three_d ? "3D" : "2D");
		cJSON_AddNumberToObject(p, "pixel_size_nm", sc.pixel_nm);
		cJSON_AddNumberToObject(p, "fine_pixel_nm", sc.pixel_nm / sc.srf);
		cJSON_AddNumberToObject(p, "fwhm_nm", sc.fwhm_nm);
		cJSON_AddNumberToObject(p, "srf", sc.srf);
		if (three_d)
			cJSON_AddNumberToObject(p, "depth_pool_nm", pool_nm);
		double s1[MAXS];
		for (int k = 0; k < nsup; k++)
			s1[k] = sup[k] + 1;
		c0_report_add_array(p, "support_stacks", s1, nsup);
		st = c0_report_write(rep, c0_outdir_file(&out, "report.json"));
	}
	for (int k = 0; k < nsup; k++)
		c0_support_result_free(&sres[k]);
	for (int q = 0; q < ns; q++)
		c0_intensity_result_free(&ires[q]), free(corr[q]), free(pooled[q]);
	c0_matirf_result_free(&vres), c0_matirf_result_free(&bres);
	free(mask);
	cJSON_Delete(rep);
	if (st) {
		c0_outdir_rollback(&out);
		return c0_cli_error("run");
	}
	return 0;
}
