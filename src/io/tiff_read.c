/* Streaming TIFF reader: validates every page once at open, then decodes
 * one plane per call through libtiff's strip/tile API. */
#define _POSIX_C_SOURCE 200809L
#include "io/tiff.h"
#include "io/imagej.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/mem.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <tiffio.h>

struct c0_tiff_reader {
	TIFF *tif;
	char name[512];
	char tiffmsg[256];          /* last libtiff error for this file */
	struct c0_tiff_info info;
	int64_t cur;                /* current directory */
	uint8_t *buf;
	size_t bufsize;
	const uint8_t *mem;         /* memory source, or NULL */
	size_t memsize, mempos;
	/* channels: the channel of file plane p is
	 * (p / series_pages) * per_series + (p % series_pages / stride) % per_series */
	int64_t series_pages, per_series, stride;
	int64_t *map;               /* selected channel: its file planes in order */
	int allow_nonfinite;
	int drop;                   /* c0_tiff_drop_behind */
	uint64_t dropped;           /* the file's bytes up to here were given back to the kernel */
};

const char *c0_dtype_name(enum c0_dtype t)
{
	static const char *n[] = { "uint8", "uint16", "uint32", "int16", "int32", "float32", "float64" };
	return (unsigned)t < 7 ? n[t] : "?";
}

size_t c0_dtype_size(enum c0_dtype t)
{
	static const size_t s[] = { 1, 2, 4, 2, 4, 4, 8 };
	return (unsigned)t < 7 ? s[t] : 0;
}

static int on_error(TIFF *tif, void *ud, const char *module, const char *fmt, va_list ap)
{
	(void)tif;
	(void)module;
	struct c0_tiff_reader *r = ud;
	vsnprintf(r->tiffmsg, sizeof r->tiffmsg, fmt, ap);
	return 1;
}

static int on_warning(TIFF *tif, void *ud, const char *module, const char *fmt, va_list ap)
{
	/* ImageJ's private tags and odd colour maps warn; nothing we act on */
	(void)tif, (void)ud, (void)module, (void)fmt, (void)ap;
	return 1;
}

/* memory source for TIFFClientOpen */
static tmsize_t mem_read(thandle_t h, void *buf, tmsize_t n)
{
	struct c0_tiff_reader *r = (struct c0_tiff_reader *)h;
	if (n < 0 || r->mempos >= r->memsize)
		return 0;
	size_t k = r->memsize - r->mempos;
	if ((size_t)n < k)
		k = (size_t)n;
	memcpy(buf, r->mem + r->mempos, k);
	r->mempos += k;
	return (tmsize_t)k;
}
static tmsize_t mem_write(thandle_t h, void *buf, tmsize_t n) { (void)h, (void)buf, (void)n; return 0; }
static toff_t mem_seek(thandle_t h, toff_t off, int whence)
{
	struct c0_tiff_reader *r = (struct c0_tiff_reader *)h;
	uint64_t base = whence == SEEK_CUR ? r->mempos : whence == SEEK_END ? r->memsize : 0;
	if (off > UINT64_MAX - base)
		return (toff_t)-1;
	r->mempos = base + off;
	return r->mempos;
}
static int mem_close(thandle_t h) { (void)h; return 0; }
static toff_t mem_size(thandle_t h) { return ((struct c0_tiff_reader *)h)->memsize; }
static int mem_map(thandle_t h, void **base, toff_t *size) { (void)h, (void)base, (void)size; return 0; }
static void mem_unmap(thandle_t h, void *base, toff_t size) { (void)h, (void)base, (void)size; }

