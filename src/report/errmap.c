/* The error map, in the spirit of SQUIRREL (Culley et al. 2018): the
 * estimate taken back to the camera by the forward model the intensity step
 * fitted, model = Psi x + b (the Gaussian PSF integrated over the camera
 * pixels, DESIGN.md section 2, plus the estimated background), against the
 * data's temporal mean ybar. SQUIRREL fits a scale and an offset between a
 * super-resolved image and the reference first; here the estimate is in
 * camera units and the background is part of it, so none is fitted:
 *   residual = ybar - model (positive: light the estimate misses, a deleted
 *   structure; negative: light it invents),
 *   RSP = Pearson correlation of ybar and model,
 *   RSE = RMS of the residual (camera units), read against the noise sd of
 *   a mean image, sqrt(sigma2 / T). */
#include "report/html.h"
#include "optics/psf.h"
#include "core/band.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* Rows of X taken to double at a time (each row's product is its own) */
#define C0_ERRMAP_BAND 256

/* model (ny x nx) = G_y X G_x^T + b */
static int forward(const struct c0_rundir *d, const float *x, const float *b, double *model)
{
	const int ny = d->ny, nx = d->nx, r = d->grid.srf, Ly = ny * r, Lx = nx * r;
	const double sigma = c0_grid_sigma_px(&d->grid);
	struct c0_band gy = { 0 }, gx = { 0 };
	double *X = c0_alloc((size_t)C0_ERRMAP_BAND * Lx, sizeof *X), *tmp = c0_alloc((size_t)Ly * nx, sizeof *tmp);
	int st = X && tmp ? C0_OK : C0_ENOMEM;
	if (!st)
		st = c0_psf_factor(ny, r, sigma, &gy);
	if (!st)
		st = c0_psf_factor(nx, r, sigma, &gx);
	if (!st) {
		for (int y0 = 0; y0 < Ly; y0 += C0_ERRMAP_BAND) {
			const int nr = Ly - y0 < C0_ERRMAP_BAND ? Ly - y0 : C0_ERRMAP_BAND;
			for (size_t i = 0; i < (size_t)nr * Lx; i++)
				X[i] = x[(size_t)y0 * Lx + i];
			c0_band_apply_x(&gx, nr, X, tmp + (size_t)y0 * nx);
		}
		c0_band_apply_y(&gy, nx, tmp, model);
		for (size_t i = 0; i < (size_t)ny * nx; i++)
			model[i] += b[i];
	}
	c0_band_free(&gy), c0_band_free(&gx);
	free(X), free(tmp);
	return st;
}

static void stats(const float *data, const double *model, size_t n, float *res, struct c0_errstat *e)
{
	double sd = 0, sm = 0, sdd = 0, smm = 0, sdm = 0, sr = 0;
	for (size_t i = 0; i < n; i++) {
		double a = data[i], m = model[i];
		res[i] = (float)(a - m);
		sd += a, sm += m, sdd += a * a, smm += m * m, sdm += a * m, sr += (a - m) * (a - m);
	}
	double va = sdd - sd * sd / n, vm = smm - sm * sm / n, cov = sdm - sd * sm / n;
	e->rsp = va > 0 && vm > 0 ? cov / sqrt(va * vm) : 0;
	e->rse = sqrt(sr / n);
	e->mean_data = sd / n;
}

int c0_errmap(struct c0_rundir *d)
{
	const size_t n = (size_t)d->ny * d->nx;
	double *model = c0_alloc(n ? n : 1, sizeof *model);
	int st = model ? C0_OK : C0_ENOMEM;
	for (int q = 0; q < d->n && !st; q++) {
		if (!d->mean[q] || !d->inten || !d->bg[q])
			continue;
		char name[64];
		float *x = NULL;
		snprintf(name, sizeof name, "intensity_q%02d.tif", q + 1);
		if (!(d->err[q] = c0_alloc(n, sizeof *d->err[q])))
			st = C0_ENOMEM;
		if (!st)
			st = c0_rundir_plane(d, name, 0, &x);
		if (!st)
			st = forward(d, x, d->bg[q], model);
		free(x);
		if (st)
			break;
		stats(d->mean[q], model, n, d->err[q], &d->es[q]);
		char k[64], f[64];
		snprintf(k, sizeof k, "intensity.%d.noise_variance", q);
		snprintf(f, sizeof f, "intensity.%d.frames", q);
		double s2 = c0_json_num(d->rep, k, 0), T = c0_json_num(d->rep, f, 0);
		d->es[q].noise_sd = s2 > 0 && T > 0 ? sqrt(s2 / T) : 0;
	}
	free(model);
	return st;
}
