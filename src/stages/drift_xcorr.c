/* The correlation of a block mean against a reference (drift_parts.h). */
#include "stages/drift_parts.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/fftw_plan.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void drift_xcorr_free(struct xcorr *x)
{
	c0_fftw_destroy(x->f), c0_fftw_destroy(x->b);
	if (!x->borrowed)
		free(x->win), free(x->lp), fftw_free(x->ref);
	fftw_free(x->re), fftw_free(x->sp), fftw_free(x->xs);
}

/* the transforms' buffers and plans; the window and reference are x's own
 * (share == NULL) or share's */
static int xcorr_buffers(struct xcorr *x, const struct xcorr *share)
{
	x->re = fftw_malloc((size_t)x->PH * x->PW * sizeof(double));
	x->sp = fftw_malloc(x->ns * sizeof(fftw_complex));
	x->xs = fftw_malloc(x->ns * sizeof(fftw_complex));
	if (share)
		x->win = share->win, x->lp = share->lp, x->ref = share->ref, x->borrowed = 1;
	else {
		x->win = c0_alloc((size_t)x->H * x->W, sizeof *x->win);
		x->ref = fftw_malloc(x->ns * sizeof(fftw_complex));
	}
	if (!x->win || !x->re || !x->ref || !x->sp || !x->xs)
		return c0_mem_fail((double)x->PH * x->PW * sizeof(double) + 3.0 * x->ns * sizeof(fftw_complex));
#pragma omp critical(c0_fftw_plan)
	{
		x->f = fftw_plan_dft_r2c_2d(x->PH, x->PW, x->re, x->sp, FFTW_ESTIMATE);
		x->b = fftw_plan_dft_c2r_2d(x->PH, x->PW, x->xs, x->re, FFTW_ESTIMATE);
	}
	if (!x->f || !x->b)
		return c0_fail(C0_ENOMEM, "drift: cannot plan the FFTs of %dx%d", x->W, x->H);
	return C0_OK;
}

/* The PSF's transfer function (a Gaussian of sd sigma pixels) on the
 * r2c spectrum: the image and the reference both filtered, the matched
 * filter for an image of PSF-blurred spots in white noise. The camera's
 * fixed pattern is white too, and does not move with the sample: unfiltered,
 * its own peak at lag 0 pulled the shift towards 0. */
static int xcorr_lowpass(struct xcorr *x, double sigma)
{
	if (!(sigma > 0))
		return C0_OK;
	const int nx = x->PW / 2 + 1;
	if (!(x->lp = c0_alloc(x->ns, sizeof *x->lp)))
		return C0_ENOMEM;
	const double c = -2 * C0_PI * C0_PI * sigma * sigma;
	for (int y = 0; y < x->PH; y++) {
		const double fy = (double)(y <= x->PH / 2 ? y : y - x->PH) / x->PH;
		for (int i = 0; i < nx; i++) {
			const double fx = (double)i / x->PW;
			x->lp[(size_t)y * nx + i] = exp(c * (fx * fx + fy * fy));
		}
	}
	return C0_OK;
}

int drift_xcorr_init(struct xcorr *x, int H, int W, double sigma)
{
	memset(x, 0, sizeof *x);
	/* lags to a quarter of the field, and one more for the sub-pixel fit */
	x->H = H, x->W = W, x->LY = H / 4 + 2, x->LX = W / 4 + 2;
	x->PH = c0_fft_size(H + x->LY, 5, 0), x->PW = c0_fft_size(W + x->LX, 5, 0);
	x->ns = (size_t)x->PH * (x->PW / 2 + 1);
	int st = xcorr_buffers(x, NULL);
	if (st)
		return st;
	for (int y = 0; y < H; y++)
		for (int i = 0; i < W; i++)   /* Hann */
			x->win[(size_t)y * W + i] = (0.5 - 0.5 * cos(2 * C0_PI * (y + 0.5) / H)) *
						    (0.5 - 0.5 * cos(2 * C0_PI * (i + 0.5) / W));
	return xcorr_lowpass(x, sigma);
}

/* another thread's set-up against the same reference */
int drift_xcorr_clone(struct xcorr *y, const struct xcorr *x)
{
	*y = *x;
	y->re = NULL, y->sp = y->xs = NULL, y->f = y->b = NULL;
	return xcorr_buffers(y, x);
}

/* windowed, mean-removed spectrum of img into x->sp */
void drift_spectrum(struct xcorr *x, const double *img)
{
	const size_t n = (size_t)x->H * x->W;
	double m = 0, w = 0;
	for (size_t i = 0; i < n; i++)
		m += img[i] * x->win[i], w += x->win[i];
	m /= w;
	memset(x->re, 0, (size_t)x->PH * x->PW * sizeof *x->re);
	for (int y = 0; y < x->H; y++)
		for (int i = 0; i < x->W; i++) {
			size_t k = (size_t)y * x->W + i;
			x->re[(size_t)y * x->PW + i] = (img[k] - m) * x->win[k];
		}
	fftw_execute(x->f);
	for (size_t i = 0; x->lp && i < x->ns; i++)
		x->sp[i] *= x->lp[i];
}

/* sub-pixel peak offset from three samples: Gaussian (log-parabola) when all
 * positive, else parabola */
static double peak3(double a, double b, double c)
{
	if (a > 0 && b > 0 && c > 0) {
		double la = log(a), lb = log(b), lc = log(c), den = la - 2 * lb + lc;
		if (den < 0)
			return 0.5 * (la - lc) / den;
	}
	double den = a - 2 * b + c;
	return den < 0 ? 0.5 * (a - c) / den : 0;
}

/* shift (px) of the content of img relative to the reference; img's
 * spectrum is left in x->sp. in_ref: the reference is a sum that holds img,
 * which is left out of it (spectra are linear), else img's own noise peaks
 * at lag 0 and pulls the shift towards 0 */
void drift_shift_of(struct xcorr *x, const double *img, int in_ref, double *dx, double *dy)
{
	const int H = x->PH, W = x->PW;
	drift_spectrum(x, img);
	for (size_t i = 0; i < x->ns; i++)
		x->xs[i] = x->sp[i] * conj(in_ref ? x->ref[i] - x->sp[i] : x->ref[i]);
	fftw_execute(x->b);   /* x->re: circular cross-correlation, lag (0, 0) at index 0 */
	int by = 0, bx = 0;
	double best = -INFINITY;
	for (int ly = 1 - x->LY; ly < x->LY; ly++)   /* the lags free of wrap-around, but the last */
		for (int lx = 1 - x->LX; lx < x->LX; lx++) {
			double v = x->re[(size_t)(ly < 0 ? ly + H : ly) * W + (lx < 0 ? lx + W : lx)];
			if (v > best)
				best = v, by = ly, bx = lx;
		}
#define AT(ly, lx) x->re[(size_t)(((ly) % H + H) % H) * W + (((lx) % W + W) % W)]
	*dx = bx + peak3(AT(by, bx - 1), AT(by, bx), AT(by, bx + 1));
	*dy = by + peak3(AT(by - 1, bx), AT(by, bx), AT(by + 1, bx));
#undef AT
}
