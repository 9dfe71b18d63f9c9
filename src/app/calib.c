/* The camera's calibration maps (sCMOS: offset, read-noise variance, gain):
 * read, checked against the stacks before any heavy work, and attached to
 * the frame sources (offset and gain) and the support's covariance (the
 * read-noise variance). docs/guide.md: making the maps from dark frames. */
#include "app/calib.h"
#include "app/result.h"
#include "app/pipeline_conf.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/order.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define REGION_FRAMES 20     /* frames of the first stack for the region test */
#define REGION_MIN_RHO 0.05  /* below: the map's pattern is not in the stack */
#define REGION_PATTERN 0.5   /* ADU: a flatter offset map cannot be placed */

/* One plane of W x H from path; what: "offset", "variance" or "gain". */
static int load_map(const char *path, const char *what, int W, int H, float **out)
{
	*out = NULL;
	struct c0_tiff_reader *t;
	int st = c0_tiff_open(path, &t);
	if (st)
		return st;
	c0_tiff_allow_nonfinite(t);
	const struct c0_tiff_info *in = c0_tiff_get_info(t);
	if (in->width != W || in->height != H)
		st = c0_fail(C0_EINVAL, "%s: calibration map is %lldx%lld, the stacks are %dx%d (the same camera region and binning are needed)",
			     path, (long long)in->width, (long long)in->height, W, H);
	else if (in->pages != 1)
		st = c0_fail(C0_EINVAL, "%s: %lld planes; a calibration map is one plane (the per-pixel %s of the dark frames)", path,
			     (long long)in->pages, strcmp(what, "variance") ? "mean" : "variance");
	else if (!(*out = c0_alloc((size_t)W * H, sizeof **out)))
		st = C0_ENOMEM;
	else
		st = c0_tiff_read_f32(t, 0, *out);
	c0_tiff_close(t);
	for (size_t i = 0; !st && i < (size_t)W * H; i++) {
		const float v = (*out)[i];
		const int x = (int)(i % (size_t)W), y = (int)(i / (size_t)W);
		if (!isfinite(v))
			st = c0_fail(C0_EINVAL, "%s: pixel (x %d, y %d) is %s; a %s map must be finite", path, x, y, isnan(v) ? "NaN" : "infinite", what);
		else if (!strcmp(what, "variance") && v < 0)
			st = c0_fail(C0_EINVAL, "%s: pixel (x %d, y %d) has a negative variance (%g); read-noise variances are >= 0", path, x, y, v);
		else if (!strcmp(what, "gain") && !(v > 0))
			st = c0_fail(C0_EINVAL, "%s: pixel (x %d, y %d) has gain %g; gains must be > 0", path, x, y, v);
	}
	if (st)
		free(*out), *out = NULL;
	return st;
}

/* v minus the mean of its 3 x 3 neighbourhood (edges: the pixels there) */
static void highpass(const double *v, int W, int H, double *h)
{
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			double s = 0;
			int m = 0;
			for (int j = y > 0 ? y - 1 : 0; j <= (y + 1 < H ? y + 1 : y); j++)
				for (int k = x > 0 ? x - 1 : 0; k <= (x + 1 < W ? x + 1 : x); k++)
					s += v[j * W + k], m++;
			h[y * W + x] = v[y * W + x] - s / m;
		}
}

/* Pixel i and its 3 x 3 neighbours (its high-pass's support) vary in time
 * no more than lim */
static int quiet(const float *tv, int W, int H, size_t i, double lim)
{
	const int x = (int)(i % (size_t)W), y = (int)(i / (size_t)W);
	for (int j = y > 0 ? y - 1 : 0; j <= (y + 1 < H ? y + 1 : y); j++)
		for (int k = x > 0 ? x - 1 : 0; k <= (x + 1 < W ? x + 1 : x); k++)
			if (!(tv[(size_t)j * W + k] <= lim))
				return 0;
	return 1;
}

/* Does the offset map's fine pattern show in the stack? The correlation of
 * the high-passed mean of the first frames with the high-passed map, over
 * the quiet pixels: no bright spot, no noisy read-out, and no more temporal
 * variance than the median pixel's across their 3 x 3 neighbourhood (where
 * labelled structures blink, their shot noise in a mean of 20 frames hides
 * a pattern of 2 ADU). A map of another
 * region (or camera) of the right size has none; a map flatter than
 * REGION_PATTERN cannot be told from another and passes. *rho: NAN then. */
