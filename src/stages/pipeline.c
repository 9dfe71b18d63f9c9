/* 3D-COL0RME as one call: support from the support stacks, intensity and
 * background of every stack on the union of their masks, and with angles
 * the MA-TIRF volume from the (pooled) intensities, plus the standard
 * MA-TIRF baseline from the background-corrected means when asked. */
#include "stages/pipeline.h"
#include "stages/depthpool.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"
#include "core/comm.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int c0_result_new(const char *command, int n, const char *const *names, const int *is_file, struct c0_result **out)
{
	*out = NULL;
	if (n < 1 || n > C0_MAX_STACKS)
		return c0_fail(C0_EINVAL, "stacks: %d given, expected 1..%d", n, C0_MAX_STACKS);
	struct c0_result *r = c0_alloc(1, sizeof *r);
	if (!r || !(r->names = c0_alloc((size_t)n, sizeof *r->names)) || !(r->rep = c0_report_new(command, 0, NULL))) {
		c0_result_free(r);
		return C0_ENOMEM;
	}
	r->n = n;
	for (int i = 0; i < n; i++) {
		snprintf(r->names[i], sizeof r->names[i], "%s", names[i]);
		r->paths[i] = is_file[i] ? r->names[i] : NULL;
	}
	r->timings = cJSON_AddObjectToObject(r->rep, "timings_s");
	*out = r;
	return C0_OK;
}

void c0_result_set_argv(struct c0_result *r, int argc, char **argv)
{
	cJSON *a = cJSON_CreateArray();
	for (int i = 0; i < argc; i++)
		cJSON_AddItemToArray(a, cJSON_CreateString(argv[i]));
	cJSON_ReplaceItemInObject(r->rep, "argv", a);
}

void c0_result_free(struct c0_result *r)
{
	if (!r)
		return;
	for (int k = 0; r->sres && k < r->nsup; k++)
		c0_support_result_free(&r->sres[k]);
	for (int q = 0; q < r->n; q++) {
		if (r->ires)
			c0_intensity_result_free(&r->ires[q]);
		if (r->corrected)
			free(r->corrected[q]);
	}
	free(r->sres), free(r->ires), free(r->corrected), free(r->mask), free(r->names), free(r->json);
	c0_matirf_result_free(&r->vol), c0_matirf_result_free(&r->base);
	cJSON_Delete(r->rep);
	free(r);
}

int c0_stacks_open(const struct c0_stack *s, int n, struct c0_frames *f)
{
	int st = C0_OK, i;
	for (i = 0; i < n && !st; i++) {
		char name[32];
		snprintf(name, sizeof name, "array %d", i + 1);
		if (s[i].path)
			st = c0_frames_open(&f[i], s[i].path);
		else
			st = c0_frames_wrap(&f[i], s[i].data, s[i].frames, s[i].height, s[i].width, s[i].pixel_nm, name);
		if (!st && s[i].pixel_nm > 0)
			f[i].pixel_nm = s[i].pixel_nm;
		if (!st && (f[i].width != f[0].width || f[i].height != f[0].height))
			st = c0_fail(C0_EINVAL, "%s: %dx%d pixels differs from %s (%dx%d)", f[i].name, f[i].width, f[i].height,
				     f[0].name, f[0].width, f[0].height);
	}
	if (st)
		c0_stacks_close(f, i);
	return st;
}

void c0_stacks_close(struct c0_frames *f, int n)
{
	for (int i = 0; i < n; i++)
		c0_frames_close(&f[i]);
}

int c0_stacks_pixel(const struct c0_run_conf *c, const struct c0_frames *f, double *pixel_nm)
{
	*pixel_nm = c->pixel_nm > 0 ? c->pixel_nm : f[0].pixel_nm;
	if (!(*pixel_nm > 0))
		return c0_fail(C0_EINVAL, "pixel_nm: %s has no pixel calibration; give the camera pixel size in nm", f[0].name);
	return C0_OK;
}

