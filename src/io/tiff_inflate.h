/* Deflated strips inflated side by side: the raw strips are read in order
 * (libtiff's file access), then inflated on every thread by libdeflate.
 * The mirror of the writer's deflated strips (tiff_write.c). The reader
 * uses it only where libtiff's decoder would do nothing but inflate
 * (no predictor, the machine's byte order, one sample a pixel); a strip
 * it cannot do is left to libtiff, whose error message then names it. */
#pragma once
#include <stddef.h>
#include <stdint.h>
#include <tiffio.h>

struct c0_inflater;

/* NULL when out of memory */
struct c0_inflater *c0_inflater_new(void);
void c0_inflater_free(struct c0_inflater *z);
/* 1 when the current directory's strips can be inflated here */
int c0_inflater_applies(TIFF *tif);
/* Strips s0 .. s0 + n - 1 into out + i * stride, strip i being want[i]
 * bytes once inflated; done[i] = 1 for the strips inflated, 0 for those
 * left to libtiff (a damaged or unusual stream). C0_OK or C0_ENOMEM. */
int c0_inflate_strips(struct c0_inflater *z, TIFF *tif, uint32_t s0, int n, const size_t *want, size_t stride,
		      uint8_t *out, uint8_t *done);
