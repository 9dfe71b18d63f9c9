/* The single-step commands as library calls on files: the intensity step on
 * a support mask from a TIFF, and the standard MA-TIRF path on one TIFF
 * image per angle. */
#include "app/single.h"
#include "app/result.h"
#include "app/pipeline_conf.h"
#include "app/steps.h"
#include "app/steps_intensity.h"
#include "app/steps_matirf.h"
#include "app/stacks.h"
#include "app/pipeline.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"

#include <stdlib.h>

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

static int intensity(const struct c0_run_conf *c, const struct c0_stage_confs *sc, struct c0_frames *f, int n,
		     struct c0_result *r, const void *support)
{
	(void)n;
	int st = load_mask(support, &f[0], c->srf, &r->mask, &r->Ly, &r->Lx);
	if (!st)
		st = c0_progress_stage("intensity");
	return st ? st : c0_step_intensity(r, &sc->intensity, &sc->support, f, c->nnoise_variance ? c->noise_variance : NULL, 0, NULL);
}

int c0_run_intensity_files(const struct c0_run_conf *c, const struct c0_stack *stacks, int n, const char *support,
			   struct c0_result **out)
{
	*out = NULL;
	if (c->nnoise_variance && c->nnoise_variance != n)
		return c0_fail(C0_EINVAL, "noise_variance: %d values for %d stacks", c->nnoise_variance, n);
	return c0_pipe_run("intensity", c, stacks, n, intensity, support, out);
}

int c0_run_matirf_files(const struct c0_run_conf *c, char *const *paths, int n, struct c0_result **out)
{
	*out = NULL;
	struct c0_matirf_conf mc;
	c0_run_conf_matirf(c, &mc);
	int st = c0_run_conf_matirf_check(c, &mc, n), is_file[C0_MAX_STACKS];
	float *data[C0_MAX_STACKS] = { 0 };
	struct c0_tiff_info in[C0_MAX_STACKS];
	for (int q = 0; !st && q < n; q++) {
		is_file[q] = 1;
		st = c0_tiff_load_f32(paths[q], &in[q], &data[q]);
		if (!st && in[q].pages != 1)
			st = c0_fail(C0_EINVAL, "%s: %lld planes; expected one 2D image per angle", paths[q], (long long)in[q].pages);
		if (!st && (in[q].width != in[0].width || in[q].height != in[0].height))
			st = c0_fail(C0_EINVAL, "%s: %lldx%lld pixels differs from %s", paths[q], (long long)in[q].width,
				     (long long)in[q].height, paths[0]);
	}
	struct c0_result *r = NULL;
	struct c0_matirf_raw raw;
	const double px = st ? 0 : c->pixel_nm > 0 ? c->pixel_nm : in[0].pixel_size_nm;
	if (!st)
		st = c0_result_new("matirf", n, (const char *const *)paths, is_file, &r);
	if (!st)
		c0_warn_assumed_optics(r, c);
	struct c0_progress_sink ps;
	c0_progress_attach(&ps, c->progress, c->progress_user);
	if (!st && !(st = c0_progress_stage("matirf")) && !(st = c0_run_conf_matirf_raw(c, px, &mc, &raw)))
		st = c0_step_matirf_raw(r, &raw, &mc, (const float *const *)data, (int)in[0].height, (int)in[0].width, px);
	st = c0_progress_detach(&ps, st);
	for (int q = 0; q < n; q++)
		free(data[q]);
	if (st)
		c0_result_free(r);
	else
		*out = r;
	return st;
}