static int page_dtype(struct c0_tiff_reader *r, int64_t page, enum c0_dtype *t)
{
	uint16_t bps = 1, fmt = SAMPLEFORMAT_UINT, spp = 1, photo = PHOTOMETRIC_MINISBLACK;
	TIFFGetFieldDefaulted(r->tif, TIFFTAG_BITSPERSAMPLE, &bps);
	TIFFGetFieldDefaulted(r->tif, TIFFTAG_SAMPLEFORMAT, &fmt);
	TIFFGetFieldDefaulted(r->tif, TIFFTAG_SAMPLESPERPIXEL, &spp);
	TIFFGetField(r->tif, TIFFTAG_PHOTOMETRIC, &photo);
	if (spp != 1 || photo == PHOTOMETRIC_RGB || photo == PHOTOMETRIC_YCBCR || photo == PHOTOMETRIC_SEPARATED)
		return c0_fail(C0_EUNSUPPORTED, "%s: page %lld has %u samples per pixel (RGB or multi-sample images are not supported; split the channels first)",
			       r->name, (long long)page + 1, spp);
	if (fmt == SAMPLEFORMAT_COMPLEXINT || fmt == SAMPLEFORMAT_COMPLEXIEEEFP)
		return c0_fail(C0_EUNSUPPORTED, "%s: page %lld has complex samples (not supported)", r->name, (long long)page + 1);
	if (fmt == SAMPLEFORMAT_UINT && bps == 8) *t = C0_U8;
	else if (fmt == SAMPLEFORMAT_UINT && bps == 16) *t = C0_U16;
	else if (fmt == SAMPLEFORMAT_UINT && bps == 32) *t = C0_U32;
	else if (fmt == SAMPLEFORMAT_INT && bps == 16) *t = C0_I16;
	else if (fmt == SAMPLEFORMAT_INT && bps == 32) *t = C0_I32;
	else if (fmt == SAMPLEFORMAT_IEEEFP && bps == 32) *t = C0_F32;
	else if (fmt == SAMPLEFORMAT_IEEEFP && bps == 64) *t = C0_F64;
	else
		return c0_fail(C0_EUNSUPPORTED, "%s: page %lld has %u-bit samples of format %u (supported: uint8/16/32, int16/32, float32/64)",
			       r->name, (long long)page + 1, bps, fmt);
	return C0_OK;
}

static int read_calibration(struct c0_tiff_reader *r)
{
	struct c0_tiff_info *in = &r->info;
	char *desc = NULL;
	TIFFGetField(r->tif, TIFFTAG_IMAGEDESCRIPTION, &desc);
	struct c0_ij_meta ij;
	c0_ij_parse(desc, &ij);
	in->imagej = ij.present;
	if (ij.present && ij.images > in->pages && in->pages == 1)
		return c0_fail(C0_EUNSUPPORTED, "%s: ImageJ raw layout (images=%lld stored after one page, used above 4 GiB) is not supported; save as OME-TIFF or BigTIFF",
			       r->name, (long long)ij.images);
	in->frames = in->pages;
	r->series_pages = in->pages, r->per_series = 1, r->stride = 1;
	if (ij.present && ij.channels * ij.slices * ij.frames == in->pages) {
		in->channels = ij.channels;
		in->slices = ij.slices;
		in->frames = ij.frames;
		r->per_series = ij.channels;   /* ImageJ stores planes in CZT order */
	}
	float xres = 0;
	uint16_t ru = RESUNIT_NONE;
	TIFFGetField(r->tif, TIFFTAG_XRESOLUTION, &xres);
	TIFFGetFieldDefaulted(r->tif, TIFFTAG_RESOLUTIONUNIT, &ru);
	const char *unit = ij.unit;
	if (ru == RESUNIT_INCH && !unit[0])
		unit = "inch";
	else if (ru == RESUNIT_CENTIMETER && !unit[0])
		unit = "cm";
	snprintf(in->unit, sizeof in->unit, "%s", unit);
	double px = xres > 0 ? c0_unit_nm(unit) / xres : 0;
	/* 72 or 96 dpi from a paint program is not a microscope calibration */
	if (px > 100e3)
		px = 0;
	in->pixel_size_nm = px;
	if (ij.spacing > 0 && c0_unit_nm(ij.unit) > 0)
		in->z_spacing_nm = ij.spacing * c0_unit_nm(ij.unit);
	struct c0_ome_layout ol;
	if (c0_ome_layout(desc, &ol) && ol.size_c * ol.size_z * ol.size_t_ * ol.series == in->pages) {
		in->ome = 1;
		in->channels = ol.size_c * ol.series;
		in->slices = ol.size_z, in->frames = ol.size_t_;
		r->series_pages = ol.size_c * ol.size_z * ol.size_t_;
		r->per_series = ol.size_c, r->stride = ol.stride_c;
	}
	double z = 0, ome = c0_ome_pixel_size_nm(desc, &z);
	if (ome > 0) {
		in->ome = 1;
		in->pixel_size_nm = ome;
		snprintf(in->unit, sizeof in->unit, "um");
		if (z > 0)
			in->z_spacing_nm = z;
	}
	return C0_OK;
}

