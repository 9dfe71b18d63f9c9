/* The intensity step's solve alone (stages/intensity.h, issue 55): one
 * mean image and a support, solved in tiles with mu by the relative
 * discrepancy principle as `run` does; prints wall and CPU seconds (user +
 * system), mu, solves and CG steps, and sums of x and b so that two builds
 * can be compared (the same digits when their solves are).
 *   intensity_tiles MEAN.tif SUPPORT.tif SIGMA2 [FRAMES [TILE [FWHM_NM [PIXEL_NM]]]]
 *   (default 500 frames, tiles of 256 camera pixels, 229 nm, 100 nm) */
#include "stages/intensity.h"
#include "core/clock.h"
#include "io/tiff.h"

#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
	if (argc < 4) {
		fprintf(stderr, "usage: intensity_tiles MEAN.tif SUPPORT.tif SIGMA2 [FRAMES [TILE [FWHM_NM [PIXEL_NM]]]]\n");
		return 1;
	}
	struct c0_tiff_info im, sm;
	float *mean = NULL, *sup = NULL;
	if (c0_tiff_load_f32(argv[1], &im, &mean) || c0_tiff_load_f32(argv[2], &sm, &sup)) {
		fprintf(stderr, "intensity_tiles: cannot read %s or %s\n", argv[1], argv[2]);
		return 1;
	}
	struct c0_intensity_conf c = C0_INTENSITY_DEFAULTS;
	c.grid.fwhm_nm = argc > 6 ? atof(argv[6]) : 229, c.grid.pixel_nm = argc > 7 ? atof(argv[7]) : 100;
	c.tile = argc > 5 ? atoi(argv[5]) : 256;
	const int H = (int)im.height, W = (int)im.width, r = c.grid.srf;
	if ((int)sm.height != H * r || (int)sm.width != W * r) {
		fprintf(stderr, "intensity_tiles: the support is not %d times the mean's size\n", r);
		return 1;
	}
	double *y = malloc((size_t)H * W * sizeof *y);
	uint8_t *mask = malloc((size_t)H * W * r * r);
	for (size_t p = 0; y && p < (size_t)H * W; p++)
		y[p] = mean[p];
	for (size_t p = 0; mask && p < (size_t)H * W * r * r; p++)
		mask[p] = sup[p] != 0;
	struct c0_intensity_result res;
	const double w0 = c0_now(), c0 = c0_cpu_seconds();
	int st = y && mask ? c0_intensity_solve(&c, y, H, W, argc > 4 ? atoll(argv[4]) : 500, mask, atof(argv[3]), &res) : 1;
	const double dw = c0_now() - w0, dc = c0_cpu_seconds() - c0;
	if (st) {
		fprintf(stderr, "intensity_tiles: solve failed (%d)\n", st);
		return 1;
	}
	double sx = 0, sb = 0;
	for (size_t p = 0; p < (size_t)H * W * r * r; p++)
		sx += res.x[p];
	for (size_t p = 0; p < (size_t)H * W; p++)
		sb += res.b[p];
	printf("%dx%d, %d tiles: wall %.2f s, CPU %.2f s; mu %.17g, %d solves, %d CG steps; sum x %.17g, sum b %.17g\n", W, H,
	       res.tiles, dw, dc, res.mu, res.solves, res.cg_iters, sx, sb);
	c0_intensity_result_free(&res);
	free(y), free(mask), free(mean), free(sup);
	return 0;
}