int c0_step_support(struct c0_result *r, const struct c0_support_conf *c, struct c0_frames *f)
{
	cJSON *arr = cJSON_AddArrayToObject(r->rep, "support");
	if (!(r->sres = c0_alloc((size_t)r->nsup, sizeof *r->sres)))
		return C0_ENOMEM;
	double t = c0_now();
	for (int k = 0; k < r->nsup; k++) {
		int i = r->sup[k];
		int st = c0_support_stack(c, &f[i], &r->sres[k]);
		if (st)
			return st;
		const struct c0_support_result *s = &r->sres[k];
		cJSON *o = cJSON_CreateObject();
		cJSON_AddStringToObject(o, "stack", r->names[i]);
		cJSON_AddNumberToObject(o, "frames", (double)s->frames);
		cJSON_AddNumberToObject(o, "lag_px", s->lag);
		cJSON_AddNumberToObject(o, "lags", s->nlag);
		cJSON_AddNumberToObject(o, "lambda", s->lambda);
		cJSON_AddNumberToObject(o, "lambda_max", s->lambda_max);
		cJSON_AddNumberToObject(o, "lambda_relative", s->lambda_max > 0 ? s->lambda / s->lambda_max : 0);
		cJSON_AddNumberToObject(o, "normalisation", s->norm);
		cJSON_AddNumberToObject(o, "noise_variance", s->sigma2);
		cJSON_AddNumberToObject(o, "iterations", s->iters);
		cJSON_AddBoolToObject(o, "converged", s->converged);
		cJSON_AddNumberToObject(o, "duality_gap", s->gap);
		cJSON_AddNumberToObject(o, "tiles", s->tiles);
		cJSON_AddNumberToObject(o, "tile_px", s->tile);
		cJSON_AddNumberToObject(o, "support_pixels", s->support_pixels);
		cJSON_AddNumberToObject(o, "covariance_s", s->t_cov);
		cJSON_AddNumberToObject(o, "covariance_frames_per_s", s->t_cov > 0 ? (double)s->frames / s->t_cov : 0);
		cJSON_AddNumberToObject(o, "solve_s", s->t_solve);
		c0_report_add_array(o, "objective", s->hist, s->nhist);
		cJSON_AddItemToArray(arr, o);
	}
	cJSON *p = cJSON_AddObjectToObject(r->rep, "support_parameters");
	cJSON_AddNumberToObject(p, "pixel_size_nm", c->pixel_nm);
	cJSON_AddNumberToObject(p, "fwhm_nm", c->fwhm_nm);
	cJSON_AddNumberToObject(p, "srf", c->srf);
	cJSON_AddStringToObject(p, "penalty", c->penalty == C0_PENALTY_L1 ? "l1" : "cel0");
	cJSON_AddNumberToObject(p, "max_iterations", c->fista.maxit);
	cJSON_AddNumberToObject(p, "tol", c->fista.tol);
	r->pixel_nm = c->pixel_nm, r->srf = c->srf;
	r->Ly = r->sres[0].Ly, r->Lx = r->sres[0].Lx;
	const size_t L = (size_t)r->Ly * r->Lx;
	if (!(r->mask = c0_alloc(L, 1)))
		return C0_ENOMEM;
	int count = 0;
	for (size_t i = 0; i < L; i++) {
		for (int k = 0; k < r->nsup; k++)
			r->mask[i] |= r->sres[k].mask[i];
		count += r->mask[i];
	}
	cJSON_AddNumberToObject(r->rep, "support_pixels_union", count);
	cJSON_AddNumberToObject(r->timings, "support", c0_now() - t);
	return C0_OK;
}

/* One stack: its mean from the support step when that ran on it, else one
 * streaming pass (the covariance when the noise variance has to be
 * estimated, else just the mean); then the solve. */
