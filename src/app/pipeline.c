/* 3D-COL0RME as one call: support from the support stacks, intensity and
 * background of every stack on the union of their masks, and with angles
 * the MA-TIRF volume from the (pooled) intensities, plus the standard
 * MA-TIRF baseline from the background-corrected means when asked. */
#include "app/pipeline.h"
#include "app/params.h"
#include "app/result.h"
#include "app/pipeline_conf.h"
#include "app/steps.h"
#include "app/steps_intensity.h"
#include "app/steps_matirf.h"
#include "app/stacks.h"
#include "app/render.h"
#include "app/report_json.h"
#include "core/progress.h"
#include "stages/depthfit.h"
#include "stages/depthpool.h"
#include "core/err.h"
#include "core/comm.h"
#include "core/mem.h"
#include "core/progress.h"

#include <math.h>
#include <stdlib.h>

/* The support stacks: 1-based numbers; or pooled, every angle's stack (one
 * sample: each holds every emitter's fluctuation, more frames hold more of
 * it, docs/defaults.md#support_pool); or alone, the smallest angle (the
 * deepest penetration sees every emitter); or the first stack in 2D mode. */
static int support_stacks(const struct c0_run_conf *c, const int *only, int n, struct c0_result *r)
{
	const int na = c->nangles - (c->bleach == C0_BLEACHING_REPEAT);   /* the repeat only measures the fade */
	if (!c->nsupport_stacks && c->support_pool && na > 1) {
		for (int i = 0; i < na; i++)
			r->sup[i] = i;
		r->nsup = na;
		return C0_OK;
	}
	if (!c->nsupport_stacks) {
		/* the support-only stacks (at or below the critical angle) and the smallest TIRF angle */
		int best = -1, k = 0;
		for (int i = 0; i < na; i++)
			if (only[i])
				r->sup[k++] = i;
			else if (best < 0 || c->angles[i] < c->angles[best])
				best = i;
		if (best >= 0 || !k)
			r->sup[k++] = best < 0 ? 0 : best;
		r->nsup = k;
		return C0_OK;
	}
	for (int k = 0; k < c->nsupport_stacks; k++) {
		if (c->support_stacks[k] < 1 || c->support_stacks[k] > n)
			return c0_fail(C0_EINVAL, "support_stacks: %d is not a stack number (1..%d)", c->support_stacks[k], n);
		r->sup[k] = c->support_stacks[k] - 1;
	}
	r->nsup = c->nsupport_stacks;
	return C0_OK;
}

/* The guide of the depth pooling: each support pixel's depth from its own
 * intensities summed over a (2 hg + 1)^2 window, one depth per pixel fitted
 * against the model's bin weights (no volume, no regulariser). own and
 * guide over the support's pixels pl. */
static int depth_guide(const struct c0_run_conf *ct, const struct c0_matirf_conf *m, const struct c0_pixlist *pl,
		       const float *const *own, int hg, float *guide)
{
	const int nq = ct->nangles, nz = c0_matirf_nz(m);
	float *g[C0_MAX_STACKS] = { 0 };
	double *W = c0_alloc((size_t)nq * nz, sizeof *W);
	int st = W ? c0_tirf_weights(&m->tirf, nq, ct->angles, ct->ngains ? ct->gains : NULL, nz, m->z0_nm, m->dz_nm, W)
		   : C0_ENOMEM;
	for (int i = 0; !st && hg > 0 && i < nq; i++)
		st = (g[i] = c0_alloc(pl->M ? pl->M : 1, sizeof(float))) ? c0_pool_window_at(own[i], pl, hg, g[i]) : C0_ENOMEM;
	if (!st)
		c0_depth_single(W, nq, nz, m->z0_nm, m->dz_nm, hg > 0 ? (const float *const *)g : own, NULL, pl->M, guide);
	for (int i = 0; i < nq; i++)
		free(g[i]);
	free(W);
	return st;
}

/* The pooled intensities' noise variances (*var, nq x pl->M; stages/depthfit.h)
 * from the intensity step's noise draws pooled as the intensities were
 * (guide and normals), and its model ns; *var stays NULL without a draw for
 * every angle, or where the residuals are mostly misfit. */