static int open_common(struct c0_tiff_reader *r)
{
	struct c0_tiff_info *in = &r->info;
	int64_t pages = 0;
	do {
		uint32_t w = 0, h = 0;
		if (!TIFFGetField(r->tif, TIFFTAG_IMAGEWIDTH, &w) || !TIFFGetField(r->tif, TIFFTAG_IMAGELENGTH, &h) || !w || !h)
			return c0_fail(C0_EFORMAT, "%s: page %lld has no image size", r->name, (long long)pages + 1);
		enum c0_dtype t = C0_U8;
		int st = page_dtype(r, pages, &t);
		if (st)
			return st;
		if (pages == 0) {
			if ((uint64_t)w * h > (1ull << 32))
				return c0_fail(C0_EUNSUPPORTED, "%s: %ux%u pixels per plane is too large", r->name, w, h);
			in->width = w, in->height = h, in->dtype = t;
			in->tiled = TIFFIsTiled(r->tif);
		} else if (w != in->width || h != in->height) {
			return c0_fail(C0_EFORMAT, "%s: page %lld is %ux%u but page 1 is %lldx%lld (pages of different sizes)",
				       r->name, (long long)pages + 1, w, h, (long long)in->width, (long long)in->height);
		} else if (t != in->dtype) {
			return c0_fail(C0_EFORMAT, "%s: page %lld is %s but page 1 is %s (mixed sample types)",
				       r->name, (long long)pages + 1, c0_dtype_name(t), c0_dtype_name(in->dtype));
		}
		pages++;
		r->tiffmsg[0] = '\0';
	} while (TIFFReadDirectory(r->tif));
	if (r->tiffmsg[0])
		return c0_fail(C0_EFORMAT, "%s: truncated or damaged after page %lld (%s)", r->name, (long long)pages, r->tiffmsg);
	in->pages = in->file_pages = pages;
	in->channels = in->slices = 1;
	if (!TIFFSetDirectory(r->tif, 0))
		return c0_fail(C0_EFORMAT, "%s: cannot return to page 1 (%s)", r->name, r->tiffmsg);
	r->cur = 0;
	in->bigtiff = TIFFIsBigTIFF(r->tif);
	in->big_endian = TIFFIsBigEndian(r->tif);
	uint16_t comp = COMPRESSION_NONE;
	TIFFGetFieldDefaulted(r->tif, TIFFTAG_COMPRESSION, &comp);
	const char *cn = comp == COMPRESSION_NONE ? "none" : comp == COMPRESSION_LZW ? "lzw"
		: comp == COMPRESSION_ADOBE_DEFLATE || comp == COMPRESSION_DEFLATE ? "deflate"
		: comp == COMPRESSION_PACKBITS ? "packbits" : "other";
	snprintf(in->compression, sizeof in->compression, "%s", cn);
	return read_calibration(r);
}

static int check_magic(const char *name, const uint8_t *b, size_t n)
{
	if (n < 8)
		return c0_fail(C0_EFORMAT, "%s: not a TIFF file (only %zu bytes)", name, n);
	int ok = (b[0] == 'I' && b[1] == 'I' && (b[2] == 42 || b[2] == 43) && b[3] == 0)
	      || (b[0] == 'M' && b[1] == 'M' && b[2] == 0 && (b[3] == 42 || b[3] == 43));
	return ok ? C0_OK : c0_fail(C0_EFORMAT, "%s: not a TIFF file (bad magic number)", name);
}

