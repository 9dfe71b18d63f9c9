/* A dense MA-TIRF test object for the benchmark: every pixel of an N x N
 * field carries fluorophores at one depth, a smooth landscape between 40
 * and 280 nm with a smooth brightness, imaged at the given angles with the
 * library's own TIRF model (bin-integrated, as the solver sees it) and
 * Gaussian noise of the given relative size.
 *   matirf_phantom OUTDIR N NOISE ANGLE...
 * writes OUTDIR/img_qNN.tif (float32) and OUTDIR/truth_depth.tif (nm). */
#include "optics/tirf.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/rng.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
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
		}
	char path[4096];
	struct c0_tiff_wopts o = { .width = n, .height = n, .dtype = C0_F32, .pixel_size_nm = 100 };
	for (int q = 0; q < nq; q++) {
		for (int i = 0; i < n * n; i++)
			img[i] = (float)(amp[i] * W[q * nz + (int)depth[i]] * (1 + noise * c0_rng_normal(&rng)));
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
	free(depth), free(img), free(amp);
	return 0;
}