static int pool_noise(const struct c0_result *r, const struct c0_run_conf *ct, const int *tirf,
		      const struct c0_stage_confs *s, const struct c0_pixlist *pl, int h, const float *guide,
		      const float *nrm, const float *const *pooled, float **var, struct c0_depth_noise *ns)
{
	const int nq = ct->nangles;
	const size_t M = pl->M ? pl->M : 1;
	for (int i = 0; i < nq; i++)
		if (!r->xnoise[tirf[i]])
			return C0_OK;
	float *d[C0_MAX_STACKS] = { 0 }, *dp[C0_MAX_STACKS] = { 0 };
	int st = C0_OK;
	for (int i = 0; i < nq && !st; i++) {
		const float g = (float)(1 / r->bleach_factor[tirf[i]]);
		if (!(d[i] = c0_alloc(M, sizeof(float))) || !(dp[i] = c0_alloc(M, sizeof(float))))
			st = C0_ENOMEM;
		for (size_t k = 0; !st && k < pl->M; k++)
			d[i][k] = r->xnoise[tirf[i]][k] * g;
	}
	if (!st)
		st = c0_pool_guided_at((const float *const *)d, nq, pl, guide, s->pool_range_nm, nrm, C0_DEPTH_POOL_WIDTH_PX, h,
				       dp);
	if (!st && !(*var = c0_alloc((size_t)nq * M, sizeof **var)))
		st = C0_ENOMEM;
	const struct c0_matirf_conf *m = &s->matirf;
	if (!st)
		st = c0_depth_noise(&m->tirf, nq, ct->angles, ct->ngains ? ct->gains : NULL, m->z0_nm, c0_matirf_nz(m) * m->dz_nm,
				    pooled, (const float *const *)dp, pl->M, *var, ns);
	for (int i = 0; i < nq; i++)
		free(d[i]), free(dp[i]);
	if (st || ns->resid_ratio > C0_DEPTH_NOISE_RATIO)   /* mostly misfit: the volume's equal-weight readout */
		free(*var), *var = NULL;
	return st;
}

/* MA-TIRF's input: the intensities over their bleaching factors, each
 * pooled over a window of about pool_nm (odd, in fine pixels) on the
 * support, over the pixels whose guide depth is within pool_range_nm of the
 * centre's and that lie on a strip along the centre's structure (range 0:
 * the whole square window). All of it on the support's pixels alone (own, pooled:
 * nq arrays over pl), the fine grid being a thousand times larger. */
static int pool_input(struct c0_result *r, const struct c0_run_conf *ct, const int *tirf, const struct c0_stage_confs *s,
		      const struct c0_pixlist *pl, int h, int hg, float *const *own, float *const *pooled, float **var,
		      struct c0_depth_noise *ns)
{
	const int nq = ct->nangles;
	for (int i = 0; i < nq; i++) {
		const float g = (float)(1 / r->bleach_factor[tirf[i]]);
		for (size_t k = 0; k < pl->M; k++)
			own[i][k] = c0_result_x_at(r, tirf[i], k) * g;
	}
	if (h <= 0)
		return C0_OK;
	int st = C0_OK;
	if (!hg) {
		for (int i = 0; !st && i < nq; i++)
			st = c0_pool_window_at(own[i], pl, h, pooled[i]);
		return st;
	}
	float *guide = c0_alloc(pl->M ? pl->M : 1, sizeof *guide), *nrm = c0_alloc(pl->M ? 2 * pl->M : 2, sizeof *nrm);
	st = guide && nrm ? depth_guide(ct, &s->matirf, pl, (const float *const *)own, hg, guide) : C0_ENOMEM;
	if (!st) {
		c0_pixlist_normals(pl, C0_DEPTH_NORMAL_PX, nrm);
		st = c0_pool_guided_at((const float *const *)own, nq, pl, guide, s->pool_range_nm, nrm,
				       C0_DEPTH_POOL_WIDTH_PX, h, pooled);
	}
	if (!st && var)
		st = pool_noise(r, ct, tirf, s, pl, h, guide, nrm, (const float *const *)pooled, var, ns);
	free(guide), free(nrm);
	return st;
}

