/* col0rme intensity: per-angle intensity and background on a known support. */
#include "cli/commands.h"
#include "cli/confopts.h"
#include "stages/pipeline.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/mem.h"

#include <stdlib.h>

static const char *const params[] = { "pixel_nm", "channel", "fwhm_nm", "emission_nm", "na", "srf", "background", "beta", "nu",
				      "mu", "cg_tol", "graph_radius", "noise_variance", NULL };
enum { NPARAMS = sizeof params / sizeof *params - 1 };

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
	struct c0_conf_cli m;
	c0_conf_cli_init(&m);
	const char *outdir = NULL, *support = NULL;
	int force = 0, verbose = 0;
	struct c0_opt opts[NPARAMS + 4];
	int no = c0_conf_cli_table(&m, params, &outdir, &force, &verbose, opts);
	opts[no++] = (struct c0_opt){ "support", 0, C0_OPT_STRING, &support, "TIF", "support mask from 'col0rme support' (required)", "none", 0, NULL };
	const struct c0_cmd_spec spec = { "intensity", "--support TIF --fwhm NM [options] -o OUTDIR STACK...",
		"Estimate each stack's mean intensity on the support (fine grid) and its smooth background\n"
		"(coarse grid), with the smoothness weight set by the discrepancy principle. Writes\n"
		"OUTDIR/intensity_qNN.tif, OUTDIR/background_qNN.tif and OUTDIR/report.json.",
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
	if (!st && m.c.nnoise_variance && m.c.nnoise_variance != ns)
		st = c0_fail(C0_EINVAL, "noise_variance: %d values for %d stacks", m.c.nnoise_variance, ns);
	if (!st)
		st = c0_stacks_open(stacks, ns, f);
	if (st) {
		c0_frames_expand_free(paths, ns);
		return c0_cli_error("intensity");
	}
	st = c0_stacks_pixel(&m.c, f, ns, &pixel_nm);
	if (!st)
		st = c0_run_conf_stages(&m.c, pixel_nm, &sc);
	if (!st)   /* every stack, before the first one's work */
		st = c0_stacks_check(&sc.support, f, ns);
	if (!st)
		st = c0_result_new("intensity", ns, (const char *const *)paths, is_file, &r);
	if (!st)
		st = load_mask(support, &f[0], m.c.srf, &r->mask, &r->Ly, &r->Lx);
	if (!st)
		st = c0_outdir_check_inputs(outdir, (const char *const *)paths, ns);
	if (!st && !(st = c0_outdir_open(&out, outdir, force))) {
		c0_result_set_argv(r, argc, argv);
		st = c0_step_intensity(r, &sc.intensity, &sc.support, f, m.c.nnoise_variance ? m.c.noise_variance : NULL, 0);
		if (!st)
			st = c0_result_write_to(r, &out);
		st = c0_outdir_finish(&out, st);
	}
	c0_stacks_close(f, ns);
	c0_result_free(r);
	c0_frames_expand_free(paths, ns);
	return st ? c0_cli_error("intensity") : 0;
}
