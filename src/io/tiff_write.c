/* ImageJ-hyperstack TIFF writer (uint8, uint16, float32), one strip per
 * plane where it fits, BigTIFF past 4 GiB, temporary name until commit.
 * ImageJ lays a hyperstack out as every directory, then the planes' data
 * back to back, and its readers (ImageJ, tifffile) read the planes from the
 * first one's offset. libtiff appends each plane's directory after its data,
 * so the directories are written first with their strip arrays deferred,
 * and the planes are appended in order after them. */
#define _POSIX_C_SOURCE 200809L
#include "io/tiff.h"
#include "io/imagej.h"
#include "io/atomic.h"
#include "core/err.h"
#include "core/mem.h"

#include <errno.h>
#include <libdeflate.h>
#include <math.h>
#include <omp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <tiffio.h>

struct c0_tiff_writer {
	TIFF *tif;
	struct c0_tiff_wopts o;
	char path[4096], tmp[4096];
	char tiffmsg[256];
	char desc[1024];
	int64_t planes, written;
	uint8_t *buf;
	struct deflated *z;      /* deflate's compressors and buffers, made on the first plane */
};

static int on_error(TIFF *tif, void *ud, const char *module, const char *fmt, va_list ap)
{
	(void)tif, (void)module;
	struct c0_tiff_writer *w = ud;
	vsnprintf(w->tiffmsg, sizeof w->tiffmsg, fmt, ap);
	return 1;
}

int64_t c0_tiff_planes(const struct c0_tiff_wopts *o)
{
	return (int64_t)(o->channels > 0 ? o->channels : 1) * (o->slices > 0 ? o->slices : 1) * (o->frames > 0 ? o->frames : 1);
}

int64_t c0_tiff_raw_bytes(const struct c0_tiff_wopts *o)
{
	return c0_tiff_planes(o) * o->width * o->height * (int64_t)c0_dtype_size(o->dtype);
}

int c0_tiff_needs_bigtiff(int64_t data_bytes)
{
	/* keep ~1 % headroom for directories and tags under the 4 GiB offset limit */
	return data_bytes > (int64_t)(4294967296.0 * 0.99);
}

/* The tags of plane p (the description and software on the first). */
static void set_tags(struct c0_tiff_writer *w, int64_t p)
{
	const struct c0_tiff_wopts *o = &w->o;
	TIFF *t = w->tif;
	const uint16_t bps = (uint16_t)(8 * c0_dtype_size(o->dtype));
	TIFFSetField(t, TIFFTAG_SUBFILETYPE, 0);
	TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)o->width);
	TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)o->height);
	TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, bps);
	TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
	TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, o->dtype == C0_F32 ? SAMPLEFORMAT_IEEEFP : SAMPLEFORMAT_UINT);
	TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
	TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
	TIFFSetField(t, TIFFTAG_COMPRESSION, o->deflate ? COMPRESSION_ADOBE_DEFLATE : COMPRESSION_NONE);
	size_t plane_bytes = (size_t)o->width * o->height * (bps / 8), row = (size_t)o->width * (bps / 8);
	uint32_t rps = plane_bytes <= (64u << 20) ? (uint32_t)o->height : TIFFDefaultStripSize(t, 0);
	if (o->deflate)   /* strips of about 1 MiB: a reader of a few rows inflates little */
		rps = (uint32_t)((1u << 20) / row > 0 ? ((1u << 20) / row < (size_t)o->height ? (1u << 20) / row : (size_t)o->height) : 1);
	TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, rps);
	if (o->pixel_size_nm > 0) {
		float res = (float)(1000.0 / o->pixel_size_nm);   /* pixels per µm */
		TIFFSetField(t, TIFFTAG_XRESOLUTION, res);
		TIFFSetField(t, TIFFTAG_YRESOLUTION, res);
		TIFFSetField(t, TIFFTAG_RESOLUTIONUNIT, RESUNIT_NONE);
	}
	if (p == 0) {
		TIFFSetField(t, TIFFTAG_IMAGEDESCRIPTION, w->desc);
		if (o->software)
			TIFFSetField(t, TIFFTAG_SOFTWARE, o->software);
	}
}

