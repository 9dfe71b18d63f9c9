#include "core/tiles.h"
#include "core/err.h"
#include "core/mem.h"

#include <stdlib.h>
#include <string.h>

/* boundaries of n near-equal parts of [0, len) */
static int cut(int len, int n, int k) { return (int)((long long)len * k / n); }

int c0_tiling_make(int H, int W, int tile, int halo, struct c0_tiling *out)
{
	memset(out, 0, sizeof *out);
	if (tile < 1 || halo < 0)
		return c0_fail(C0_EINVAL, "tiles: invalid size %d or overlap %d", tile, halo);
	out->nty = (H + tile - 1) / tile, out->ntx = (W + tile - 1) / tile;
	out->n = out->nty * out->ntx;
	if (!(out->t = c0_alloc((size_t)out->n, sizeof *out->t)))
		return C0_ENOMEM;
	for (int a = 0; a < out->nty; a++)
		for (int b = 0; b < out->ntx; b++) {
			struct c0_tile *t = &out->t[a * out->ntx + b];
			int y0 = cut(H, out->nty, a), y1 = cut(H, out->nty, a + 1);
			int x0 = cut(W, out->ntx, b), x1 = cut(W, out->ntx, b + 1);
			t->y0 = y0 - halo > 0 ? y0 - halo : 0, t->x0 = x0 - halo > 0 ? x0 - halo : 0;
			t->h = (y1 + halo < H ? y1 + halo : H) - t->y0, t->w = (x1 + halo < W ? x1 + halo : W) - t->x0;
			t->iy0 = y0, t->ix0 = x0, t->ih = y1 - y0, t->iw = x1 - x0;
		}
	return C0_OK;
}

void c0_tiling_free(struct c0_tiling *tl)
{
	free(tl->t);
	memset(tl, 0, sizeof *tl);
}

void c0_tiling_share(const struct c0_tiling *tl, int rank, int size, int *k0, int *k1, int *y0, int *y1, int *i0,
		     int *i1)
{
	int r0 = cut(tl->nty, size, rank), r1 = cut(tl->nty, size, rank + 1);
	*k0 = r0 * tl->ntx, *k1 = r1 * tl->ntx;
	*y0 = *y1 = *i0 = *i1 = 0;
	if (r0 == r1)
		return;
	const struct c0_tile *a = &tl->t[*k0], *b = &tl->t[*k1 - 1];
	*y0 = a->y0, *y1 = b->y0 + b->h, *i0 = a->iy0, *i1 = b->iy0 + b->ih;
}

void c0_tile_copy(void *dst, size_t dld, const void *src, size_t sld, int h, size_t n)
{
	for (int y = 0; y < h; y++)
		memcpy((char *)dst + (size_t)y * dld, (const char *)src + (size_t)y * sld, n);
}
