/* The MA-TIRF steps (steps_matirf.h): the volume from the intensities, and
 * the standard path on raw images. */
#include "app/steps_matirf.h"
#include "app/steps.h"
#include "app/report_json.h"
#include "stages/depthpool.h"
#include "stages/depthfit.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* the single-depth fit (stages/depthfit.h) of each column into res->depth at
 * its pixel; 0 off the columns, as their volume. With the pooled
 * intensities' noise known, the fit weighs the angles by it and reads the
 * pooled intensities themselves: the solve's projections are fitted to
 * them with equal weights and smoothed across pixels, which takes back most
 * of what the weights gain
 * (docs/defaults.md#depth_noise_block). */
static int depth_fit_cols(const struct c0_matirf_conf *m, const struct c0_angles *a, int nq, const struct c0_pooled *pool,
			  struct c0_matirf_result *res)
{
	const int w = pool && pool->var;
	const size_t M = (size_t)res->M, L = w ? pool->pl->M : M;
	float *d = c0_alloc(L ? L : 1, sizeof *d);
	int st = d ? C0_OK : C0_ENOMEM;
	const double *gain = a->ngains ? a->gain : NULL;
	if (!st && w)
		st = c0_depth_fit_y(&m->tirf, nq, a->deg, gain, m->z0_nm, res->nz * m->dz_nm, pool->pooled, L, pool->var, d);
	else if (!st)
		st = c0_depth_fit(&m->tirf, nq, a->deg, gain, res->nz, m->z0_nm, m->dz_nm, res->f, M, d);
	for (size_t k = 0, i = 0; !st && k < M; k++) {
		while (w && i < L && pool->pl->pix[i] < res->pixel[k])   /* pixel[] and pl's pixels both increase */
			i++;
		res->depth[res->pixel[k]] = !w ? d[k] : i < L && pool->pl->pix[i] == res->pixel[k] ? d[i] : 0;
	}
	free(d);
	return st;
}

int c0_step_matirf(struct c0_result *r, const struct c0_angles *a, const struct c0_matirf_conf *m,
		   const float *const *img, const struct c0_pooled *pool, int ny, int nx, double pixel_nm, int baseline)
{
	struct c0_matirf_result *res = baseline ? &r->base : &r->vol;
	const char *key = baseline ? "baseline_matirf" : "matirf";
	const int nq = a->n;
	const struct c0_step_clock t = c0_step_begin(key);
	int st = c0_matirf_solve(m, nq, a->deg, a->ngains ? a->gain : NULL, img, ny, nx, res);
	if (st)
		return st;
	if (pool) {
		const size_t M = res->M;
		c0_pool_rescale_at(res->f, res->nz, res->pixel, M, nq, pool->pl, pool->own, pool->pooled);
		for (size_t k = 0; k < M; k++) {     /* off the columns the total stays 0 */
			double s = 0;
			for (int j = 0; j < res->nz; j++)
				s += res->f[j * M + k];
			res->total[res->pixel[k]] = (float)s;
		}
	}
	/* the fine grid's depth map: each column's single-depth fit, not its mean,
	 * which reads deep (stages/depthfit.h). The camera-grid baseline keeps the
	 * mean: its 100 nm pixels hold several depths, whose brightness-weighted
	 * mean the single fit misses (demo: -29 nm signed, the mean -8 nm) */
	const double tfit = c0_now();
	if (!baseline && (st = depth_fit_cols(m, a, nq, pool, res)))
		return st;
	if (!baseline)
		r->vol_pixel_nm = pixel_nm;
	r->z0_nm = m->z0_nm, r->dz_nm = m->dz_nm;
	c0_report_depth_readout(c0_report_matirf(r->rep, key, a, m, res), baseline, baseline ? 0 : c0_now() - tfit);
	c0_step_end(r, &t);
	return C0_OK;
}

int c0_step_matirf_raw(struct c0_result *r, const struct c0_matirf_raw *raw, const struct c0_matirf_conf *m,
		       const float *const *img, int ny, int nx, double pixel_nm)
{
	const int nq = raw->angles.n;
	const size_t np = (size_t)ny * nx;
	float *x[C0_MAX_STACKS] = { 0 };
	int st = C0_OK;
	for (int q = 0; q < nq && !st; q++)
		if (!(x[q] = c0_alloc(np, sizeof **x)))
			st = C0_ENOMEM;
		else
			memcpy(x[q], img[q], np * sizeof **x);
	if (!st)
		st = c0_matirf_subtract(x, nq, np, raw->offset, "offset");
	if (!st)
		st = c0_matirf_subtract(x, nq, np, raw->background, "matirf_background");
	if (!st)
		st = c0_step_matirf(r, &raw->angles, m, (const float *const *)x, NULL, ny, nx, pixel_nm, 0);
	for (int q = 0; q < nq; q++)
		free(x[q]);
	if (st)
		return st;
	c0_report_matirf_raw(cJSON_GetObjectItem(r->rep, "matirf"), raw, &r->vol);
	return C0_OK;
}
