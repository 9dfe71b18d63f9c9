/* The support stage's helpers that its files share (support.c,
 * support_solve.c, support_stream.c, support_tiles.c, lambda.c,
 * lambda_cv.c): the configuration's derived values and its check, the
 * errors, the accumulator and the tile grid. They call nothing of those
 * files, so the files stand in a line instead of a loop. */
#include "stages/support_util.h"
#include "optics/psf.h"
#include "core/err.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int c0_support_lag(const struct c0_support_conf *c)
{
	return c0_grid_lag(&c->grid, c->lag);
}

void c0_support_set_width(struct c0_support_conf *c, double fwhm_nm)
{
	if (c->lag == 0)
		c->lag = c0_support_lag(c);
	c->grid.fwhm_nm = fwhm_nm;
}

double c0_support_default_lambda(enum c0_penalty p)
{
	return p == C0_PENALTY_CEL0 ? 3e-5 : 1e-2;
}

double c0_support_tol(const struct c0_support_conf *c)
{
	if (c->fista.tol >= 0)
		return c->fista.tol;
	return c->penalty == C0_PENALTY_L1 && c->solver == C0_SUPPORT_FISTA ? 0 : C0_SUPPORT_TOL;
}

double c0_support_guard_ratio(const struct c0_support_conf *c)
{
	const double sigma = c0_grid_sigma_px(&c->grid);
	double g = INFINITY, w[3];
	/* a source inside pixel 0 (others give larger ratios: the pixel is
	 * then on their Gaussian's flank or tail) */
	for (int k = 0; k <= 64; k++) {
		c0_psf_pixel_weights(k / 64.0, sigma, -1, 3, w);
		if (w[1] > 0)
			g = fmin(g, (w[0] + w[2]) / (2 * w[1]));
	}
	return g < 1 ? g : 1;
}

int c0_support_acc_new(const struct c0_support_conf *c, int W, int H, int d, int x0, int y0, struct c0_cov_acc **a)
{
	int st = c0_cov_acc_new(W, H, d, a);
	if (!st && c->guard)
		c0_cov_acc_set_guard(*a, c0_support_guard_ratio(c));
	if (!st && c->noise_map)
		c0_cov_acc_set_noise(*a, c->noise_map, c->noise_map_w, x0, y0);
	return st;
}

double c0_support_lambda_rel(const struct c0_support_conf *c)
{
	return c->lambda_rel > 0 ? c->lambda_rel : c0_support_default_lambda(c->penalty);
}

int c0_support_fail_flat(void)
{
	return c0_fail(C0_EINVAL, "the stack does not fluctuate (zero temporal variance everywhere)");
}

int c0_support_fail_short(const struct c0_frames *in)
{
	return c0_fail(C0_EINVAL, "%s: %lld frames is too short to choose lambda from two halves (needs >= 6; "
		       "give lambda)", in->name, (long long)in->count);
}

int c0_support_check(const struct c0_support_conf *c, int W, int H, int64_t frames, const char *name)
{
	if (!(c->grid.pixel_nm > 0))
		return c0_fail(C0_EINVAL, "pixel_nm %g: must be positive (nm; not found in %s's calibration)", c->grid.pixel_nm, name);
	int st = c0_grid_check(&c->grid);
	if (st)
		return st;
	if (!(c->lambda_rel >= 0 && c->lambda_rel < 1))
		return c0_fail(C0_EINVAL, "lambda %g: must be in (0, 1) (relative to lambda_max)", c->lambda_rel);
	if (c->fista.maxit < 1)
		return c0_fail(C0_EINVAL, "iterations %d: must be positive", c->fista.maxit);
	if (!(c->fista.tol >= 0 && c->fista.tol < 1) && c->fista.tol != -1)
		return c0_fail(C0_EINVAL, "tol %g: must be in [0, 1) (0: every iteration), or -1 for the solver's", c->fista.tol);
	if (c->penalty == C0_PENALTY_CEL0 && c->cel0_outer < 1)
		return c0_fail(C0_EINVAL, "reweightings %d: must be at least 1", c->cel0_outer);
	if (c->lag < 0 || c->lag > 1000)
		return c0_fail(C0_EINVAL, "lag %d: must be 0 (from the PSF) to 1000 pixels", c->lag);
	int d = c0_support_lag(c);
	if (c->tile && c->tile < 2 * d + 1)
		return c0_fail(C0_EINVAL, "tile %d: smaller than the PSF band (%d pixels for lag %d)", c->tile, 2 * d + 1, d);
	if (c->tile && c->tile > (W > H ? W : H))
		return c0_fail(C0_EINVAL, "tile %d: larger than the %dx%d image of %s", c->tile, W, H, name);
	if (W < 2 * d + 1 || H < 2 * d + 1)
		return c0_fail(C0_EINVAL, "%s: %dx%d pixels is smaller than the PSF band (%d x %d pixels for lag %d)",
			       name, W, H, 2 * d + 1, 2 * d + 1, d);
	if (frames < 3)
		return c0_fail(C0_EINVAL, "%s: %lld frames; the covariance needs at least 3", name, (long long)frames);
	return C0_OK;
}

void c0_support_result_free(struct c0_support_result *r)
{
	free(r->mask), free(r->rx), free(r->mean), free(r->hist);
	c0_frc_free(&r->frc);
	memset(r, 0, sizeof *r);
}

int c0_support_tile_size(const struct c0_support_conf *c, int W, int H)
{
	int big = W > H ? W : H;
	return c->tile > 0 ? c->tile : C0_SUPPORT_TILE < big ? C0_SUPPORT_TILE : big;
}

int c0_support_grid(const struct c0_support_conf *c, const struct c0_frames *in, struct c0_tiling *tl)
{
	const int W = in->width, H = in->height;
	memset(tl, 0, sizeof *tl);
	int st = c0_support_check(c, W, H, in->count, in->name);
	return st ? st : c0_tiling_make(H, W, c0_support_tile_size(c, W, H), 2 * c0_support_lag(c), tl);
}

void c0_lambda_max(const double *C, double norm, double s0, const double *n, size_t L, double lm[2])
{
	lm[0] = lm[1] = 0;
	for (size_t i = 0; i < L; i++) {
		const double g = C[i] / norm - s0 * n[i];
		lm[0] = fmax(lm[0], g);
		if (g > 0)
			lm[1] = fmax(lm[1], g * g / (2 * n[i] * n[i]));
	}
}