/* Both opens' mode. r: read, not map (a mapped stack counts as resident
 * memory); c: a page's one uncompressed strip is read whole, not chopped by
 * libtiff into 8 kB strips of a seek and a read each (256 seeks and reads
 * for a 1024^2 uint16 frame: docs/speed.md, "Reading a frame in one read") */
#define OPEN_MODE "rmc"

static TIFFOpenOptions *options(struct c0_tiff_reader *r)
{
	TIFFOpenOptions *o = TIFFOpenOptionsAlloc();
	if (!o)
		return NULL;
	TIFFOpenOptionsSetErrorHandlerExtR(o, on_error, r);
	TIFFOpenOptionsSetWarningHandlerExtR(o, on_warning, r);
	TIFFOpenOptionsSetMaxSingleMemAlloc(o, (tmsize_t)1 << 31);
	return o;
}

static int finish_open(struct c0_tiff_reader *r, struct c0_tiff_reader **out)
{
	if (!r->tif) {
		int st = c0_fail(C0_EFORMAT, "%s: no image pages or damaged header%s%s", r->name, r->tiffmsg[0] ? ": " : "", r->tiffmsg);
		free(r);
		return st;
	}
	int st = open_common(r);
	if (st) {
		c0_tiff_close(r);
		return st;
	}
	*out = r;
	return C0_OK;
}

static int open_file(const char *path, const char *name, struct c0_tiff_reader **out)
{
	struct stat sb;
	if (stat(path, &sb))
		return c0_fail(C0_EIO, "%s: %s", name, strerror(errno));
	if (S_ISDIR(sb.st_mode))
		return c0_fail(C0_EIO, "%s: is a directory, not a TIFF file", name);
	FILE *f = fopen(path, "rb");
	if (!f)
		return c0_fail(C0_EIO, "%s: %s", name, strerror(errno));
	uint8_t magic[8];
	size_t n = fread(magic, 1, 8, f);
	fclose(f);
	int st = check_magic(name, magic, n);
	if (st)
		return st;
	struct c0_tiff_reader *r = c0_alloc(1, sizeof *r);
	if (!r)
		return C0_ENOMEM;
	snprintf(r->name, sizeof r->name, "%s", name);
	TIFFOpenOptions *o = options(r);
	r->tif = TIFFOpenExt(path, OPEN_MODE, o);
	TIFFOpenOptionsFree(o);
	return finish_open(r, out);
}

int c0_tiff_open(const char *path, struct c0_tiff_reader **out)
{
	*out = NULL;
	char file[4096];
	struct stat sb;
	int k = stat(path, &sb) ? c0_tiff_channel_spec(path, file, sizeof file) : 0;
	if (!k)
		return open_file(path, path, out);
	int st = open_file(file, path, out);
	if (!st && (st = c0_tiff_select_channel(*out, k))) {
		c0_tiff_close(*out);
		*out = NULL;
	}
	return st;
}

int c0_tiff_open_mem(const void *data, size_t size, const char *name, struct c0_tiff_reader **out)
{
	*out = NULL;
	int st = check_magic(name, data, size);
	if (st)
		return st;
	struct c0_tiff_reader *r = c0_alloc(1, sizeof *r);
	if (!r)
		return C0_ENOMEM;
	snprintf(r->name, sizeof r->name, "%s", name);
	r->mem = data;
	r->memsize = size;
	TIFFOpenOptions *o = options(r);
	r->tif = TIFFClientOpenExt(name, OPEN_MODE, (thandle_t)r, mem_read, mem_write, mem_seek, mem_close,
				   mem_size, mem_map, mem_unmap, o);
	TIFFOpenOptionsFree(o);
	return finish_open(r, out);
}

const struct c0_tiff_info *c0_tiff_get_info(const struct c0_tiff_reader *r)
{
	return &r->info;
}

void c0_tiff_close(struct c0_tiff_reader *r)
{
	if (!r)
		return;
	if (r->tif)
		TIFFClose(r->tif);
	free(r->buf);
	free(r->map);
	free(r);
}