static int intensity_one(const struct c0_intensity_conf *ic, const struct c0_support_conf *sc, struct c0_frames *f,
			 const uint8_t *mask, double s2, const struct c0_support_result *known,
			 struct c0_intensity_result *res, float **corrected, int64_t *frames, double *seconds)
{
	const double *mean;
	double *own = NULL;          /* the mean when this function read it */
	int H, W, st = C0_OK;
	if (known) {
		mean = known->mean, *frames = known->frames, s2 = known->sigma2, *seconds = 0;
		H = known->Ly / sc->srf, W = known->Lx / sc->srf;
	} else {
		H = f->height, W = f->width;
		if (s2 > 0) {
			st = c0_stack_mean(sc, f, &own, frames, seconds);
		} else {
			struct c0_cov cov = { 0 };
			st = c0_stack_covariance(sc, f, &cov, seconds);
			if (!st) {
				*frames = cov.frames;
				st = c0_support_noise(sc, &cov, mask, &s2);
				own = cov.mean, cov.mean = NULL;
			}
			c0_cov_free(&cov);
		}
		mean = own;
	}
	if (!st)
		st = c0_intensity_solve(ic, mean, H, W, *frames, mask, s2, res);
	if (!st && corrected) {
		size_t nc = (size_t)H * W;
		if (!(*corrected = malloc(nc * sizeof **corrected)))
			st = C0_ENOMEM;
		for (size_t p = 0; !st && p < nc; p++)
			(*corrected)[p] = (float)(mean[p] - res->b[p]);
	}
	free(own);
	return st;
}

int c0_step_intensity(struct c0_result *r, const struct c0_intensity_conf *ic, const struct c0_support_conf *sc,
		      struct c0_frames *f, const double *sigma2, int corrected)
{
	const int n = r->n;
	const struct c0_support_result *known[C0_MAX_STACKS] = { 0 };
	for (int k = 0; r->sres && k < r->nsup; k++)
		known[r->sup[k]] = &r->sres[k];
	if (f[0].height * sc->srf != r->Ly || f[0].width * sc->srf != r->Lx)
		return c0_fail(C0_EINVAL, "%s: %dx%d pixels at srf %d do not match the %dx%d support", f[0].name, f[0].width,
			       f[0].height, sc->srf, r->Lx, r->Ly);
	/* the stacks are independent: solve them side by side */
	int64_t frames[C0_MAX_STACKS];
	double tc[C0_MAX_STACKS], t = c0_now();
	int sts[C0_MAX_STACKS];
	char (*msg)[256] = c0_alloc((size_t)n, sizeof *msg);
	r->ires = c0_alloc((size_t)n, sizeof *r->ires);
	if (corrected)
		r->corrected = c0_alloc((size_t)n, sizeof *r->corrected);
	if (!msg || !r->ires || (corrected && !r->corrected)) {
		free(msg);
		return C0_ENOMEM;
	}
	struct c0_progress pr;
	int done = 0;
	c0_progress_begin(&pr, "intensity (stacks)", n);
#pragma omp parallel for schedule(dynamic, 1) if (n > 1)   /* one stack: its own loops get the threads */
	for (int i = 0; i < n; i++) {
		sts[i] = intensity_one(ic, sc, &f[i], r->mask, sigma2 ? sigma2[i] : 0, known[i], &r->ires[i],
				       corrected ? &r->corrected[i] : NULL, &frames[i], &tc[i]);
		if (sts[i])   /* error messages are per thread */
			snprintf(msg[i], sizeof msg[i], "%s", c0_errmsg());
#pragma omp critical(c0_intensity_progress)
		c0_progress_update(&pr, ++done);
	}
	c0_progress_end(&pr);
	for (int i = 0; i < n; i++)
		if (sts[i]) {
			int st = c0_fail(sts[i], "%s", msg[i]);
			free(msg);
			return st;
		}
	free(msg);
	r->pixel_nm = ic->pixel_nm, r->srf = ic->srf;
	cJSON *arr = cJSON_AddArrayToObject(r->rep, "intensity");
	for (int i = 0; i < n; i++) {
		const struct c0_intensity_result *s = &r->ires[i];
		cJSON *j = cJSON_CreateObject();
		cJSON_AddStringToObject(j, "stack", r->names[i]);
		cJSON_AddNumberToObject(j, "frames", (double)frames[i]);
		cJSON_AddNumberToObject(j, "noise_variance", s->sigma2);
		cJSON_AddNumberToObject(j, "mu", s->mu);
		cJSON_AddNumberToObject(j, "residual2", s->residual2);
		cJSON_AddNumberToObject(j, "discrepancy_target2", s->target2);
		static const char *dp[] = { "met", "below: even the smallest mu leaves a larger residual",
					    "above: even the largest mu leaves a smaller residual", "not converged" };
		cJSON_AddStringToObject(j, "discrepancy", s->dp_status < 0 ? "fixed mu" : dp[s->dp_status]);
		cJSON_AddNumberToObject(j, "solves", s->solves);
		cJSON_AddNumberToObject(j, "cg_iterations", s->cg_iters);
		cJSON_AddNumberToObject(j, "seconds", s->seconds + tc[i]);
		cJSON_AddItemToArray(arr, j);
	}
	cJSON *p = cJSON_AddObjectToObject(r->rep, "intensity_parameters");
	static const char *bg[] = { "none", "constant", "smooth" };
	cJSON_AddStringToObject(p, "background", bg[ic->background]);
	cJSON_AddNumberToObject(p, "beta", ic->beta);
	cJSON_AddNumberToObject(p, "nu", ic->nu);
	cJSON_AddNumberToObject(p, "fixed_mu", ic->mu);
	cJSON_AddNumberToObject(p, "graph_radius_px", ic->graph_radius);
	cJSON_AddNumberToObject(r->timings, "intensity", c0_now() - t);
	return C0_OK;
}

