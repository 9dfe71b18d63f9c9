/* A dense MA-TIRF test object for the benchmark: every pixel of an N x N
 * field carries fluorophores at one depth, a smooth landscape between 40
 * and 280 nm with a smooth brightness, imaged at the given angles with the
 * library's own TIRF model (bin-integrated, as the solver sees it) and
 * Gaussian noise of the given relative size; with --blur, each angle's image
 * blurred by a Gaussian PSF of that FWHM (nm, 100 nm pixels) before the
 * noise, and the brightness dimmed to a fifth outside a grid of 3-pixel
 * lines every 8 pixels, fine detail that the blur takes away.
 *   matirf_phantom [--blur FWHM_NM] OUTDIR N NOISE ANGLE...
 * writes OUTDIR/img_qNN.tif (float32), OUTDIR/truth_depth.tif (nm) and
 * OUTDIR/truth_brightness.tif (the sum over depth of the true volume, in the
 * images' units at W = 1). */
#include "optics/tirf.h"
#include "optics/psf.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/rng.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* img blurred in place by the separable kernel k[-r..r], zero outside */
static void blur(float *img, int n, const double *k, int r)
{
	double *t = calloc((size_t)n * n, sizeof *t);
	for (int y = 0; y < n; y++)
		for (int x = 0; x < n; x++)
			for (int d = -r; d <= r; d++)
				if (x + d >= 0 && x + d < n)
					t[y * n + x] += k[r + d] * img[y * n + x + d];
	for (int y = 0; y < n; y++)
		for (int x = 0; x < n; x++) {
			double s = 0;
			for (int d = -r; d <= r; d++)
				if (y + d >= 0 && y + d < n)
					s += k[r + d] * t[(y + d) * n + x];
			img[y * n + x] = (float)s;
		}
	free(t);
}

int main(int argc, char **argv)
{
	double fwhm = 0;
	if (argc > 2 && !strcmp(argv[1], "--blur"))
		fwhm = atof(argv[2]), argv += 2, argc -= 2;
	if (argc < 6) {
		fprintf(stderr, "usage: matirf_phantom OUTDIR N NOISE ANGLE ANGLE...\n");
		return 2;
	}
	const int n = atoi(argv[2]), nq = argc - 4, nz = 400;
	const double noise = atof(argv[3]);
	double ang[64], W[64 * 400];
	struct c0_tirf t = C0_TIRF_DEFAULTS;
	if (n < 8 || nq > 64) {
		fprintf(stderr, "matirf_phantom: N >= 8 and at most 64 angles\n");
		return 2;
	}
	for (int q = 0; q < nq; q++)
		ang[q] = atof(argv[4 + q]);
	/* 1 nm bins: the weights at the true depth */
	if (c0_tirf_weights(&t, nq, ang, NULL, nz, 0, 1, W)) {
		fprintf(stderr, "matirf_phantom: %s\n", c0_errmsg());
		return 1;
	}
	float *depth = malloc(sizeof(float) * n * n), *img = malloc(sizeof(float) * n * n);
	double *amp = malloc(sizeof(double) * n * n);
	struct c0_rng rng;
	c0_rng_init(&rng, 1, 0);
	for (int y = 0; y < n; y++)
		for (int x = 0; x < n; x++) {
			double u = 6.283185307179586 * x / n, v = 6.283185307179586 * y / n;
			depth[y * n + x] = (float)(160 + 80 * sin(2 * u + 0.5) * cos(3 * v) + 40 * sin(5 * (u + v)));
			amp[y * n + x] = 1000 * (1 + 0.5 * cos(3 * u - 2 * v));
			if (fwhm > 0 && x % 8 >= 3 && y % 8 >= 3)
				amp[y * n + x] *= 0.2;
		}
	double k[129];
	const double sigma = fwhm > 0 ? c0_psf_sigma_px(fwhm, 100) : 0;
	const int r = fwhm > 0 ? (int)ceil(C0_PSF_CUTOFF * sigma) : 0;
	if (r > 64) {
		fprintf(stderr, "matirf_phantom: --blur %g: too wide\n", fwhm);
		return 2;
	}
	if (fwhm > 0)
		c0_psf_pixel_weights(0.5, sigma, -r, 2 * r + 1, k);
	char path[4096];
	struct c0_tiff_wopts o = { .width = n, .height = n, .dtype = C0_F32, .pixel_size_nm = 100 };
	for (int q = 0; q < nq; q++) {
		for (int i = 0; i < n * n; i++)
			img[i] = (float)(amp[i] * W[q * nz + (int)depth[i]] * (fwhm > 0 ? 1 : 1 + noise * c0_rng_normal(&rng)));
		if (fwhm > 0) {       /* the noise after the blur */
			blur(img, n, k, r);
			for (int i = 0; i < n * n; i++)
				img[i] = (float)(img[i] * (1 + noise * c0_rng_normal(&rng)));
		}
		snprintf(path, sizeof path, "%s/img_q%02d.tif", argv[1], q + 1);
		if (c0_tiff_save_f32(path, &o, img)) {
			fprintf(stderr, "matirf_phantom: %s\n", c0_errmsg());
			return 1;
		}
	}
	snprintf(path, sizeof path, "%s/truth_depth.tif", argv[1]);
	if (c0_tiff_save_f32(path, &o, depth)) {
		fprintf(stderr, "matirf_phantom: %s\n", c0_errmsg());
		return 1;
	}
	for (int i = 0; i < n * n; i++)
		img[i] = (float)amp[i];
	snprintf(path, sizeof path, "%s/truth_brightness.tif", argv[1]);
	if (c0_tiff_save_f32(path, &o, img)) {
		fprintf(stderr, "matirf_phantom: %s\n", c0_errmsg());
		return 1;
	}
	free(depth), free(img), free(amp);
	return 0;
}