static int seek_page(struct c0_tiff_reader *r, int64_t page)
{
	if (page < 0 || page >= r->info.pages)
		return c0_fail(C0_EINVAL, "%s: page %lld out of range (1..%lld)", r->name, (long long)page + 1, (long long)r->info.pages);
	if (r->map)
		page = r->map[page];
	if (page == r->cur)
		return C0_OK;
	int ok = 1;
	/* a channel's planes are a few apart: step forward rather than search from the start */
	if (r->cur >= 0 && page > r->cur && page - r->cur <= 64)
		while (ok && r->cur < page)
			ok = TIFFReadDirectory(r->tif), r->cur++;
	else
		ok = TIFFSetDirectory(r->tif, (tdir_t)page);
	if (!ok) {
		r->cur = -1;   /* unknown: the next read searches */
		return c0_fail(C0_EFORMAT, "%s: cannot read page %lld (%s)", r->name, (long long)page + 1, r->tiffmsg);
	}
	r->cur = page;
	return C0_OK;
}

int c0_tiff_select_channel(struct c0_tiff_reader *r, int k)
{
	struct c0_tiff_info *in = &r->info;
	free(r->map);
	r->map = NULL;
	in->pages = in->file_pages, in->channel = 0;
	if (k == 0)
		return C0_OK;
	if (k < 0 || k > in->channels)
		return c0_fail(C0_EINVAL, "%s: channel %d requested; the file has %lld channel%s", r->name, k,
			       (long long)in->channels, in->channels == 1 ? "" : "s");
	int64_t n = 0;
	if (!(r->map = c0_alloc((size_t)(in->file_pages / in->channels + 1), sizeof *r->map)))
		return C0_ENOMEM;
	for (int64_t p = 0; p < in->file_pages; p++) {
		int64_t c = p / r->series_pages * r->per_series + p % r->series_pages / r->stride % r->per_series;
		if (c == k - 1 && n <= in->file_pages / in->channels)
			r->map[n++] = p;
	}
	in->pages = n, in->channel = k;
	return C0_OK;
}

void c0_tiff_allow_nonfinite(struct c0_tiff_reader *r)
{
	r->allow_nonfinite = 1;
}

int c0_tiff_channel_spec(const char *path, char *file, size_t n)
{
	const char *c = strrchr(path, ':');
	if (!c || c[1] != 'c' || !c[2] || (size_t)(c - path) >= n)
		return 0;
	char *end;
	long k = strtol(c + 2, &end, 10);
	if (*end || k < 1 || k > 4096 || c[2] == '+' || c[2] == '-')
		return 0;
	memcpy(file, path, (size_t)(c - path));
	file[c - path] = '\0';
	return (int)k;
}

/* NaN or infinity in a float stack would poison every sum it enters; the
 * message says where, so that the user can mend the file. */
static int check_finite(const struct c0_tiff_reader *r, int64_t page, int64_t ya, int64_t yb, const float *d32,
			const double *d64)
{
	const size_t n = (size_t)r->info.width * (size_t)(yb - ya);
	size_t i = 0;
	if (d32) {
		while (i < n && isfinite(d32[i]))
			i++;
	} else {
		while (i < n && isfinite(d64[i]))
			i++;
	}
	if (i == n)
		return C0_OK;
	double v = d32 ? d32[i] : d64[i];
	return c0_fail(C0_EFORMAT, "%s: frame %lld, pixel (x %lld, y %lld) is %s; non-finite pixels are not supported (replace them first)",
		       r->name, (long long)page + 1, (long long)(i % r->info.width), (long long)(ya + (int64_t)(i / r->info.width)),
		       isnan(v) ? "NaN" : v > 0 ? "+infinity" : "-infinity");
}

static int ensure_buf(struct c0_tiff_reader *r, size_t n)
{
	if (n <= r->bufsize)
		return C0_OK;
	free(r->buf);
	r->buf = c0_alloc(n, 1);
	r->bufsize = r->buf ? n : 0;
	return r->buf ? C0_OK : C0_ENOMEM;
}

/* Convert n samples of the file's type at src to float (dst32) or double (dst64):
 * exact for every type but float64 to float32, which rounds the same in each build. */
