#include "optics/psffit.h"
#include "optics/psf.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>

struct fitctx { const float *img; int w, h; double *gx, *gy; double A, b; };

/* residual sum of squares for centre (cx, cy) and width s, with the
 * amplitude and background solved in closed form (linear least squares) */
static double rss(struct fitctx *f, double cx, double cy, double s)
{
	c0_psf_pixel_weights(cx, s, 0, f->w, f->gx);
	c0_psf_pixel_weights(cy, s, 0, f->h, f->gy);
	double sg = 0, sgg = 0, sy = 0, sgy = 0, syy = 0, n = (double)f->w * f->h;
	for (int y = 0; y < f->h; y++)
		for (int x = 0; x < f->w; x++) {
			double g = f->gy[y] * f->gx[x], v = f->img[(size_t)y * f->w + x];
			sg += g, sgg += g * g, sy += v, sgy += g * v, syy += v * v;
		}
	double det = n * sgg - sg * sg;
	f->A = det > 0 ? (n * sgy - sg * sy) / det : 0;
	f->b = (sy - f->A * sg) / n;
	return syy - 2 * f->A * sgy - 2 * f->b * sy + f->A * f->A * sgg + 2 * f->A * f->b * sg + f->b * f->b * n;
}

/* golden-section minimum of rss along one parameter in [lo, hi] */
static double golden(struct fitctx *f, double *p, double lo, double hi, double *cx, double *cy, double *s)
{
	const double g = (sqrt(5) - 1) / 2;
	double a = lo, b = hi, c = b - g * (b - a), d = a + g * (b - a), fc, fd;
	*p = c, fc = rss(f, *cx, *cy, *s);
	*p = d, fd = rss(f, *cx, *cy, *s);
	for (int it = 0; it < 60 && b - a > 1e-6; it++) {
		if (fc < fd)
			b = d, d = c, fd = fc, c = b - g * (b - a), *p = c, fc = rss(f, *cx, *cy, *s);
		else
			a = c, c = d, fc = fd, d = a + g * (b - a), *p = d, fd = rss(f, *cx, *cy, *s);
	}
	*p = (a + b) / 2;
	return rss(f, *cx, *cy, *s);
}

static int cmpf(const void *a, const void *b)
{
	float x = *(const float *)a, y = *(const float *)b;
	return (x > y) - (x < y);
}

int c0_psf_fit_image(const float *img, int w, int h, const char *name, struct c0_psf_fit *out)
{
	if (w < 5 || h < 5)
		return c0_fail(C0_EINVAL, "psf_image %s: %dx%d pixels; need at least 5x5 around the bead", name, w, h);
	/* start: the brightest pixel, the median as background, the width from the area above half maximum */
	size_t n = (size_t)w * h, imax = 0;
	float *sorted = c0_alloc(n, sizeof *sorted);
	if (!sorted)
		return C0_ENOMEM;
	for (size_t i = 0; i < n; i++) {
		sorted[i] = img[i];
		if (img[i] > img[imax])
			imax = i;
	}
	qsort(sorted, n, sizeof *sorted, cmpf);
	const double med = sorted[n / 2];
	free(sorted);
	const double peak = img[imax] - med;
	if (!(peak > 0))
		return c0_fail(C0_EINVAL, "psf_image %s: no peak above the background", name);
	int above = 0;
	for (size_t i = 0; i < n; i++)
		above += img[i] - med > peak / 2;
	double s = fmax(0.5, sqrt(above / 3.14159265358979) / 1.1774), cx = (double)(imax % w) + 0.5, cy = (double)(imax / w) + 0.5;
	struct fitctx f = { img, w, h, c0_alloc((size_t)w, sizeof(double)), c0_alloc((size_t)h, sizeof(double)), 0, 0 };
	if (!f.gx || !f.gy) {
		free(f.gx), free(f.gy);
		return C0_ENOMEM;
	}
	double r = 0;
	for (int round = 0; round < 6; round++) {
		golden(&f, &cx, cx - 1, cx + 1, &cx, &cy, &s);
		golden(&f, &cy, cy - 1, cy + 1, &cx, &cy, &s);
		r = golden(&f, &s, fmax(0.2, s / 2), s * 2, &cx, &cy, &s);
	}
	*out = (struct c0_psf_fit){ .sigma_px = s, .fwhm_px = 2 * sqrt(2 * log(2)) * s, .cx = cx, .cy = cy,
				    .amplitude = f.A, .background = f.b };
	/* the fitted Gaussian's peak pixel value */
	double gpk = f.A * f.gx[(int)fmin(fmax(cx, 0), w - 1)] * f.gy[(int)fmin(fmax(cy, 0), h - 1)];
	out->rel_rms = gpk > 0 ? sqrt(fmax(r, 0) / (double)n) / gpk : INFINITY;
	free(f.gx), free(f.gy);
	if (!(f.A > 0) || s > fmin(w, h) / 2.0)
		return c0_fail(C0_EINVAL, "psf_image %s: no Gaussian spot fits (width %.2f px in a %dx%d image); crop the image around one bead",
			       name, s, w, h);
	return C0_OK;
}
