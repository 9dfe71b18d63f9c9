/* col0rme intensity: per-angle intensity and background on a known support. */
#include "cli/commands.h"
#include "cli/cmdkit.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/mem.h"

#include <stdlib.h>

static const char *const params[] = { "pixel_nm", "channel", "fwhm_nm", "psf_image", "emission_nm", "na", "srf", "background", "beta", "nu", "discrepancy",
				      "mu", "cg_tol", "graph_radius", "noise_variance", NULL };

/* The support mask from a file, checked against the stacks' grid. */
static int load_mask(const char *path, const struct c0_frames *f, int srf, uint8_t **mask, int *Ly, int *Lx)
{
	struct c0_tiff_info si;
	float *sm;
	if (!path)
		return c0_fail(C0_EINVAL, "--support: a support mask is required");
	int st = c0_tiff_load_f32(path, &si, &sm);
	if (st)
		return st;
	if (si.width != (int64_t)f->width * srf || si.height != (int64_t)f->height * srf)
		st = c0_fail(C0_EINVAL, "--support %s: %lldx%lld does not cover the %dx%d stack at --srf %d (expected %lldx%lld)",
			     path, (long long)si.width, (long long)si.height, f->width, f->height, srf,
			     (long long)f->width * srf, (long long)f->height * srf);
	*Ly = (int)si.height, *Lx = (int)si.width;
	if (!st && !(*mask = c0_alloc((size_t)si.width * si.height, 1)))
		st = C0_ENOMEM;
	int any = 0;
	for (int64_t i = 0; !st && i < si.width * si.height; i++)
		any |= (*mask)[i] = sm[i] > 0;
	if (!st && !any)
		st = c0_fail(C0_EINVAL, "--support %s: the support is empty", path);
	free(sm);
	return st;
}

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
	const struct c0_run_conf *c = &k.m.c;
	if (c->nnoise_variance && c->nnoise_variance != k.n)
		return c0_cli_end(&k, "intensity", NULL,
				  c0_fail(C0_EINVAL, "noise_variance: %d values for %d stacks", c->nnoise_variance, k.n), argc, argv);
	struct c0_frames f[C0_MAX_STACKS];
	struct c0_stage_confs sc;
	struct c0_result *r = NULL;
	int st = c0_pipe_begin("intensity", c, k.stacks, k.n, f, &sc, &r);
	if (st)
		return c0_cli_end(&k, "intensity", r, st, argc, argv);
	st = load_mask(support, &f[0], c->srf, &r->mask, &r->Ly, &r->Lx);
	if (!st)
		st = c0_cli_open(&k);
	if (!st)
		st = c0_step_intensity(r, &sc.intensity, &sc.support, f, c->nnoise_variance ? c->noise_variance : NULL, 0);
	c0_stacks_close(f, k.n);
	return c0_cli_end(&k, "intensity", r, st, argc, argv);
}