C0_HOT_SAME static void convert(enum c0_dtype t, const uint8_t *src, size_t n, float *d32, double *d64)
{
#define CONV(T) do { const T *s = (const T *)(const void *)src; \
	if (d32) for (size_t i = 0; i < n; i++) d32[i] = (float)s[i]; \
	else for (size_t i = 0; i < n; i++) d64[i] = (double)s[i]; } while (0)
	switch (t) {
	case C0_U8: CONV(uint8_t); break;
	case C0_U16: CONV(uint16_t); break;
	case C0_U32: CONV(uint32_t); break;
	case C0_I16: CONV(int16_t); break;
	case C0_I32: CONV(int32_t); break;
	case C0_F32: CONV(float); break;
	case C0_F64: CONV(double); break;
	}
#undef CONV
}

static int read_strips(struct c0_tiff_reader *r, int64_t page, int64_t ya, int64_t yb, float *d32, double *d64);

void c0_tiff_drop_behind(struct c0_tiff_reader *r, int on)
{
	r->drop = on && !r->mem;
}

/* With c0_tiff_drop_behind, after a whole plane: the kernel is told that the
 * file's bytes up to this page's last strip or tile are not wanted again
 * (they stay on disk), a window at a time, so that it frees their page cache
 * instead of evicting pages that other files will be read from again. A hint
 * only: the bytes read are the same. (Asking for the bytes ahead as well,
 * POSIX_FADV_WILLNEED, measured no faster: docs/speed.md.) */
#define DROP_WINDOW ((uint64_t)32 << 20)
static void drop_behind(struct c0_tiff_reader *r)
{
	const uint32_t n = TIFFIsTiled(r->tif) ? TIFFNumberOfTiles(r->tif) : TIFFNumberOfStrips(r->tif);
	int err = 0;
	if (!n)
		return;
	const uint64_t end = TIFFGetStrileOffsetWithErr(r->tif, n - 1, &err) +
			     TIFFGetStrileByteCountWithErr(r->tif, n - 1, &err);
	if (err)
		return;
	if (end < r->dropped)   /* a new pass from an earlier plane */
		r->dropped = 0;
	if (end - r->dropped < DROP_WINDOW)
		return;
	(void)posix_fadvise(TIFFFileno(r->tif), (off_t)r->dropped, (off_t)(end - r->dropped), POSIX_FADV_DONTNEED);
	r->dropped = end;
}

/* rows [ya, yb) of a page into rows 0.. of the destination */
static int read_page(struct c0_tiff_reader *r, int64_t page, int64_t ya, int64_t yb, float *d32, double *d64)
{
	int st = seek_page(r, page);
	if (st)
		return st;
	const int64_t W = r->info.width, H = r->info.height;
	const size_t bs = c0_dtype_size(r->info.dtype);
	r->tiffmsg[0] = '\0';
	if (TIFFIsTiled(r->tif)) {
		uint32_t tw = 0, th = 0;
		TIFFGetField(r->tif, TIFFTAG_TILEWIDTH, &tw);
		TIFFGetField(r->tif, TIFFTAG_TILELENGTH, &th);
		/* tiles may overhang the image, but not absurdly (a damaged tag would
		 * otherwise ask for gigabytes) */
		if (!tw || !th || (double)tw * th > fmax(4.0 * W * H, 1 << 20))
			return c0_fail(C0_EFORMAT, "%s: page %lld has an invalid tile size %ux%u", r->name, (long long)page + 1, tw, th);
		size_t tsz = (size_t)tw * th * bs;
		if ((st = ensure_buf(r, tsz)))
			return st;
		for (int64_t y0 = ya / th * th; y0 < yb; y0 += th)
			for (int64_t x0 = 0; x0 < W; x0 += tw) {
				uint32_t ti = TIFFComputeTile(r->tif, (uint32_t)x0, (uint32_t)y0, 0, 0);
				if (TIFFReadEncodedTile(r->tif, ti, r->buf, (tmsize_t)tsz) != (tmsize_t)tsz)
					return c0_fail(C0_EFORMAT, "%s: page %lld: cannot read tile %u (%s)", r->name,
						       (long long)page + 1, ti, r->tiffmsg[0] ? r->tiffmsg : "truncated file");
				int64_t nx = W - x0 < tw ? W - x0 : tw, ny = H - y0 < th ? H - y0 : th;
				for (int64_t y = 0; y < ny; y++) {
					if (y0 + y < ya || y0 + y >= yb)
						continue;
					size_t o = (size_t)(y0 + y - ya) * W + x0;
					convert(r->info.dtype, r->buf + (size_t)y * tw * bs, nx, d32 ? d32 + o : NULL, d64 ? d64 + o : NULL);
				}
			}
	} else if ((st = read_strips(r, page, ya, yb, d32, d64)))
		return st;
	if (r->drop && ya == 0 && yb == H)   /* not after a band's rows: the page's other bands are still to be read */
		drop_behind(r);
	if (r->allow_nonfinite || (r->info.dtype != C0_F32 && r->info.dtype != C0_F64))
		return C0_OK;
	return check_finite(r, page, ya, yb, d32, d64);
}