int c0_step_matirf(struct c0_result *r, const struct c0_run_conf *c, const struct c0_matirf_conf *m,
		   const float *const *img, const float *const *own, int ny, int nx, double pixel_nm, int baseline)
{
	struct c0_matirf_result *res = baseline ? &r->base : &r->vol;
	const char *key = baseline ? "baseline_matirf" : "matirf";
	const int nq = c->nangles;
	double t = c0_now();
	int st = c0_matirf_solve(m, nq, c->angles, c->ngains ? c->gains : NULL, img, ny, nx, res);
	if (st)
		return st;
	if (own) {
		c0_pool_rescale(res->f, res->nz, ny, nx, nq, own, img);
		for (size_t p = 0; p < (size_t)ny * nx; p++) {
			double s = 0;
			for (int j = 0; j < res->nz; j++)
				s += res->f[j * (size_t)ny * nx + p];
			res->total[p] = (float)s;
		}
	}
	if (!baseline)
		r->vol_pixel_nm = pixel_nm;
	r->z0_nm = m->z0_nm, r->dz_nm = m->dz_nm;
	cJSON *j = cJSON_AddObjectToObject(r->rep, key);
	c0_report_add_array(j, "angles_deg", c->angles, nq);
	if (c->ngains)
		c0_report_add_array(j, "gains", c->gains, c->ngains);
	double pen[C0_MAX_STACKS];
	for (int q = 0; q < nq; q++)
		c0_tirf_p(&m->tirf, c->angles[q], &pen[q]), pen[q] = 1 / pen[q];
	c0_report_add_array(j, "penetration_depth_nm", pen, nq);
	cJSON_AddNumberToObject(j, "critical_angle_deg", c0_tirf_critical_deg(&m->tirf));
	cJSON_AddNumberToObject(j, "n_glass", m->tirf.n_glass);
	cJSON_AddNumberToObject(j, "n_sample", m->tirf.n_sample);
	cJSON_AddNumberToObject(j, "wavelength_nm", m->tirf.wavelength_nm);
	cJSON_AddNumberToObject(j, "s_fraction", m->tirf.s_fraction);
	c0_report_add_array(j, "z_nm", res->z_nm, res->nz);
	if (!cJSON_GetObjectItem(r->rep, "z_nm"))
		c0_report_add_array(r->rep, "z_nm", res->z_nm, res->nz);
	cJSON_AddStringToObject(j, "regulariser", m->reg == C0_REG_TV ? "tv" : "hessian");
	cJSON_AddNumberToObject(j, "kappa", m->kappa);
	cJSON_AddNumberToObject(j, "axial_weight", m->wz);
	cJSON_AddNumberToObject(j, "sparsity", m->sparsity);
	cJSON_AddNumberToObject(j, "data_scale", res->scale);
	cJSON_AddNumberToObject(j, "iterations", res->iters);
	cJSON_AddBoolToObject(j, "converged", res->converged);
	cJSON_AddNumberToObject(j, "seconds", res->seconds);
	cJSON_AddNumberToObject(r->timings, key, c0_now() - t);
	return C0_OK;
}

