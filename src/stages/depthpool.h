/* Depth pooling for 3D-COL0RME. Each angle's intensity estimate is accurate
 * in total over a PSF-sized patch, but how it splits among neighbouring
 * fine pixels is noisy and independent from angle to angle, and depth lives
 * in the ratios between angles. So the depth profile of a support pixel is
 * reconstructed from the intensities summed over a window around it (on the
 * support only), and the volume is then rescaled pixel by pixel to the
 * pixel's own intensity. On the default simulation this halves the median
 * depth error (docs/defaults.md#depth_pool_nm). */
#pragma once
#include <stddef.h>
#include <stdint.h>

/* Each mask pixel's depth (nm) from its own intensities x[q] alone: the
 * centre of the bin j whose weights W[q][j] (nq x nz, optics/tirf.h) fit
 * them best with one non-negative amplitude; 0 elsewhere (mask NULL: every
 * pixel, as on a c0_pixlist's values). */
void c0_depth_single(const double *W, int nq, int nz, double z0, double dz, const float *const *x, const uint8_t *mask,
		     size_t np, float *out);

/* The support's pixels by rows, what the run's pooling works on (the fine
 * grid holds a thousand pixels for one of them at 2048 x 2048 camera
 * pixels): pix[0..M) raster indices, increasing; those of row y at
 * row[y]..row[y + 1]. Values over the list are arrays of M, v[k] at pix[k]. */
struct c0_pixlist {
	int ny, nx;
	size_t M;
	int *pix;
	size_t *row;
};
int c0_pixlist_from_mask(const uint8_t *mask, int ny, int nx, struct c0_pixlist *pl);
void c0_pixlist_free(struct c0_pixlist *pl);
/* the index in pl of raster pixel p, or -1 when p is not on it */
long c0_pixlist_find(const struct c0_pixlist *pl, size_t p);
/* out = sum of x over the (2h+1)^2 window on the list's pixels (x and out
 * over pl). The summed-area table in a band of 2h + 2 rows: the same sums
 * as the whole grid's table (the tests' c0_pool_window), bit for bit. */
int c0_pool_window_at(const float *x, const struct c0_pixlist *pl, int h, float *out);
/* Each pixel's unit normal to the structure it lies on, (x, y) at nrm[2k],
 * nrm[2k + 1] over pl: the minor axis of the second moments of the list's
 * pixels within r fine pixels (a disc). A lone pixel or a round blob gets an
 * arbitrary one. */
void c0_pixlist_normals(const struct c0_pixlist *pl, int r, float *nrm);
/* out[q] = sum of x[q] over the (2h+1)^2 window on the list, counting only
 * the pixels whose guide depth lies within range nm of the centre's: a
 * neighbour on another structure at another depth stays out (x[q], guide
 * and out[q] over pl; the same sums in the same order as the tests'
 * whole-grid c0_pool_guided, bit for bit). With nrm (c0_pixlist_normals) only the
 * window's pixels within width fine pixels of the line through the centre
 * along its structure are summed: a strip along a filament, which keeps out
 * a neighbour beside it whatever the guide says. */
int c0_pool_guided_at(const float *const *x, int nq, const struct c0_pixlist *pl, const float *guide, double range,
		      const float *nrm, double width, int h, float *const *out);
/* A run's pooled MA-TIRF input: each angle's own and pooled intensities over
 * pl, and the pooled intensities' noise variances (nq x pl->M,
 * stages/depthfit.h; NULL: the depth fit weighs the angles alike). */
struct c0_pooled {
	const struct c0_pixlist *pl;
	const float *const *own, *const *pooled;
	const float *var;
};
/* f (nz x M: the columns at raster indices pixel[0..M) on pl, increasing,
 * stages/matirf.h) reconstructed from pooled images: each column scaled by
 * sum_q x_q / sum_q pooled_q at its pixel (x and pooled over pl), so the
 * volume keeps the pixel's own intensity (the depth profile, hence the
 * depth map, is unchanged). */
void c0_pool_rescale_at(float *f, int nz, const int *pixel, size_t M, int nq, const struct c0_pixlist *pl,
			const float *const *x, const float *const *pooled);

/* Default window of run's depth pooling, as a multiple of the PSF FWHM:
 * its length along the structure (the guided pool is a strip), long enough
 * to average the blinking's and the splitting's noise (docs/defaults.md#depth_pool_nm). */
#define C0_DEPTH_POOL_FWHM 1.75
/* The guided pool's strip: pixels within this many fine pixels of the line
 * along the structure, whose direction comes from the support's pixels
 * within C0_DEPTH_NORMAL_PX
 * (docs/defaults.md#depth_pool_nm). */
#define C0_DEPTH_POOL_WIDTH_PX 2.0
#define C0_DEPTH_NORMAL_PX 3
/* Within the window, only the pixels whose guide depth is within this many
 * nm of the centre's are summed, the guide being each pixel's single-depth
 * fit to its intensities summed over C0_DEPTH_GUIDE_FWHM: filaments 90 nm
 * apart and 100 nm apart in depth were pulled together by the plain window
 * (median depth error 29-32 nm, 15-20 guided; docs/defaults.md#depth_pool_range_nm). */
#define C0_DEPTH_POOL_RANGE_NM 50
#define C0_DEPTH_GUIDE_FWHM 0.55
