#include "ops/blur2.h"
#include "core/c0math.h"

/* Both passes add one tap at a time along a contiguous row (x fastest), so
 * that the inner loops vectorise; the taps go in the same order (d rising)
 * as a per-pixel sum would, so the sums are the same. */

/* row y along x into work (k: the kernel's centre) */
C0_HOT_SAME static void pass_x(const float *ar, float *wr, int nx, const float *k, int r)
{
	for (int x = 0; x < nx; x++)
		wr[x] = 0;
	for (int d = -r; d <= r; d++) {
		const int x0 = d < 0 ? -d : 0, x1 = d > 0 ? nx - d : nx;
		const float kd = k[d];
		for (int x = x0; x < x1; x++)
			wr[x] += kd * ar[x + d];
	}
}

/* row y along y from work back into the image */
C0_HOT_SAME static void pass_y(const float *w, float *ar, int y, int ny, int nx, const float *k, int r)
{
	const int d0 = y - r < 0 ? -y : -r, d1 = y + r >= ny ? ny - 1 - y : r;
	for (int x = 0; x < nx; x++)
		ar[x] = 0;
	for (int d = d0; d <= d1; d++) {
		const float kd = k[d], *wr = w + (size_t)(y + d) * nx;
		for (int x = 0; x < nx; x++)
			ar[x] += kd * wr[x];
	}
}

void c0_blur2_apply(const struct c0_blur2 *b, float *img, int n)
{
	const int ny = b->ny, nx = b->nx, r = b->r;
	const float *k = b->k + r;
	for (int m = 0; m < n; m++) {
		float *a = img + (size_t)m * ny * nx, *w = b->work;
#pragma omp parallel for schedule(static) if ((size_t)ny * nx > 50000)
		for (int y = 0; y < ny; y++)
			pass_x(a + (size_t)y * nx, w + (size_t)y * nx, nx, k, r);
#pragma omp parallel for schedule(static) if ((size_t)ny * nx > 50000)
		for (int y = 0; y < ny; y++)
			pass_y(w, a + (size_t)y * nx, y, ny, nx, k, r);
	}
}