static int volume(struct c0_result *r, const struct c0_run_conf *ct, const int *tirf, const struct c0_stage_confs *s)
{
	const int nq = ct->nangles, Ly = r->Ly, Lx = r->Lx;
	const size_t Nc = r->ires[0].Ny * (size_t)r->ires[0].Nx, M = r->pl.M ? r->pl.M : 1;
	float *own[C0_MAX_STACKS] = { 0 }, *pooled[C0_MAX_STACKS] = { 0 }, *img[C0_MAX_STACKS] = { 0 }, *base[C0_MAX_STACKS] = { 0 };
	const double fine = c0_grid_fine_nm(&s->support.grid);
	const int h = (int)lround((s->pool_nm / fine - 1) / 2), guided = h > 0 && s->pool_range_nm > 0;
	c0_mem_stage("matirf");   /* the pooled intensities are its input */
	const int hg = guided ? (int)lround((C0_DEPTH_GUIDE_FWHM * s->support.grid.fwhm_nm / fine - 1) / 2) : 0;
	const struct c0_pixlist *pl = &r->pl;
	int st = C0_OK;
	for (int i = 0; !st && i < nq; i++) {
		if (!(own[i] = c0_alloc(M, sizeof(float))) || (h > 0 && !(pooled[i] = c0_alloc(M, sizeof(float)))) ||
		    (ct->baseline && !(base[i] = c0_alloc(Nc, sizeof(float)))))
			st = C0_ENOMEM;
		for (size_t p = 0; !st && ct->baseline && p < Nc; p++)
			base[i][p] = r->corrected[tirf[i]][p] * (float)(1 / r->bleach_factor[tirf[i]]);
	}
	float *var = NULL;   /* with the noise draws and the guided pool: the angles' weights in the depth fit */
	struct c0_depth_noise ns = { 0 };
	if (!st)
		st = pool_input(r, ct, tirf, s, pl, h, guided ? hg : 0, own, pooled, &var, &ns);
	/* the solve reads whole images, 0 off the support: untouched, their
	 * pages stay out of memory (a few in ten at 2048 x 2048 camera pixels) */
	for (int i = 0; !st && i < nq; i++) {
		if (!(img[i] = c0_alloc((size_t)Ly * Lx, sizeof(float))))
			st = C0_ENOMEM;
		for (size_t k = 0; !st && k < pl->M; k++)
			img[i][pl->pix[k]] = (h > 0 ? pooled : own)[i][k];
	}
	const struct c0_pooled pin = { pl, (const float *const *)own, (const float *const *)pooled, var };
	struct c0_angles a;
	c0_run_conf_angles(ct, &a);
	if (!st)
		st = c0_step_matirf(r, &a, &s->matirf, (const float *const *)img, h > 0 ? &pin : NULL, Ly, Lx, fine, 0);
	if (!st)
		st = c0_report_bleach_depth(r, &a, tirf, &s->matirf.tirf);
	for (int i = 0; i < nq; i++)
		free(img[i]), img[i] = NULL;
	if (!st)
		c0_report_pool(cJSON_GetObjectItem(r->rep, "matirf"), h > 0 ? 2 * h + 1 : 0, guided ? s->pool_range_nm : 0,
			       guided ? C0_DEPTH_POOL_WIDTH_PX : 0, guided ? 2 * hg + 1 : 0);
	if (!st)
		c0_report_depth_noise(cJSON_GetObjectItem(r->rep, "matirf"), ns.nq ? &ns : NULL, var != NULL, s->intensity.noise_block);
	if (!st && ct->baseline)
		st = c0_step_matirf(r, &a, &s->matirf, (const float *const *)base, NULL, r->ires[0].Ny, r->ires[0].Nx,
				    s->support.grid.pixel_nm, 1);
	for (int i = 0; i < nq; i++)
		free(own[i]), free(pooled[i]), free(base[i]);
	free(var);
	return st;
}

/* The run's checks, before any work: angles and gains against the n stacks;
 * the stacks at or below the critical angle (epi) only join the support
 * (only[q]): ct holds the TIRF stacks' angles and gains, tirf[] their
 * indices, for the MA-TIRF step. */
/* Angles below this share of the critical angle are refused as typos. */
#define C0_ANGLE_FLOOR 0.8

/* With bleach repeat the last stack repeats the first's angle. */
#define C0_REPEAT_ANGLE_TOL 0.01

