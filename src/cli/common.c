#define _XOPEN_SOURCE 700
#include "cli/common.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"
#include "io/png.h"
#include "stages/depthcode.h"
#include "stages/depthpool.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int c0_check_inputs(char **stacks, int n, const char *outdir)
{
	char od[PATH_MAX] = "";
	if (outdir && !realpath(outdir, od))
		od[0] = '\0';          /* does not exist yet: cannot hold an input */
	for (int i = 0; i < n; i++) {
		struct c0_tiff_reader *r;
		int st = c0_tiff_open(stacks[i], &r);
		if (st)
			return st;
		c0_tiff_close(r);
		char in[PATH_MAX];
		if (od[0] && realpath(stacks[i], in)) {
			char *slash = strrchr(in, '/');
			if (slash)
				*slash = '\0';
			if (!strcmp(in[0] ? in : "/", od))
				return c0_fail(C0_EINVAL, "-o %s: is the directory of input %s; write results elsewhere", outdir, stacks[i]);
		}
	}
	return C0_OK;
}

int c0_run_support(struct c0_support_conf *c, char **stacks, int n, struct c0_support_result *res, cJSON *rep)
{
	cJSON *arr = cJSON_AddArrayToObject(rep, "support");
	for (int i = 0; i < n; i++) {
		struct c0_tiff_reader *r;
		int st = c0_tiff_open(stacks[i], &r);
		if (st)
			return st;
		const struct c0_tiff_info *in = c0_tiff_get_info(r);
		if (!(c->pixel_nm > 0) && in->pixel_size_nm > 0)
			c->pixel_nm = in->pixel_size_nm;
		st = c0_support_stack(c, r, stacks[i], &res[i]);
		c0_tiff_close(r);
		if (st)
			return st;
		if (i > 0 && (res[i].Ly != res[0].Ly || res[i].Lx != res[0].Lx))
			return c0_fail(C0_EINVAL, "%s: %dx%d pixels differs from %s", stacks[i], res[i].Lx / c->srf,
				       res[i].Ly / c->srf, stacks[0]);
		const struct c0_support_result *s = &res[i];
		cJSON *o = cJSON_CreateObject();
		cJSON_AddStringToObject(o, "stack", stacks[i]);
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
	cJSON *p = cJSON_AddObjectToObject(rep, "support_parameters");
	cJSON_AddNumberToObject(p, "pixel_size_nm", c->pixel_nm);
	cJSON_AddNumberToObject(p, "fwhm_nm", c->fwhm_nm);
	cJSON_AddNumberToObject(p, "srf", c->srf);
	cJSON_AddStringToObject(p, "penalty", c->penalty == C0_PENALTY_L1 ? "l1" : "cel0");
	cJSON_AddNumberToObject(p, "max_iterations", c->fista.maxit);
	cJSON_AddNumberToObject(p, "tol", c->fista.tol);
	return C0_OK;
}

int c0_write_support(struct c0_outdir *out, const struct c0_support_conf *c, const struct c0_support_result *res,
		     int n, cJSON *rep)
{
	const size_t L = (size_t)res[0].Ly * res[0].Lx;
	float *img = c0_alloc(L * (size_t)n, sizeof *img);
	if (!img)
		return C0_ENOMEM;
	int count = 0;
	for (size_t i = 0; i < L; i++) {
		int on = 0;
		for (int k = 0; k < n; k++)
			on |= res[k].mask[i];
		img[i] = (float)on;
		count += on;
	}
	cJSON_AddNumberToObject(rep, "support_pixels_union", count);
	struct c0_tiff_wopts o = { .width = res[0].Lx, .height = res[0].Ly, .dtype = C0_U8,
				   .pixel_size_nm = c->pixel_nm / c->srf, .software = "col0rme" };
	int st = c0_tiff_save_f32(c0_outdir_file(out, "support.tif"), &o, img);
	if (!st) {
		for (int k = 0; k < n; k++)
			memcpy(img + k * L, res[k].rx, L * sizeof *img);
		o.dtype = C0_F32;
		o.slices = n;
		st = c0_tiff_save_f32(c0_outdir_file(out, "rx.tif"), &o, img);
	}
	free(img);
	return st;
}

/* One stack: its mean from the support step when that ran on it, else one
 * streaming pass (the covariance when the noise variance has to be
 * estimated, else just the mean); then the solve. */
static int intensity_one(const struct c0_intensity_conf *ic, const struct c0_support_conf *sc, const char *stack,
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
		struct c0_tiff_reader *r;
		if ((st = c0_tiff_open(stack, &r)))
			return st;
		const struct c0_tiff_info *in = c0_tiff_get_info(r);
		H = (int)in->height, W = (int)in->width;
		if (s2 > 0) {
			st = c0_stack_mean(sc, r, stack, &own, frames, seconds);
		} else {
			struct c0_cov cov = { 0 };
			st = c0_stack_covariance(sc, r, stack, &cov, seconds);
			if (!st) {
				*frames = cov.frames;
				st = c0_support_noise(sc, &cov, mask, &s2);
				own = cov.mean, cov.mean = NULL;
			}
			c0_cov_free(&cov);
		}
		c0_tiff_close(r);
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

int c0_run_intensity(struct c0_outdir *out, const struct c0_intensity_conf *ic, const struct c0_support_conf *sc,
		     char **stacks, int n, const uint8_t *mask, const double *sigma2,
		     const struct c0_support_result *const *known, struct c0_intensity_result *res, float **corrected,
		     cJSON *rep)
{
	/* the stacks are independent: solve them side by side, write in order */
	int64_t frames[64];
	double tc[64];
	int sts[64];
	char (*msg)[256] = c0_alloc((size_t)n, sizeof *msg);
	if (!msg || n > 64) {
		free(msg);
		return n > 64 ? c0_fail(C0_EINVAL, "at most 64 stacks") : C0_ENOMEM;
	}
	struct c0_progress pr;
	int done = 0;
	c0_progress_begin(&pr, "intensity (stacks)", n);
#pragma omp parallel for schedule(dynamic, 1) if (n > 1)   /* one stack: its own loops get the threads */
	for (int i = 0; i < n; i++) {
		sts[i] = intensity_one(ic, sc, stacks[i], mask, sigma2 ? sigma2[i] : 0, known ? known[i] : NULL, &res[i],
				       corrected ? &corrected[i] : NULL, &frames[i], &tc[i]);
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
	cJSON *arr = cJSON_AddArrayToObject(rep, "intensity");
	for (int i = 0; i < n; i++) {
		int st;
		const struct c0_intensity_result *s = &res[i];
		char name[64];
		struct c0_tiff_wopts o = { .width = s->Lx, .height = s->Ly, .dtype = C0_F32,
					   .pixel_size_nm = ic->pixel_nm / ic->srf, .software = "col0rme" };
		snprintf(name, sizeof name, "intensity_q%02d.tif", i + 1);
		if ((st = c0_tiff_save_f32(c0_outdir_file(out, name), &o, s->x)))
			return st;
		o.width = s->Nx, o.height = s->Ny, o.pixel_size_nm = ic->pixel_nm;
		snprintf(name, sizeof name, "background_q%02d.tif", i + 1);
		if ((st = c0_tiff_save_f32(c0_outdir_file(out, name), &o, s->b)))
			return st;
		cJSON *j = cJSON_CreateObject();
		cJSON_AddStringToObject(j, "stack", stacks[i]);
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
	cJSON *p = cJSON_AddObjectToObject(rep, "intensity_parameters");
	static const char *bg[] = { "none", "constant", "smooth" };
	cJSON_AddStringToObject(p, "background", bg[ic->background]);
	cJSON_AddNumberToObject(p, "beta", ic->beta);
	cJSON_AddNumberToObject(p, "nu", ic->nu);
	cJSON_AddNumberToObject(p, "fixed_mu", ic->mu);
	cJSON_AddNumberToObject(p, "graph_radius_px", ic->graph_radius);
	return C0_OK;
}

void c0_matirf_cli_opts(struct c0_matirf_cli *m, struct c0_opt *o)
{
	m->reg = m->c.reg == C0_REG_TV ? "tv" : "hessian";
	const struct c0_opt rows[C0_MATIRF_CLI_OPTS] = {
		{ "angles", 0, C0_OPT_DOUBLES, m->angles, "DEG,...", "incidence angle in the glass of each stack/image, same order", "none", 64, &m->nangles },
		{ "n-glass", 0, C0_OPT_DOUBLE, &m->c.tirf.n_glass, "N", "refractive index of the coverslip and immersion", NULL, 0, NULL },
		{ "n-sample", 0, C0_OPT_DOUBLE, &m->c.tirf.n_sample, "N", "refractive index of the sample", NULL, 0, NULL },
		{ "wavelength", 0, C0_OPT_DOUBLE, &m->c.tirf.wavelength_nm, "NM", "excitation wavelength in vacuum", NULL, 0, NULL },
		{ "s-fraction", 0, C0_OPT_DOUBLE, &m->c.tirf.s_fraction, "F", "share of s-polarised excitation in I0", NULL, 0, NULL },
		{ "gains", 0, C0_OPT_DOUBLES, m->gains, "G,...", "per-angle gain calibration (multiplies I0)", "1 for every angle", 64, &m->ngains },
		{ "z-range", 0, C0_OPT_DOUBLES, m->zr, "MIN,MAX,STEP", "depth bins in nm", "0,400,20", 3, &m->nzr },
		{ "reg", 0, C0_OPT_STRING, &m->reg, "tv|hessian", "regulariser: total variation or Hessian-Schatten", NULL, 0, NULL },
		{ "kappa", 0, C0_OPT_DOUBLE, &m->c.kappa, "K", "regularisation weight (images scaled to a maximum of 1)", NULL, 0, NULL },
		{ "sparsity", 0, C0_OPT_DOUBLE, &m->c.sparsity, "S", "weight of the l1 term that keeps few depths per pixel", NULL, 0, NULL },
		{ "axial-weight", 0, C0_OPT_DOUBLE, &m->c.wz, "W", "axial weight of the regulariser relative to lateral", NULL, 0, NULL },
		{ "matirf-iterations", 0, C0_OPT_INT, &m->c.pdhg.maxit, "N", "maximum primal-dual iterations", NULL, 0, NULL },
	};
	memcpy(o, rows, sizeof rows);
}

int c0_matirf_cli_finish(struct c0_matirf_cli *m, int nimages)
{
	if (!strcmp(m->reg, "tv"))
		m->c.reg = C0_REG_TV;
	else if (!strcmp(m->reg, "hessian"))
		m->c.reg = C0_REG_HESSIAN;
	else
		return c0_fail(C0_EINVAL, "--reg %s: expected tv or hessian", m->reg);
	if (m->nzr && m->nzr != 3)
		return c0_fail(C0_EINVAL, "--z-range: expected MIN,MAX,STEP in nm");
	if (m->nzr)
		m->c.z0_nm = m->zr[0], m->c.z1_nm = m->zr[1], m->c.dz_nm = m->zr[2];
	if (m->nangles != nimages)
		return c0_fail(C0_EINVAL, "--angles: %d angles for %d stacks (one per stack, same order)", m->nangles, nimages);
	if (m->ngains && m->ngains != nimages)
		return c0_fail(C0_EINVAL, "--gains: %d gains for %d stacks", m->ngains, nimages);
	for (int q = 0; q < m->ngains; q++)
		if (!(m->gains[q] > 0))
			return c0_fail(C0_EINVAL, "--gains: gain %d is %g, must be > 0", q + 1, m->gains[q]);
	return c0_matirf_check(&m->c, m->nangles, m->angles);
}

int c0_run_matirf(struct c0_outdir *out, const struct c0_matirf_cli *m, const float *const *img,
		  const float *const *own, int ny, int nx, double pixel_nm, const char *prefix, const char *key,
		  struct c0_matirf_result *res, cJSON *rep)
{
	int st = c0_matirf_solve(&m->c, m->nangles, m->angles, m->ngains ? m->gains : NULL, img, ny, nx, res);
	if (st)
		return st;
	if (own) {
		c0_pool_rescale(res->f, res->nz, ny, nx, m->nangles, own, img);
		for (size_t p = 0; p < (size_t)ny * nx; p++) {
			double s = 0;
			for (int j = 0; j < res->nz; j++)
				s += res->f[j * (size_t)ny * nx + p];
			res->total[p] = (float)s;
		}
	}
	char name[128];
	struct c0_tiff_wopts o = { .width = nx, .height = ny, .slices = res->nz, .dtype = C0_F32,
				   .pixel_size_nm = pixel_nm, .z_spacing_nm = m->c.dz_nm, .software = "col0rme" };
	snprintf(name, sizeof name, "%svolume.tif", prefix);
	if ((st = c0_tiff_save_f32(c0_outdir_file(out, name), &o, res->f)))
		return st;
	o.slices = 1;
	snprintf(name, sizeof name, "%sdepth.tif", prefix);
	if ((st = c0_tiff_save_f32(c0_outdir_file(out, name), &o, res->depth)))
		return st;
	uint8_t *rgb;
	int w, h;
	if ((st = c0_depthcode(res->f, res->nz, ny, nx, m->c.z0_nm, m->c.z0_nm + res->nz * m->c.dz_nm, &rgb, &w, &h)))
		return st;
	snprintf(name, sizeof name, "%sdepth.png", prefix);
	st = c0_png_write_rgb(c0_outdir_file(out, name), w, h, rgb);
	free(rgb);
	if (st)
		return st;
	cJSON *j = cJSON_AddObjectToObject(rep, key);
	c0_report_add_array(j, "angles_deg", m->angles, m->nangles);
	if (m->ngains)
		c0_report_add_array(j, "gains", m->gains, m->ngains);
	double pen[64];
	for (int q = 0; q < m->nangles; q++)
		c0_tirf_p(&m->c.tirf, m->angles[q], &pen[q]), pen[q] = 1 / pen[q];
	c0_report_add_array(j, "penetration_depth_nm", pen, m->nangles);
	cJSON_AddNumberToObject(j, "critical_angle_deg", c0_tirf_critical_deg(&m->c.tirf));
	cJSON_AddNumberToObject(j, "n_glass", m->c.tirf.n_glass);
	cJSON_AddNumberToObject(j, "n_sample", m->c.tirf.n_sample);
	cJSON_AddNumberToObject(j, "wavelength_nm", m->c.tirf.wavelength_nm);
	cJSON_AddNumberToObject(j, "s_fraction", m->c.tirf.s_fraction);
	c0_report_add_array(j, "z_nm", res->z_nm, res->nz);
	if (!cJSON_GetObjectItem(rep, "z_nm"))
		c0_report_add_array(rep, "z_nm", res->z_nm, res->nz);
	cJSON_AddStringToObject(j, "regulariser", m->c.reg == C0_REG_TV ? "tv" : "hessian");
	cJSON_AddNumberToObject(j, "kappa", m->c.kappa);
	cJSON_AddNumberToObject(j, "axial_weight", m->c.wz);
	cJSON_AddNumberToObject(j, "sparsity", m->c.sparsity);
	cJSON_AddNumberToObject(j, "data_scale", res->scale);
	cJSON_AddNumberToObject(j, "iterations", res->iters);
	cJSON_AddBoolToObject(j, "converged", res->converged);
	cJSON_AddNumberToObject(j, "seconds", res->seconds);
	return C0_OK;
}