int c0_tiff_create(const char *path, const struct c0_tiff_wopts *o, struct c0_tiff_writer **out)
{
	*out = NULL;
	if (o->width <= 0 || o->height <= 0 || o->width > UINT32_MAX || o->height > UINT32_MAX)
		return c0_fail(C0_EINVAL, "%s: invalid image size %lldx%lld", path, (long long)o->width, (long long)o->height);
	if (o->dtype != C0_U8 && o->dtype != C0_U16 && o->dtype != C0_F32)
		return c0_fail(C0_EINVAL, "%s: can write uint8, uint16 or float32, not %s", path, c0_dtype_name(o->dtype));
	struct c0_tiff_writer *w = c0_alloc(1, sizeof *w);
	if (!w)
		return C0_ENOMEM;
	w->o = *o;
	if (w->o.channels <= 0) w->o.channels = 1;
	if (w->o.slices <= 0) w->o.slices = 1;
	if (w->o.frames <= 0) w->o.frames = 1;
	w->planes = c0_tiff_planes(o);
	snprintf(w->path, sizeof w->path, "%s", path);
	c0_tmp_name(path, w->tmp, sizeof w->tmp);
	int64_t bytes = c0_tiff_raw_bytes(o);
	int big = o->bigtiff || c0_tiff_needs_bigtiff(o->deflate && o->max_bytes > 0 ? o->max_bytes : bytes);
	int dl = c0_ij_format(w->desc, sizeof w->desc, w->o.channels, w->o.slices, w->o.frames, o->pixel_size_nm > 0,
			      o->z_spacing_nm / 1000, o->frame_interval_s, o->display_min, o->display_max);
	/* ImageJ's z origin is in slices: slice k is at (k - zorigin) * spacing */
	if (dl >= 0 && o->z_origin_nm != 0 && o->z_spacing_nm > 0)
		dl = c0_ij_append(w->desc, sizeof w->desc, dl, "zorigin", -o->z_origin_nm / o->z_spacing_nm);
	if (dl < 0) {
		free(w);
		return c0_fail(C0_EINVAL, "%s: metadata too long", path);
	}
	w->buf = c0_alloc((size_t)o->width * o->height, c0_dtype_size(o->dtype));
	TIFFOpenOptions *oo = TIFFOpenOptionsAlloc();
	if (!w->buf || !oo) {
		free(w->buf);
		free(w);
		TIFFOpenOptionsFree(oo);
		return C0_ENOMEM;
	}
	TIFFOpenOptionsSetErrorHandlerExtR(oo, on_error, w);
	TIFFOpenOptionsSetWarningHandlerExtR(oo, on_error, w);
	errno = 0;
	w->tif = TIFFOpenExt(w->tmp, big ? "w8" : "w", oo);
	int err = errno, ok = w->tif != NULL;
	for (int64_t p = 0; ok && p < w->planes; p++) {
		set_tags(w, p);
		ok = TIFFDeferStrileArrayWriting(w->tif) && TIFFWriteCheck(w->tif, 0, "c0_tiff_create") && TIFFWriteDirectory(w->tif);
	}
	if (ok) {
		TIFFClose(w->tif);
		w->tif = TIFFOpenExt(w->tmp, "r+", oo);
		ok = w->tif != NULL;
	}
	err = ok ? 0 : err ? err : errno;
	TIFFOpenOptionsFree(oo);
	if (!ok) {
		int st = c0_fail(C0_EIO, "%s: cannot create (%s%s%s)", path, w->tiffmsg, err ? ": " : "", err ? strerror(err) : "");
		if (w->tif)
			TIFFClose(w->tif);
		remove(w->tmp);
		free(w->buf);
		free(w);
		return st;
	}
	*out = w;
	return C0_OK;
}

static void convert_plane(const struct c0_tiff_wopts *o, const float *src, uint8_t *dst)
{
	size_t n = (size_t)o->width * o->height;
	if (o->dtype == C0_F32) {
		memcpy(dst, src, n * sizeof(float));
		return;
	}
	double hi = o->dtype == C0_U8 ? 255 : 65535;
	for (size_t i = 0; i < n; i++) {
		double v = src[i];
		v = v != v ? 0 : v < 0 ? 0 : v > hi ? hi : v;   /* NaN -> 0, clamp */
		uint32_t q = (uint32_t)lrint(v);
		if (o->dtype == C0_U8)
			dst[i] = (uint8_t)q;
		else
			((uint16_t *)(void *)dst)[i] = (uint16_t)q;
	}
}

