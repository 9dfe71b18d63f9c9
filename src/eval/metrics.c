#include "eval/metrics.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/order.h"

#include <math.h>
#include <stdlib.h>

struct pair { double d; int t, e; };

static int cmp_pair(const void *a, const void *b)
{
	const struct pair *p = a, *q = b;
	if (p->d != q->d)
		return p->d < q->d ? -1 : 1;
	if (p->t != q->t)          /* deterministic ties */
		return p->t < q->t ? -1 : 1;
	return (p->e > q->e) - (p->e < q->e);
}

int c0_jaccard_index(const uint8_t *est, const uint8_t *truth, int H, int W, double px,
		     double radius, int margin, struct c0_jaccard *out)
{
	if (!(px > 0 && isfinite(px)))
		return c0_fail(C0_EINVAL, "pixel_nm %g: must be a positive number of nm", px);
	if (!(radius > 0 && radius <= 1000 * px))   /* the search window is (2R+1)^2 pixels */
		return c0_fail(C0_EINVAL, "radius %g nm: must be positive and at most 1000 pixels of %g nm", radius, px);
	if (margin < 0)
		return c0_fail(C0_EINVAL, "margin %d: must be >= 0", margin);
	int R = (int)floor(radius / px);
	size_t cap = 1024, np = 0;
	struct pair *p = malloc(cap * sizeof *p);
	if (!p)
		return c0_fail(C0_ENOMEM, "jaccard: out of memory");
	int nt = 0, ne = 0;
	for (int y = margin; y < H - margin; y++)
		for (int x = margin; x < W - margin; x++) {
			ne += est[y * W + x] != 0;
			if (!truth[y * W + x])
				continue;
			nt++;
			for (int dy = -R; dy <= R; dy++)
				for (int dx = -R; dx <= R; dx++) {
					int yy = y + dy, xx = x + dx;
					double d = px * sqrt((double)(dy * dy + dx * dx));
					if (yy < margin || yy >= H - margin || xx < margin || xx >= W - margin || d > radius || !est[yy * W + xx])
						continue;
					if (np == cap) {
						struct pair *q = realloc(p, 2 * cap * sizeof *p);
						if (!q) {
							free(p);
							return c0_fail(C0_ENOMEM, "jaccard: out of memory");
						}
						p = q, cap *= 2;
					}
					p[np++] = (struct pair){ d, y * W + x, yy * W + xx };
				}
		}
	qsort(p, np, sizeof *p, cmp_pair);
	uint8_t *used = c0_alloc((size_t)H * W, 1);
	if (!used) {
		free(p);
		return C0_ENOMEM;
	}
	int tp = 0;
	for (size_t k = 0; k < np; k++)
		if (!(used[p[k].t] & 1) && !(used[p[k].e] & 2)) {
			used[p[k].t] |= 1;
			used[p[k].e] |= 2;
			tp++;
		}
	free(used), free(p);
	out->tp = tp, out->fn = nt - tp, out->fp = ne - tp;
	int den = tp + out->fn + out->fp;
	out->index = den ? (double)tp / den : 1;
	return C0_OK;
}

double c0_psnr(const float *est, const float *truth, int H, int W, int margin)
{
	double se = 0, mx = 0;
	long n = 0;
	for (int y = margin; y < H - margin; y++)
		for (int x = margin; x < W - margin; x++) {
			double d = (double)est[y * W + x] - truth[y * W + x];
			se += d * d;
			mx = fmax(mx, truth[y * W + x]);
			n++;
		}
	return n && se > 0 ? 10 * log10(mx * mx / (se / n)) : INFINITY;
}

int c0_depth_error(const float *est, int eh, int ew, const float *truth, const uint8_t *truth_mask, int th, int tw,
		   int margin, struct c0_depth_err *out)
{
	if (eh <= 0 || ew <= 0 || th % eh || tw % ew || th / eh != tw / ew)
		return c0_fail(C0_EINVAL, "depth map %dx%d does not divide the truth's %dx%d", ew, eh, tw, th);
	const int r = th / eh;
	double *e = c0_alloc((size_t)th * tw, sizeof *e), *a = c0_alloc((size_t)th * tw, sizeof *a);
	if (!e || !a) {
		free(e), free(a);
		return C0_ENOMEM;
	}
	int n = 0, nt = 0;
	double sum = 0;
	for (int y = margin; y < th - margin; y++)
		for (int x = margin; x < tw - margin; x++) {
			size_t i = (size_t)y * tw + x;
			if (truth_mask ? !truth_mask[i] : !(truth[i] > 0))
				continue;
			nt++;
			float d = est[(size_t)(y / r) * ew + x / r];
			if (!(d > 0))
				continue;
			e[n] = d - truth[i];
			a[n] = fabs(e[n]);
			sum += a[n++];
		}
	*out = (struct c0_depth_err){ n, nt, 0, 0, 0 };
	if (n) {
		out->mean = sum / n;
		out->median = c0_median(a, (size_t)n);
		out->bias = c0_median(e, (size_t)n);
	}
	free(e), free(a);
	return C0_OK;
}