/* The support stacks: 1-based numbers, or the smallest angle (the deepest
 * penetration sees every emitter), or the first stack in 2D mode. */
static int support_stacks(const struct c0_run_conf *c, int n, struct c0_result *r)
{
	if (!c->nsupport_stacks) {
		int best = 0;
		for (int i = 1; i < c->nangles; i++)
			if (c->angles[i] < c->angles[best])
				best = i;
		r->sup[0] = best, r->nsup = 1;
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

/* The volume from the intensities, each pooled over a window of about
 * pool_nm (odd, in fine pixels) on the support. */
static int volume(struct c0_result *r, const struct c0_run_conf *c, const struct c0_stage_confs *s)
{
	const int n = r->n, Ly = r->Ly, Lx = r->Lx;
	const float *img[C0_MAX_STACKS];
	float *pooled[C0_MAX_STACKS] = { 0 };
	const double fine = s->support.pixel_nm / s->support.srf;
	int h = (int)lround((s->pool_nm / fine - 1) / 2), st = C0_OK;
	for (int q = 0; !st && q < n; q++) {
		img[q] = r->ires[q].x;
		if (h <= 0)
			continue;
		pooled[q] = malloc((size_t)Ly * Lx * sizeof(float));
		st = pooled[q] ? c0_pool_window(r->ires[q].x, r->mask, Ly, Lx, h, pooled[q]) : C0_ENOMEM;
	}
	if (!st)
		st = c0_step_matirf(r, c, &s->matirf, h > 0 ? (const float *const *)pooled : img, h > 0 ? img : NULL, Ly, Lx,
				    fine, 0);
	if (!st)
		cJSON_AddNumberToObject(cJSON_GetObjectItem(r->rep, "matirf"), "depth_pool_window_px", h > 0 ? 2 * h + 1 : 0);
	for (int q = 0; q < n; q++)
		free(pooled[q]);
	if (!st && c->baseline)
		st = c0_step_matirf(r, c, &s->matirf, (const float *const *)r->corrected, NULL, r->ires[0].Ny,
				    r->ires[0].Nx, s->support.pixel_nm, 1);
	return st;
}

static int run(const struct c0_run_conf *c, const struct c0_stage_confs *sc, struct c0_frames *f, int n,
	       struct c0_result *r)
{
	const struct c0_stage_confs s = *sc;
	const int three_d = c->nangles > 0;
	int st = C0_OK;
	if (three_d)
		st = c0_run_conf_matirf_check(c, &s.matirf, n);
	if (!st && c->nnoise_variance)
		st = c0_fail(C0_EINVAL, "noise_variance: not used by the whole method (the support step estimates it)");
	if (!st)
		st = support_stacks(c, n, r);
	if (!st)
		st = c0_step_support(r, &s.support, f);
	if (c0_comm_rank() != 0)
		return st;      /* MPI: the other ranks share the support step; rank 0 has the result */
	int any = 0;
	for (size_t i = 0; !st && i < (size_t)r->Ly * r->Lx; i++)
		any |= r->mask[i];
	if (!st && !any)
		st = c0_fail(C0_EINVAL, "the support is empty: no emitter found (try a smaller lambda)");
	if (!st)
		st = c0_step_intensity(r, &s.intensity, &s.support, f, NULL, c->baseline && three_d);
	if (!st && three_d)
		st = volume(r, c, &s);
	if (st)
		return st;
	cJSON *p = cJSON_AddObjectToObject(r->rep, "parameters");
	cJSON_AddStringToObject(p, "mode", three_d ? "3D" : "2D");
	cJSON_AddNumberToObject(p, "pixel_size_nm", s.support.pixel_nm);
	cJSON_AddNumberToObject(p, "fine_pixel_nm", s.support.pixel_nm / s.support.srf);
	cJSON_AddNumberToObject(p, "fwhm_nm", s.support.fwhm_nm);
	cJSON_AddNumberToObject(p, "srf", s.support.srf);
	if (three_d)
		cJSON_AddNumberToObject(p, "depth_pool_nm", s.pool_nm);
	double s1[C0_MAX_STACKS];
	for (int k = 0; k < r->nsup; k++)
		s1[k] = r->sup[k] + 1;
	c0_report_add_array(p, "support_stacks", s1, r->nsup);
	return C0_OK;
}

int c0_pipe_begin(const char *command, const struct c0_run_conf *c, const struct c0_stack *stacks, int n,
		  struct c0_frames *f, struct c0_stage_confs *sc, struct c0_result **out)
{
	*out = NULL;
	if (n < 1 || n > C0_MAX_STACKS || !stacks || !c)
		return c0_fail(C0_EINVAL, "stacks: %d given, expected 1..%d", n, C0_MAX_STACKS);
	int st = c0_stacks_open(stacks, n, f);
	if (st)
		return st;
	const char *names[C0_MAX_STACKS];
	int is_file[C0_MAX_STACKS];
	double pixel_nm;
	for (int i = 0; i < n; i++)
		names[i] = f[i].name, is_file[i] = stacks[i].path != NULL;
	st = c0_stacks_pixel(c, f, &pixel_nm);
	if (!st)
		st = c0_run_conf_stages(c, pixel_nm, sc);
	if (!st)
		st = c0_result_new(command, n, names, is_file, out);
	if (st)
		c0_stacks_close(f, n);
	return st;
}

int c0_run(const struct c0_run_conf *c, const struct c0_stack *stacks, int n, struct c0_result **out)
{
	struct c0_frames f[C0_MAX_STACKS];
	struct c0_stage_confs sc;
	struct c0_result *r;
	int st = c0_pipe_begin("run", c, stacks, n, f, &sc, &r);
	if (st)
		return st;
	st = run(c, &sc, f, n, r);
	c0_stacks_close(f, n);
	if (st) {
		c0_result_free(r);
		return st;
	}
	*out = r;
	return C0_OK;
}

int c0_result_nstacks(const struct c0_result *r)
{
	return r->n;
}

static void dims(int *h, int *w, int hv, int wv)
{
	if (h)
		*h = hv;
	if (w)
		*w = wv;
}

const uint8_t *c0_result_support(const struct c0_result *r, int *h, int *w)
{
	dims(h, w, r->Ly, r->Lx);
	return r->mask;
}

const float *c0_result_intensity(const struct c0_result *r, int q, int *h, int *w)
{
	if (!r->ires || q < 0 || q >= r->n)
		return NULL;
	dims(h, w, r->ires[q].Ly, r->ires[q].Lx);
	return r->ires[q].x;
}

const float *c0_result_background(const struct c0_result *r, int q, int *h, int *w)
{
	if (!r->ires || q < 0 || q >= r->n)
		return NULL;
	dims(h, w, r->ires[q].Ny, r->ires[q].Nx);
	return r->ires[q].b;
}

static const float *vol(const struct c0_matirf_result *v, int *nz, int *h, int *w)
{
	if (nz)
		*nz = v->nz;
	dims(h, w, v->ny, v->nx);
	return v->f;
}

const float *c0_result_volume(const struct c0_result *r, int *nz, int *h, int *w)
{
	return vol(&r->vol, nz, h, w);
}

const float *c0_result_baseline_volume(const struct c0_result *r, int *nz, int *h, int *w)
{
	return vol(&r->base, nz, h, w);
}

const float *c0_result_depth(const struct c0_result *r, int *h, int *w)
{
	dims(h, w, r->vol.ny, r->vol.nx);
	return r->vol.depth;
}

const double *c0_result_z_nm(const struct c0_result *r, int *nz)
{
	if (nz)
		*nz = r->vol.nz;
	return r->vol.z_nm;
}

const char *c0_result_report_json(const struct c0_result *r)
{
	struct c0_result *m = (struct c0_result *)r;   /* the text is a cache of the report */
	if (!m->json)
		m->json = cJSON_Print(r->rep);
	return m->json;
}