/* libtiff's message, and the system's reason when there is one (ENOSPC) */
static int write_error(struct c0_tiff_writer *w, int err)
{
	return c0_fail(C0_EIO, "%s: write failed at plane %lld (%s%s%s)", w->path, (long long)w->written + 1, w->tiffmsg,
		       err && w->tiffmsg[0] ? ": " : "", err ? strerror(err) : "");
}

/* An output with NaN or infinity is never written: it would look like a
 * result. The message names the file (not its staging directory). */
static int check_finite(const struct c0_tiff_writer *w, const float *plane)
{
	const size_t n = (size_t)w->o.width * w->o.height;
	size_t bad = n;
	for (size_t i = 0; i < n; i++)
		if (!isfinite(plane[i])) {
			bad = i;
			break;
		}
	if (bad == n)
		return C0_OK;
	const char *base = strrchr(w->path, '/');
	return c0_fail(C0_EINVAL, "%s: plane %lld, pixel (x %lld, y %lld) is %s: not written (the computation overflowed; "
		       "check the input for extreme values)", base ? base + 1 : w->path, (long long)w->written + 1,
		       (long long)(bad % w->o.width), (long long)(bad / w->o.width), isnan(plane[bad]) ? "NaN" : "infinite");
}

/* A plane's strips deflated side by side and written raw, in order (libtiff's
 * codec is not used). Level 1, the fastest: a mostly-zero volume at 1024^2 x
 * 20 bins 9.1 -> 4.8 s against the default level, 2.85 -> 3.31 MB. For a
 * whole strip at ZIPQUALITY 1 libtiff's codec makes one call to
 * libdeflate_zlib_compress at level 1 (tif_zip.c), so these are the bytes
 * libtiff would write, a strip at a time on one thread: there a 4096^2 x 20
 * mostly empty volume took 5 s, most of the writing (docs/speed.md). */
enum { Z_BATCH = 16 };   /* strips compressed before they are written */
struct deflated {
	int nz;                            /* compressors: one a thread */
	struct libdeflate_compressor **c;
	size_t cap;                        /* bytes a strip's output may take */
	uint8_t *out;                      /* Z_BATCH x cap */
	size_t len[Z_BATCH];
};

static void deflated_free(struct deflated *z)
{
	for (int i = 0; z && i < z->nz; i++)
		libdeflate_free_compressor(z->c[i]);
	if (z)
		free(z->c), free(z->out);
	free(z);
}

static struct deflated *deflated_new(size_t strip)
{
	struct deflated *z = c0_alloc(1, sizeof *z);
	if (!z)
		return NULL;
	z->nz = omp_get_max_threads();
	z->c = c0_alloc((size_t)z->nz, sizeof *z->c);
	for (int i = 0; z->c && i < z->nz; i++)
		if (!(z->c[i] = libdeflate_alloc_compressor(1))) {
			z->nz = i;
			break;
		}
	if (!z->c || z->nz < 1 || !(z->out = c0_alloc(Z_BATCH, z->cap = libdeflate_zlib_compress_bound(z->c[0], strip)))) {
		deflated_free(z);
		return NULL;
	}
	return z;
}

static int write_deflated(struct c0_tiff_writer *w, uint32_t rps, size_t row)
{
	TIFF *t = w->tif;
	const int64_t H = w->o.height;
	if (!w->z && !(w->z = deflated_new((size_t)rps * row)))
		return C0_ENOMEM;
	struct deflated *z = w->z;
	for (int64_t y0 = 0; y0 < H; y0 += (int64_t)rps * Z_BATCH) {
		const int nb = (int)((H - y0 + rps - 1) / rps < Z_BATCH ? (H - y0 + rps - 1) / rps : Z_BATCH);
#pragma omp parallel for schedule(dynamic, 1) num_threads(z->nz) if (nb > 1)
		for (int b = 0; b < nb; b++) {
			const int64_t y = y0 + (int64_t)b * rps, ny = H - y < rps ? H - y : rps;
			z->len[b] = libdeflate_zlib_compress(z->c[omp_get_thread_num()], w->buf + (size_t)y * row,
							     (size_t)ny * row, z->out + (size_t)b * z->cap, z->cap);
		}
		errno = 0;
		for (int b = 0; b < nb; b++) {
			const uint32_t s = TIFFComputeStrip(t, (uint32_t)(y0 + (int64_t)b * rps), 0);
			if (!z->len[b])   /* the output's bound was its room: not expected */
				return c0_fail(C0_EIO, "%s: deflate failed at plane %lld", w->path, (long long)w->written + 1);
			if (TIFFWriteRawStrip(t, s, z->out + (size_t)b * z->cap, (tmsize_t)z->len[b]) < 0)
				return write_error(w, errno);
		}
	}
	return C0_OK;
}

