/* The tile grid of an image (DESIGN section 9). Interiors split the image
 * evenly into ceil(H/N) x ceil(W/N) blocks; each window adds `halo` pixels
 * on every side (clipped at the edges). The grid depends on the image only,
 * never on threads or processes, so results do not either. Processes take
 * contiguous runs of tile rows, so each reads one band of rows of a frame. */
#pragma once
#include <stddef.h>

struct c0_tile {
	int y0, x0, h, w;          /* window */
	int iy0, ix0, ih, iw;      /* interior (kept), inside the window */
};

struct c0_tiling {
	int nty, ntx, n;           /* tile rows, columns, count (row-major) */
	struct c0_tile *t;
};

int c0_tiling_make(int H, int W, int tile, int halo, struct c0_tiling *out);
void c0_tiling_free(struct c0_tiling *tl);
/* Process `rank` of `size`: its tiles [*k0, *k1), the rows its windows read
 * [*y0, *y1) and the rows its interiors cover [*i0, *i1) (empty when it has
 * no tile). */
void c0_tiling_share(const struct c0_tiling *tl, int rank, int size, int *k0, int *k1, int *y0, int *y1, int *i0,
		     int *i1);
/* h rows of n bytes from src to dst, rows sld and dld bytes apart: a
 * window or an interior cut from an image or pasted into one. */
void c0_tile_copy(void *dst, size_t dld, const void *src, size_t sld, int h, size_t n);
