#include "io/tiff_inflate.h"
#include "core/err.h"
#include "core/mem.h"

#include <libdeflate.h>
#include <omp.h>
#include <stdlib.h>

struct c0_inflater {
	int nd;                                 /* decompressors: one a thread */
	struct libdeflate_decompressor **d;
	uint8_t *raw;                           /* the raw strips, one after another */
	size_t rawsize;
	size_t *at, *len;                       /* each strip's place in raw and its length */
	int cap;                                /* strips at and len hold */
};

struct c0_inflater *c0_inflater_new(void)
{
	struct c0_inflater *z = c0_alloc(1, sizeof *z);
	if (!z)
		return NULL;
	z->nd = omp_get_max_threads();
	z->d = c0_alloc((size_t)z->nd, sizeof *z->d);
	for (int i = 0; z->d && i < z->nd; i++)
		if (!(z->d[i] = libdeflate_alloc_decompressor())) {
			z->nd = i;
			break;
		}
	if (!z->d || z->nd < 1) {
		c0_inflater_free(z);
		return NULL;
	}
	return z;
}

void c0_inflater_free(struct c0_inflater *z)
{
	for (int i = 0; z && z->d && i < z->nd; i++)
		libdeflate_free_decompressor(z->d[i]);
	if (z)
		free(z->d), free(z->raw), free(z->at), free(z->len);
	free(z);
}

int c0_inflater_applies(TIFF *tif)
{
	uint16_t comp = COMPRESSION_NONE, pred = PREDICTOR_NONE, fill = FILLORDER_MSB2LSB, bps = 8;
	TIFFGetFieldDefaulted(tif, TIFFTAG_COMPRESSION, &comp);
	TIFFGetFieldDefaulted(tif, TIFFTAG_PREDICTOR, &pred);
	TIFFGetFieldDefaulted(tif, TIFFTAG_FILLORDER, &fill);
	TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &bps);
	return (comp == COMPRESSION_ADOBE_DEFLATE || comp == COMPRESSION_DEFLATE) && pred == PREDICTOR_NONE &&
	       fill == FILLORDER_MSB2LSB && !TIFFIsTiled(tif) && (bps == 8 || !TIFFIsByteSwapped(tif));
}

/* room for the raw strips: a deflated strip is at most a few bytes a
 * 64 KiB block longer than its data; a longer one is left to libtiff */
static size_t raw_cap(size_t want)
{
	return want + want / 16 + 1024;
}

static int reserve(struct c0_inflater *z, int n, size_t bytes)
{
	if (n > z->cap) {
		free(z->at), free(z->len);
		z->at = c0_alloc((size_t)n, sizeof *z->at), z->len = c0_alloc((size_t)n, sizeof *z->len);
		z->cap = z->at && z->len ? n : 0;
		if (!z->cap)
			return C0_ENOMEM;
	}
	if (bytes > z->rawsize) {
		free(z->raw);
		z->raw = c0_alloc(bytes, 1);
		z->rawsize = z->raw ? bytes : 0;
		if (!z->raw)
			return C0_ENOMEM;
	}
	return C0_OK;
}

int c0_inflate_strips(struct c0_inflater *z, TIFF *tif, uint32_t s0, int n, const size_t *want, size_t stride,
		      uint8_t *out, uint8_t *done)
{
	size_t bytes = 0;
	for (int i = 0; i < n; i++)
		bytes += raw_cap(want[i]);
	int st = reserve(z, n, bytes);
	if (st)
		return st;
	/* the file in order, on this thread */
	size_t at = 0;
	for (int i = 0; i < n; i++) {
		const uint64_t bc = TIFFGetStrileByteCount(tif, s0 + (uint32_t)i);
		z->at[i] = at, z->len[i] = 0;
		if (bc > 0 && bc <= raw_cap(want[i]) &&
		    TIFFReadRawStrip(tif, s0 + (uint32_t)i, z->raw + at, (tmsize_t)bc) == (tmsize_t)bc)
			z->len[i] = (size_t)bc;
		at += raw_cap(want[i]);
	}
#pragma omp parallel for schedule(dynamic, 1) num_threads(z->nd) if (n > 1)
	for (int i = 0; i < n; i++)
		done[i] = z->len[i] && libdeflate_zlib_decompress(z->d[omp_get_thread_num()], z->raw + z->at[i], z->len[i],
								   out + (size_t)i * stride, want[i], NULL) == LIBDEFLATE_SUCCESS;
	return C0_OK;
}
