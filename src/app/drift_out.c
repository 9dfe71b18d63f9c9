/* drift.csv and drift.png: the trajectory of stages/drift.h written out */
#include "app/drift_out.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

int c0_drift_csv(const struct c0_drift *d, double pixel_nm, char **buf, size_t *len)
{
	struct c0_drift_info in;
	c0_drift_get_info(d, &in);
	int64_t G = 0;
	for (int q = 0; q < in.stacks; q++)
		G += in.stack_frames[q];
	size_t cap = (size_t)G * 48 + 64, k = 0;
	char *b = c0_alloc(cap, 1);
	if (!b)
		return C0_ENOMEM;
	k += (size_t)snprintf(b + k, cap - k, "stack,frame,dx_nm,dy_nm\n");
	for (int q = 0; q < in.stacks; q++)
		for (int64_t t = 0; t < in.stack_frames[q]; t++) {
			double dx, dy;
			c0_drift_at(d, q, t, &dx, &dy);
			k += (size_t)snprintf(b + k, cap - k, "%d,%lld,%.2f,%.2f\n", q + 1, (long long)t + 1, dx * pixel_nm,
					      dy * pixel_nm);
		}
	*buf = b, *len = k;
	return C0_OK;
}

static void put(uint8_t *rgb, int w, int h, int x, int y, const uint8_t *c)
{
	if (x >= 0 && x < w && y >= 0 && y < h)
		memcpy(rgb + 3 * ((size_t)y * w + x), c, 3);
}

int c0_drift_plot(const struct c0_drift *d, double pixel_nm, uint8_t **rgb, int *w, int *h)
{
	const int W = 480, H = 240, m = 10;
	struct c0_drift_info in;
	c0_drift_get_info(d, &in);
	const double G = in.frames;   /* the clock's length: the plot's x axis */
	const int64_t *nt = in.stack_frames;
	uint8_t *p = c0_alloc((size_t)W * H * 3, 1);
	if (!p)
		return C0_ENOMEM;
	memset(p, 255, (size_t)W * H * 3);
	double lim = 10;   /* nm, symmetric about 0 */
	for (int q = 0; q < in.stacks; q++)
		for (int64_t t = 0; t < nt[q]; t++) {
			double dx, dy;
			c0_drift_at(d, q, t, &dx, &dy);
			lim = fmax(lim, fmax(fabs(dx), fabs(dy)) * pixel_nm * 1.1);
		}
	const uint8_t grey[3] = { 190, 190, 190 }, black[3] = { 0, 0, 0 }, red[3] = { 220, 30, 30 }, blue[3] = { 30, 60, 220 };
#define ROW(v) (H / 2 - (int)lround((v) / lim * (H / 2 - m)))
#define COL(g) (m + (int)lround((g) / (G > 1 ? G - 1 : 1) * (W - 2 * m)))
	for (double v = -floor(lim / 10) * 10; v <= lim; v += 10)
		for (int x = 0; x < m; x++)
			put(p, W, H, x, ROW(v), grey);
	for (int x = m; x < W - m; x++)
		put(p, W, H, x, H / 2, grey);
	for (int q = 0; q < in.stacks; q++)   /* where a stack began (not interleaved stacks) */
		for (int y = 0; in.start[q] >= 1 && y < H; y += 4)
			put(p, W, H, COL(in.start[q]), y, grey);
	for (int y = m; y < H - m; y++)
		put(p, W, H, m - 1, y, black);
	for (int q = 0; q < in.stacks; q++)
		for (int64_t t = 0; t < nt[q]; t++) {
			double dx, dy;
			c0_drift_at(d, q, t, &dx, &dy);
			int x = COL(in.start[q] + (double)t);
			for (int k = -1; k <= 1; k++)
				put(p, W, H, x, ROW(dx * pixel_nm) + k, red), put(p, W, H, x, ROW(dy * pixel_nm) + k, blue);
		}
#undef ROW
#undef COL
	*rgb = p, *w = W, *h = H;
	return C0_OK;
}