static int repeat_check(const struct c0_run_conf *c, int n)
{
	if (!c->nangles)
		return c0_fail(C0_EINVAL, "bleach repeat: needs the stacks' angles (3D mode)");
	if (c->nbleach_factors)
		return c0_fail(C0_EINVAL, "bleach_factors: given with bleach repeat (choose one)");
	if (n < 3)
		return c0_fail(C0_EINVAL, "bleach repeat: needs at least 2 angles and the repeat of the first as the last stack (got %d stacks)", n);
	if (fabs(c->angles[n - 1] - c->angles[0]) > C0_REPEAT_ANGLE_TOL)
		return c0_fail(C0_EINVAL, "angles: with bleach repeat the last stack repeats the first angle (%g deg), but its angle is %g deg",
			       c->angles[0], c->angles[n - 1]);
	return C0_OK;
}

static int run_check(const struct c0_run_conf *c, const struct c0_stage_confs *s, int n, int *only, int *tirf,
		     struct c0_run_conf *ct)
{
	const int three_d = c->nangles > 0;
	int st = C0_OK, ntirf = 0;
	*ct = *c;
	if (three_d)
		st = c0_run_conf_angles_check(c, n);
	const int repeat = c->bleach == C0_BLEACHING_REPEAT;
	if (!st && repeat)
		st = repeat_check(c, n);
	const double crit = c0_tirf_critical_deg(&s->matirf.tirf);
	for (int q = 0; !st && three_d && q < n - repeat; q++) {
		only[q] = c->angles[q] <= crit;
		if (c->angles[q] != 0 && c->angles[q] < C0_ANGLE_FLOOR * crit)   /* 0: epi, at normal incidence */
			st = c0_fail(C0_EINVAL, "angles: %g deg (stack %d) is far below the critical angle %.2f deg of n_glass %g "
				     "and n_sample %g (under %g of it): a typo? An epifluorescence stack is given as 0",
				     c->angles[q], q + 1, crit, c->n_glass, c->n_sample, C0_ANGLE_FLOOR);
		if (!only[q])
			ct->angles[ntirf] = c->angles[q], ct->gains[ntirf] = c->gains[q], tirf[ntirf++] = q;
	}
	ct->nangles = ntirf, ct->ngains = c->ngains ? ntirf : 0;
	if (!st && three_d && ntirf < 2)
		st = c0_fail(C0_EINVAL, "angles: MA-TIRF needs at least 2 angles above the critical angle %.2f deg (got %d; stacks below it only join the support)",
			     crit, ntirf);
	if (!st && three_d)
		st = c0_run_conf_matirf_check(ct, &s->matirf, ntirf);
	if (!st && three_d)   /* the acquisition options, before any work */
		st = c0_bleach_check(&s->bleach, n);
	if (!st && c->nnoise_variance)
		st = c0_fail(C0_EINVAL, "noise_variance: not used by the whole method (the support step estimates it)");
	return st;
}

/* After the support: each stack's intensity, the render, the bleaching and
 * the volume (rank 0 alone). */
static int run_rest(const struct c0_run_conf *c, const struct c0_run_conf *ct, const struct c0_stage_confs *s,
		    const int *tirf, struct c0_frames *f, struct c0_result *r)
{
	const int three_d = c->nangles > 0;
	int any = 0, st = C0_OK;
	for (size_t i = 0; i < (size_t)r->Ly * r->Lx; i++)
		any |= r->mask[i];
	if (!any)
		st = c0_fail(C0_EINVAL, "the support is empty: no emitter found (try a smaller lambda)");
	int share[C0_MAX_STACKS] = { 0 };   /* the MA-TIRF stacks share one intensity mu */
	for (int i = 0; three_d && i < ct->nangles; i++)
		share[tirf[i]] = 1;
	if (three_d && c->bleach == C0_BLEACHING_REPEAT)
		share[r->n - 1] = 1;   /* the repeat's total is compared with the first's */
	if (!st && !(st = c0_progress_stage("intensity")))
		st = c0_step_intensity(r, &s->intensity, &s->support, f, NULL, c->baseline && three_d, three_d ? share : NULL);
	if (!st && !(st = c0_progress_stage("render")))
		st = c0_step_render(r);
	for (int q = 0; q < r->n; q++)
		r->bleach_factor[q] = 1;
	r->bleach_k_sd = NAN;
	if (!st && three_d && !(st = c0_progress_stage("bleaching")))
		st = c0_step_bleach(r, &s->bleach, f);
	if (!st && three_d && !(st = c0_progress_stage("matirf")))
		st = volume(r, ct, tirf, s);
	return st;
}