static int read_strips(struct c0_tiff_reader *r, int64_t page, int64_t ya, int64_t yb, float *d32, double *d64)
{
	const int64_t W = r->info.width, H = r->info.height;
	const size_t bs = c0_dtype_size(r->info.dtype);
	int st;
	uint32_t rps = 0;
	TIFFGetFieldDefaulted(r->tif, TIFFTAG_ROWSPERSTRIP, &rps);
	if (rps == 0 || rps > H)
		rps = (uint32_t)H;
	if ((st = ensure_buf(r, (size_t)rps * W * bs)))
		return st;
	for (int64_t y0 = ya / rps * rps; y0 < yb; y0 += rps) {
		int64_t ny = H - y0 < rps ? H - y0 : rps;
		tmsize_t want = (tmsize_t)(ny * W * bs);
		uint32_t s = TIFFComputeStrip(r->tif, (uint32_t)y0, 0);
		if (TIFFReadEncodedStrip(r->tif, s, r->buf, want) != want)
			return c0_fail(C0_EFORMAT, "%s: page %lld: cannot read strip %u (%s)", r->name,
				       (long long)page + 1, s, r->tiffmsg[0] ? r->tiffmsg : "truncated file");
		int64_t a = y0 > ya ? y0 : ya, b = y0 + ny < yb ? y0 + ny : yb;
		size_t o = (size_t)(a - ya) * W;
		convert(r->info.dtype, r->buf + (size_t)(a - y0) * W * bs, (size_t)((b - a) * W), d32 ? d32 + o : NULL,
			d64 ? d64 + o : NULL);
	}
	return C0_OK;
}

int c0_tiff_read_f32(struct c0_tiff_reader *r, int64_t page, float *dst)
{
	return read_page(r, page, 0, r->info.height, dst, NULL);
}

int c0_tiff_read_rows_f32(struct c0_tiff_reader *r, int64_t page, int64_t y0, int64_t ny, float *dst)
{
	if (y0 < 0 || ny < 1 || y0 + ny > r->info.height)
		return c0_fail(C0_EINVAL, "%s: rows %lld..%lld are outside the %lld-row image", r->name, (long long)y0,
			       (long long)(y0 + ny - 1), (long long)r->info.height);
	return read_page(r, page, y0, y0 + ny, dst, NULL);
}

int c0_tiff_read_f64(struct c0_tiff_reader *r, int64_t page, double *dst)
{
	return read_page(r, page, 0, r->info.height, NULL, dst);
}

int c0_tiff_load_f32(const char *path, struct c0_tiff_info *info, float **data)
{
	*data = NULL;
	struct c0_tiff_reader *r;
	int st = c0_tiff_open(path, &r);
	if (st)
		return st;
	*info = r->info;
	size_t plane = (size_t)info->width * info->height;
	float *d = c0_alloc(plane * info->pages, sizeof *d);
	if (!d) {
		c0_tiff_close(r);
		return C0_ENOMEM;
	}
	for (int64_t p = 0; p < info->pages && !st; p++)
		st = c0_tiff_read_f32(r, p, d + p * plane);
	c0_tiff_close(r);
	if (st) {
		free(d);
		return st;
	}
	*data = d;
	return C0_OK;
}