int c0_tiff_write_plane(struct c0_tiff_writer *w, const float *plane)
{
	const struct c0_tiff_wopts *o = &w->o;
	if (w->written >= w->planes)
		return c0_fail(C0_EINVAL, "%s: more planes than the %lld declared", w->path, (long long)w->planes);
	int st = check_finite(w, plane);
	if (st)
		return st;
	TIFF *t = w->tif;
	const uint16_t bps = (uint16_t)(8 * c0_dtype_size(o->dtype));
	uint32_t rps = 0;
	if (!(w->written == 0 || TIFFReadDirectory(t)) || !TIFFGetField(t, TIFFTAG_ROWSPERSTRIP, &rps) || !rps)
		return write_error(w, errno);
	convert_plane(o, plane, w->buf);
	size_t row = (size_t)o->width * (bps / 8);
	if (o->deflate && (st = write_deflated(w, rps, row)))
		return st;
	errno = 0;
	for (int64_t y0 = 0; !o->deflate && y0 < o->height; y0 += rps) {   /* uncompressed */
		int64_t ny = o->height - y0 < rps ? o->height - y0 : rps;
		uint32_t s = TIFFComputeStrip(t, (uint32_t)y0, 0);
		if (TIFFWriteEncodedStrip(t, s, w->buf + (size_t)y0 * row, (tmsize_t)(ny * row)) < 0)
			return write_error(w, errno);
	}
	/* the strip offsets into the directory written at creation; the planes
	 * land one after another at the end of the file */
	if (!TIFFForceStrileArrayWriting(t))
		return write_error(w, errno);
	w->written++;
	return C0_OK;
}

static void release(struct c0_tiff_writer *w)
{
	deflated_free(w->z);
	free(w->buf);
	free(w);
}

void c0_tiff_abort(struct c0_tiff_writer *w)
{
	if (!w)
		return;
	if (w->tif)
		TIFFClose(w->tif);
	remove(w->tmp);
	release(w);
}

int c0_tiff_commit(struct c0_tiff_writer *w)
{
	if (w->written != w->planes) {
		int st = c0_fail(C0_EINVAL, "%s: %lld of %lld planes written", w->path, (long long)w->written, (long long)w->planes);
		c0_tiff_abort(w);
		return st;
	}
	w->tiffmsg[0] = '\0';
	errno = 0;
	TIFFClose(w->tif);
	int err = errno;
	w->tif = NULL;
	int st = w->tiffmsg[0] ? c0_fail(C0_EIO, "%s: closing failed (%s%s%s)", w->path, w->tiffmsg, err ? ": " : "",
					 err ? strerror(err) : "")
			       : c0_commit_file(w->tmp, w->path);
	if (st)
		remove(w->tmp);
	release(w);
	return st;
}

int c0_tiff_save_f32(const char *path, const struct c0_tiff_wopts *opts, const float *data)
{
	struct c0_tiff_wopts o = *opts;
	int64_t planes = c0_tiff_planes(&o);
	size_t plane = (size_t)o.width * o.height, n = plane * planes;
	if (o.display_min == 0 && o.display_max == 0 && n) {
		float lo = INFINITY, hi = -INFINITY;
		for (size_t i = 0; i < n; i++) {
			if (data[i] < lo) lo = data[i];
			if (data[i] > hi) hi = data[i];
		}
		if (lo <= hi) {
			o.display_min = lo;
			o.display_max = hi > lo ? hi : lo + 1;
		}
	}
	struct c0_tiff_writer *w;
	int st = c0_tiff_create(path, &o, &w);
	for (int64_t p = 0; !st && p < planes; p++)
		st = c0_tiff_write_plane(w, data + p * plane);
	if (st) {
		c0_tiff_abort(w);
		return st;
	}
	return c0_tiff_commit(w);
}