void c0_warn_assumed_optics(struct c0_result *r, const struct c0_run_conf *c)
{
	const int wl = c0_param_assumed(c, "wavelength_nm"), ns = c0_param_assumed(c, "n_sample");
	const double cell = 1.37, crit = asin(c->n_sample / c->n_glass) * 180 / acos(-1.0),
		     crit_cell = asin(cell / c->n_glass) * 180 / acos(-1.0);
	if (wl && ns)
		c0_result_warn(r, "wavelength_nm %g and n_sample %g (water) assumed, the defaults: every penetration depth "
			       "scales with the excitation wavelength (561 or 640 nm changes them all), and a cell's index "
			       "(about 1.36-1.38) moves the critical angle from %.1f to about %.1f deg; give both",
			       c->wavelength_nm, c->n_sample, crit, crit_cell);
	else if (wl)
		c0_result_warn(r, "wavelength_nm %g assumed, the default: every penetration depth scales with the excitation "
			       "wavelength (561 or 640 nm changes them all); give the laser's", c->wavelength_nm);
	else if (ns)
		c0_result_warn(r, "n_sample %g (water) assumed, the default: a cell's index (about 1.36-1.38) moves the critical "
			       "angle from %.1f to about %.1f deg and every penetration depth; give the sample's",
			       c->n_sample, crit, crit_cell);
}

static int run(const struct c0_run_conf *c, const struct c0_stage_confs *sc, struct c0_frames *f, int n,
	       struct c0_result *r, const void *arg)
{
	(void)arg;
	struct c0_stage_confs s = *sc;
	int only[C0_MAX_STACKS] = { 0 }, tirf[C0_MAX_STACKS];
	struct c0_run_conf ct;
	int st = run_check(c, &s, n, only, tirf, &ct);
	if (!st && c->nangles)
		c0_warn_assumed_optics(r, c);
	const double crit = c0_tirf_critical_deg(&s.matirf.tirf);
	for (int q = 0; !st && q < n; q++)
		if (c->nangles && only[q])
			c0_result_warn(r, "stack %d (%s) at %g deg is at or below the critical angle %.2f deg: no evanescent "
				       "field, so it joins the support only and is left out of the MA-TIRF fit",
				       q + 1, r->names[q], c->angles[q], crit);
	if (!st)
		st = support_stacks(c, only, n, r);
	r->pixel_nm = s.support.grid.pixel_nm, r->srf = s.support.grid.srf;
	/* the bleaching's sums over a window that follows the drift (app/steps.c)
	 * need each frame's row and column sums, noted from the drift's pass on */
	for (int q = 0; !st && c->drift && c->nangles > 0 && s.bleach.mode == C0_BLEACH_ESTIMATE && q < n; q++)
		st = c0_frames_keep_profiles(&f[q]);
	if (!st && c->drift && !(st = c0_progress_stage("drift")))
		st = c0_step_drift(r, &s.drift, c->nangles > 0 ? &s.bleach : NULL, f, n);
	if (!st && !(st = c0_progress_stage("support")))
		st = c0_step_support(r, &s.support, f, c->support_pool);
	if (!st && r->fwhm_nm > 0 && r->fwhm_nm != s.support.grid.fwhm_nm)
		c0_stage_confs_width(&s, r->fwhm_nm);   /* the data's width (fwhm_rule data, app/steps.c) */
	if (c0_comm_rank() != 0)
		return st;      /* MPI: the other ranks share the support step; rank 0 has the result */
	if (!st)
		st = run_rest(c, &ct, &s, tirf, f, r);
	if (!st)
		c0_report_run_params(r->rep, c, &s, r, only, c->nangles > 0);
	return st;
}

int c0_run(const struct c0_run_conf *c, const struct c0_stack *stacks, int n, struct c0_result **out)
{
	return c0_pipe_run("run", c, stacks, n, run, NULL, out);
}