static int region_check(const char *path, struct c0_frames *f, const float *off, const float *var, double *rho)
{
	*rho = NAN;
	const int W = f->width, H = f->height, K = f->count < REGION_FRAMES ? (int)f->count : REGION_FRAMES;
	const size_t n = (size_t)W * H;
	double *m = c0_alloc(5 * n, sizeof *m), *hm = m + n, *o = m + 2 * n, *ho = m + 3 * n, *m2 = m + 4 * n;
	float *fr = c0_alloc(n, sizeof *fr);
	int st = m && fr ? C0_OK : C0_ENOMEM;
	for (int t = 0; !st && t < K; t++)
		if (!(st = c0_frames_read(f, t, fr)))
			for (size_t i = 0; i < n; i++)
				m[i] += fr[i] / (double)K, m2[i] += (double)fr[i] * fr[i] / K;
	for (int t = 0; t < K; t++)   /* raw sums: the calibrated passes note their own */
		f->sum[t] = NAN;
	float *a = st ? NULL : c0_alloc(n, sizeof *a);
	if (!st && !a)
		st = C0_ENOMEM;
	if (!st) {
		for (size_t i = 0; i < n; i++)
			o[i] = off[i];
		highpass(m, W, H, hm), highpass(o, W, H, ho);
		for (size_t i = 0; i < n; i++)
			a[i] = (float)fabs(ho[i]);
		const double pat = 1.4826 * c0_median_of(a, n);
		for (size_t i = 0; i < n; i++)
			a[i] = (float)fabs(hm[i]);
		const double lim = 4 * 1.4826 * c0_median_of(a, n), vmed = var ? c0_median_of(var, n) : 0;
		for (size_t i = 0; i < n; i++)
			a[i] = (float)(m2[i] - m[i] * m[i]);
		const double tmed = c0_median_of(a, n);
		double sxy = 0, sxx = 0, syy = 0;
		for (size_t i = 0; i < n; i++)
			if (fabs(hm[i]) <= lim && (!var || var[i] <= 4 * vmed) && quiet(a, W, H, i, tmed))
				sxy += hm[i] * ho[i], sxx += ho[i] * ho[i], syy += hm[i] * hm[i];
		if (pat >= REGION_PATTERN && sxx > 0 && syy > 0) {
			*rho = sxy / sqrt(sxx * syy);
			if (*rho < REGION_MIN_RHO)
				st = c0_fail(C0_EINVAL, "%s: the offset map's pixel pattern (%.2g ADU) is not in %s (correlation %.3f): a map of "
					     "another camera region, binning or camera?", path, pat, f->name, *rho);
		}
	}
	free(m), free(fr), free(a);
	return st;
}

int c0_calib_attach(const struct c0_run_conf *c, struct c0_frames *f, int n, struct c0_stage_confs *sc, struct c0_result *r)
{
	if (!c->offset_map && !c->variance_map && !c->gain_map)
		return C0_OK;
	const int W = f[0].width, H = f[0].height;
	const size_t np = (size_t)W * H;
	float *off = NULL, *var = NULL, *gain = NULL;
	int st = c->offset_map ? load_map(c->offset_map, "offset", W, H, &off) : C0_OK;
	if (!st && c->variance_map)
		st = load_map(c->variance_map, "variance", W, H, &var);
	if (!st && c->gain_map)
		st = load_map(c->gain_map, "gain", W, H, &gain);
	double rho = NAN;
	if (!st && off)
		st = region_check(c->offset_map, &f[0], off, var, &rho);
	if (st) {
		free(off), free(var), free(gain);
		return st;
	}
	/* gains evened to their mean: the frames keep their ADU scale */
	double gm = 0;
	for (size_t i = 0; gain && i < np; i++)
		gm += gain[i] / (double)np;
	for (size_t i = 0; gain && i < np; i++)
		gain[i] = (float)(gm / gain[i]);
	/* the read variance in those units, less its median: the support's noise
	 * variance keeps the typical pixel's read noise */
	double vmed = var ? c0_median_of(var, np) : 0;
	for (size_t i = 0; var && i < np; i++)
		var[i] = (float)(var[i] * (gain ? (double)gain[i] * gain[i] : 1) - vmed);
	for (int q = 0; q < n; q++)
		f[q].cal_offset = off, f[q].cal_scale = gain;
	sc->support.noise_map = var, sc->support.noise_map_w = W;
	r->cal_offset = off, r->cal_scale = gain, r->cal_noise = var;
	cJSON *o = cJSON_AddObjectToObject(r->rep, "camera_calibration");
	if (off) {
		cJSON_AddNumberToObject(o, "offset_median_adu", c0_median_of(off, np));
		if (!isnan(rho))
			cJSON_AddNumberToObject(o, "offset_pattern_correlation", rho);
	}
	if (var)
		cJSON_AddNumberToObject(o, "read_variance_median_adu2", vmed);
	if (gain)
		cJSON_AddNumberToObject(o, "gain_mean", gm);
	return C0_OK;
}
