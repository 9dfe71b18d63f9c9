/* TIFF reader/writer round trips, metadata and bad input (C side; the
 * independent tifffile checks are in python/test_tiff_interop.py). */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE   /* mincore */
#include "check.h"
#include "io/tiff.h"
#include "io/imagej.h"
#include "core/err.h"

#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <tiffio.h>
#include <unistd.h>

static char dir[256];

static int count_files(void)
{
	DIR *d = opendir(dir);
	int n = 0;
	for (struct dirent *e; (e = readdir(d));)
		n += e->d_name[0] != '.' || (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."));
	closedir(d);
	return n;
}

static void roundtrip(enum c0_dtype t)
{
	char path[512];
	snprintf(path, sizeof path, "%s/rt_%s.tif", dir, c0_dtype_name(t));
	const int W = 13, H = 7, Z = 3, T = 2;
	float *data = malloc(sizeof(float) * W * H * Z * T);
	for (int i = 0; i < W * H * Z * T; i++)
		data[i] = t == C0_F32 ? (float)(i * 0.37 - 50) : (float)(i % (t == C0_U8 ? 256 : 60000));
	struct c0_tiff_wopts o = { .width = W, .height = H, .slices = Z, .frames = T, .dtype = t,
				   .pixel_size_nm = 25, .z_spacing_nm = 20 };
	CHECK(c0_tiff_save_f32(path, &o, data) == C0_OK);
	struct c0_tiff_info in;
	float *back = NULL;
	CHECK(c0_tiff_load_f32(path, &in, &back) == C0_OK);
	if (!back) {
		free(data);
		return;
	}
	CHECK(in.width == W && in.height == H && in.pages == Z * T);
	CHECK(in.slices == Z && in.frames == T && in.channels == 1);
	CHECK(in.dtype == t);
	CHECK_CLOSE(in.pixel_size_nm, 25, 1e-3);
	CHECK_CLOSE(in.z_spacing_nm, 20, 1e-6);
	int same = 1;
	for (int i = 0; i < W * H * Z * T; i++)
		same &= back[i] == data[i];
	CHECK(same);
	free(data);
	free(back);
}

static void test_roundtrip(void)
{
	roundtrip(C0_U8);
	roundtrip(C0_U16);
	roundtrip(C0_F32);
}

static void test_integer_clamp(void)
{
	char path[512];
	snprintf(path, sizeof path, "%s/clamp.tif", dir);
	float v[4] = { -3.f, 1.6f, 70000.f, 0 };
	struct c0_tiff_wopts o = { .width = 4, .height = 1, .dtype = C0_U16 };
	CHECK(c0_tiff_save_f32(path, &o, v) == C0_OK);
	struct c0_tiff_info in;
	float *b = NULL;
	CHECK(c0_tiff_load_f32(path, &in, &b) == C0_OK);
	CHECK(b && b[0] == 0 && b[1] == 2 && b[2] == 65535 && b[3] == 0);
	CHECK(in.pixel_size_nm == 0);
	free(b);
}

static void test_bigtiff(void)
{
	CHECK(!c0_tiff_needs_bigtiff(1000));
	CHECK(!c0_tiff_needs_bigtiff(4000000000LL));
	CHECK(c0_tiff_needs_bigtiff(4294967296LL));
	char path[512];
	snprintf(path, sizeof path, "%s/big.tif", dir);
	float v[6] = { 1, 2, 3, 4, 5, 6 };
	struct c0_tiff_wopts o = { .width = 3, .height = 2, .dtype = C0_F32, .bigtiff = 1 };
	CHECK(c0_tiff_save_f32(path, &o, v) == C0_OK);
	struct c0_tiff_reader *r;
	CHECK(c0_tiff_open(path, &r) == C0_OK);
	CHECK(c0_tiff_get_info(r)->bigtiff);
	c0_tiff_close(r);
}

/* deflated strips: the same values back, several strips a plane (rows of
 * 512 KiB, 2 a strip), several planes, mostly zero; the bound on the bytes
 * keeps a large one classic TIFF (ImageJ reads no BigTIFF) */
static void test_deflate(void)
{
	char path[512];
	snprintf(path, sizeof path, "%s/deflate.tif", dir);
	enum { W = 131072, H = 5, Z = 3 };
	float *v = calloc((size_t)W * H * Z, sizeof *v);
	for (int i = 0; i < 1000; i++)
		v[(size_t)i * 1231 % ((size_t)W * H * Z)] = (float)i - 300.5f;
	struct c0_tiff_wopts o = { .width = W, .height = H, .slices = Z, .dtype = C0_F32, .deflate = 1, .max_bytes = 1 << 20 };
	CHECK(c0_tiff_save_f32(path, &o, v) == C0_OK);
	struct c0_tiff_info in;
	float *b = NULL;
	CHECK(c0_tiff_load_f32(path, &in, &b) == C0_OK);
	CHECK(b && memcmp(b, v, sizeof *v * W * H * Z) == 0);
	CHECK(strcmp(in.compression, "deflate") == 0 && !in.bigtiff && in.slices == Z);
	struct stat st;
	CHECK(stat(path, &st) == 0 && st.st_size < (off_t)W * H * Z * 4 / 20);
	free(b), free(v);
}

/* the raw strips of a file, concatenated, with each strip's length */
static uint8_t *raw_strips(const char *path, uint32_t *n, uint64_t *len)
{
	TIFF *t = TIFFOpen(path, "r");
	*n = t ? TIFFNumberOfStrips(t) : 0;
	uint64_t total = 0;
	for (uint32_t s = 0; s < *n && s < 64; s++)
		total += len[s] = (uint64_t)TIFFRawStripSize(t, s);
	uint8_t *b = malloc(total + 1), *at = b;
	for (uint32_t s = 0; b && s < *n && s < 64; at += len[s], s++)
		if (TIFFReadRawStrip(t, s, at, (tmsize_t)len[s]) != (tmsize_t)len[s])
			*n = 0;
	if (t)
		TIFFClose(t);
	return b;
}

/* a float plane written by libtiff itself, deflated at level 1 (ZIPQUALITY,
 * as io/tiff_write.c) in strips of rps rows; 0 when a write failed */
static int libtiff_deflated(const char *path, const float *v, int W, int H, uint32_t rps, uint16_t predictor)
{
	TIFF *t = TIFFOpen(path, "w");
	if (!t)
		return 0;
	TIFFSetField(t, TIFFTAG_IMAGEWIDTH, (uint32_t)W), TIFFSetField(t, TIFFTAG_IMAGELENGTH, (uint32_t)H);
	TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 32), TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
	TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP);
	TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
	TIFFSetField(t, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE), TIFFSetField(t, TIFFTAG_ZIPQUALITY, 1);
	TIFFSetField(t, TIFFTAG_PREDICTOR, predictor);
	TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, rps);
	int ok = 1;
	for (uint32_t y = 0; y < (uint32_t)H; y += rps)
		ok &= TIFFWriteEncodedStrip(t, TIFFComputeStrip(t, y, 0), (void *)(v + (size_t)y * W),
					    (tmsize_t)(((uint32_t)H - y < rps ? (uint32_t)H - y : rps) * W * sizeof *v)) > 0;
	TIFFClose(t);
	return ok;
}

/* the plane's strips are deflated side by side (io/tiff_write.c): more
 * strips than one batch and a short last one, each strip's bytes the ones
 * libtiff's own codec writes for it (ZIPQUALITY 1) */
static void test_deflate_strips(void)
{
	enum { W = 1024, H = 256 * 17 + 5 };   /* rows of 4 KiB: 256 a strip, 18 strips */
	char path[512], ref[512];
	snprintf(path, sizeof path, "%s/strips.tif", dir), snprintf(ref, sizeof ref, "%s/strips_ref.tif", dir);
	float *v = calloc((size_t)W * H, sizeof *v);
	for (int i = 0; i < 20000; i++)
		v[(size_t)i * 7919 % ((size_t)W * H)] = (float)(i % 97) * 0.25f - 3;
	struct c0_tiff_wopts o = { .width = W, .height = H, .dtype = C0_F32, .deflate = 1 };
	CHECK(c0_tiff_save_f32(path, &o, v) == C0_OK);
	uint32_t rps = 0, ns = 0, nr = 0;
	TIFF *f = TIFFOpen(path, "r");
	CHECK(f && TIFFGetField(f, TIFFTAG_ROWSPERSTRIP, &rps) && rps == 256);
	if (f)
		TIFFClose(f);
	CHECK(rps == 256 && libtiff_deflated(ref, v, W, H, rps, PREDICTOR_NONE));
	uint64_t la[64], lb[64];
	uint8_t *a = raw_strips(path, &ns, la), *b = raw_strips(ref, &nr, lb);
	int same = ns == 18 && nr == ns;
	for (uint32_t s = 0, at = 0; same && s < ns; at += (uint32_t)la[s], s++)
		same = la[s] == lb[s] && memcmp(a + at, b + at, la[s]) == 0;
	CHECK_MSG(same, "the deflated strips differ from libtiff's own (%u and %u strips)", ns, nr);
	struct c0_tiff_info in;
	float *back = NULL;
	CHECK(c0_tiff_load_f32(path, &in, &back) == C0_OK && back && memcmp(back, v, sizeof *v * W * H) == 0);
	free(a), free(b), free(v), free(back);
}

/* a plane deflated by libtiff itself reads back: many strips, a short last
 * one and rows across strips; with the floating-point predictor too; a
 * damaged strip is an error that names it */
static void test_deflate_read(void)
{
	enum { W = 1024, H = 256 * 17 + 5, RPS = 256 };
	char path[512], pred[512];
	snprintf(path, sizeof path, "%s/deflated.tif", dir), snprintf(pred, sizeof pred, "%s/deflated_pred.tif", dir);
	float *v = calloc((size_t)W * H, sizeof *v), *back = calloc((size_t)W * H, sizeof *back);
	for (int i = 0; i < 40000; i++)
		v[(size_t)i * 7919 % ((size_t)W * H)] = (float)(i % 89) * 0.5f - 7;
	CHECK(libtiff_deflated(path, v, W, H, RPS, PREDICTOR_NONE));
	CHECK(libtiff_deflated(pred, v, W, H, RPS, PREDICTOR_FLOATINGPOINT));
	struct c0_tiff_reader *r = NULL;
	CHECK(c0_tiff_open(path, &r) == C0_OK);
	if (r) {
		CHECK(c0_tiff_read_f32(r, 0, back) == C0_OK && memcmp(back, v, sizeof *v * W * H) == 0);
		const int y0 = 16 * RPS - 3, ny = H - y0;   /* across two strips to the end */
		CHECK(c0_tiff_read_rows_f32(r, 0, y0, ny, back) == C0_OK &&
		      memcmp(back, v + (size_t)y0 * W, sizeof *v * (size_t)ny * W) == 0);
		c0_tiff_close(r);
	}
	memset(back, 0, sizeof *back * W * H);
	CHECK(c0_tiff_open(pred, &r) == C0_OK);
	if (r) {
		CHECK(c0_tiff_read_f32(r, 0, back) == C0_OK && memcmp(back, v, sizeof *v * W * H) == 0);
		c0_tiff_close(r);
	}
	/* strip 5's stream damaged, in a copy in memory */
	FILE *f = fopen(path, "rb");
	uint8_t *file = malloc(8 << 20);
	size_t n = f ? fread(file, 1, 8 << 20, f) : 0;
	if (f)
		fclose(f);
	TIFF *t = TIFFOpen(path, "r");
	const uint64_t off = t ? TIFFGetStrileOffset(t, 5) : 0, len = t ? TIFFGetStrileByteCount(t, 5) : 0;
	if (t)
		TIFFClose(t);
	CHECK(n > 0 && len > 16 && off + len <= n);
	if (n > 0 && len > 16 && off + len <= n) {
		for (uint64_t k = len / 2; k < len / 2 + 8; k++)
			file[off + k] ^= 0x5a;
		CHECK(c0_tiff_open_mem(file, n, "damaged.tif", &r) == C0_OK);
		if (r) {
			CHECK(c0_tiff_read_f32(r, 0, back) != C0_OK);
			CHECK_MSG(strstr(c0_errmsg(), "damaged.tif") && strstr(c0_errmsg(), "strip 5"), "message: %s", c0_errmsg());
			c0_tiff_close(r);
		}
	}
	free(file), free(v), free(back);
}

static void test_abort_leaves_nothing(void)
{
	int before = count_files();
	char path[512];
	snprintf(path, sizeof path, "%s/partial.tif", dir);
	struct c0_tiff_wopts o = { .width = 4, .height = 4, .frames = 3, .dtype = C0_U16 };
	struct c0_tiff_writer *w;
	float p[16] = { 0 };
	CHECK(c0_tiff_create(path, &o, &w) == C0_OK);
	CHECK(c0_tiff_write_plane(w, p) == C0_OK);
	/* two of three planes missing: commit must refuse and clean up */
	CHECK(c0_tiff_commit(w) != C0_OK);
	CHECK(strstr(c0_errmsg(), "partial.tif") != NULL);
	CHECK(count_files() == before);
	CHECK(access(path, F_OK) != 0);
}

static void expect_error(const char *path, const char *needle)
{
	struct c0_tiff_reader *r = NULL;
	int st = c0_tiff_open(path, &r);
	CHECK_MSG(st != C0_OK && r == NULL, "%s opened", path);
	CHECK_MSG(strstr(c0_errmsg(), path) && strstr(c0_errmsg(), needle), "message '%s' lacks '%s'", c0_errmsg(), needle);
}

static void test_bad_input(void)
{
	char p[512];
	snprintf(p, sizeof p, "%s/missing.tif", dir);
	expect_error(p, "No such file");
	snprintf(p, sizeof p, "%s/text.tif", dir);
	FILE *f = fopen(p, "w");
	fputs("this is not an image at all\n", f);
	fclose(f);
	expect_error(p, "not a TIFF");
	snprintf(p, sizeof p, "%s/empty.tif", dir);
	fclose(fopen(p, "w"));
	expect_error(p, "not a TIFF");
	/* header whose first directory offset is 0: zero pages */
	snprintf(p, sizeof p, "%s/nopages.tif", dir);
	f = fopen(p, "wb");
	fwrite("II*\0\0\0\0\0", 1, 8, f);
	fclose(f);
	expect_error(p, "no image pages");
	/* truncated: a valid file cut in the middle of its pixel data */
	char good[512];
	snprintf(good, sizeof good, "%s/rt_uint16.tif", dir);
	snprintf(p, sizeof p, "%s/cut.tif", dir);
	FILE *in = fopen(good, "rb");
	char buf[300];
	size_t n = fread(buf, 1, sizeof buf, in);
	fclose(in);
	f = fopen(p, "wb");
	fwrite(buf, 1, n, f);
	fclose(f);
	struct c0_tiff_reader *r = NULL;
	int st = c0_tiff_open(p, &r);
	if (st == C0_OK) {       /* header survived: reading pixels must fail */
		float plane[13 * 7];
		st = c0_tiff_read_f32(r, 0, plane);
		c0_tiff_close(r);
	}
	CHECK(st != C0_OK);
	CHECK(strstr(c0_errmsg(), "cut.tif") != NULL);
	expect_error(dir, "directory");
}

static void test_imagej_meta(void)
{
	struct c0_ij_meta m;
	c0_ij_parse("ImageJ=1.52e\nimages=50\nframes=50\nunit=micron\nspacing=0.375\nloop=false\n", &m);
	CHECK(m.present && m.images == 50 && m.frames == 50 && m.slices == 1 && m.channels == 1);
	CHECK(!strcmp(m.unit, "um"));
	CHECK_CLOSE(m.spacing, 0.375, 1e-12);
	c0_ij_parse("ImageJ=1.51w\nimages=20\nslices=20\nunit=\\u00B5m\n", &m);
	CHECK(!strcmp(m.unit, "um") && m.slices == 20);
	c0_ij_parse("not imagej", &m);
	CHECK(!m.present && m.frames == 1);
	double z = 0;
	CHECK_CLOSE(c0_ome_pixel_size_nm("<OME><Pixels PhysicalSizeX=\"0.08\" PhysicalSizeZ=\"120\" PhysicalSizeZUnit=\"nm\"/></OME>", &z), 80, 1e-9);
	CHECK_CLOSE(z, 120, 1e-9);
	char buf[256];
	CHECK(c0_ij_format(buf, sizeof buf, 1, 5, 2, 1, 0.02, 0, 0, 1) > 0);
	c0_ij_parse(buf, &m);
	CHECK(m.images == 10 && m.slices == 5 && m.frames == 2 && !strcmp(m.unit, "um"));
	CHECK(strstr(buf, "hyperstack=true") != NULL);
	CHECK(c0_ij_format(buf, 8, 1, 5, 2, 1, 0.02, 0, 0, 1) < 0);
}

/* An output with NaN or infinity is refused whole, naming the file. */
static void test_nonfinite_output(void)
{
	char path[512];
	snprintf(path, sizeof path, "%s/nonfinite.tif", dir);
	int before = count_files();
	float v[6] = { 1, 2, 3, 4, NAN, 6 };
	struct c0_tiff_wopts o = { .width = 3, .height = 2, .dtype = C0_F32 };
	CHECK(c0_tiff_save_f32(path, &o, v) == C0_EINVAL);
	CHECK_MSG(strstr(c0_errmsg(), "nonfinite.tif") && strstr(c0_errmsg(), "NaN") && strstr(c0_errmsg(), "x 1, y 1"),
		  "message '%s'", c0_errmsg());
	v[4] = INFINITY, o.dtype = C0_U16;   /* integer outputs too: no silent clamping of infinity */
	CHECK(c0_tiff_save_f32(path, &o, v) == C0_EINVAL && strstr(c0_errmsg(), "infinite"));
	CHECK(count_files() == before);
}

/* A hyperstack of C channels (planes in CZT order) gives each channel's
 * frames in order through FILE:cK and c0_tiff_select_channel. */
static void test_channels(void)
{
	char path[512], spec[600];
	snprintf(path, sizeof path, "%s/chan.tif", dir);
	const int W = 5, H = 4, C = 3, T = 4;
	float *data = malloc(sizeof(float) * W * H * C * T);
	for (int t = 0; t < T; t++)
		for (int c = 0; c < C; c++)
			for (int i = 0; i < W * H; i++)
				data[((size_t)t * C + c) * W * H + i] = (float)(100 * c + 10 * t + i % 7);
	struct c0_tiff_wopts o = { .width = W, .height = H, .channels = C, .frames = T, .dtype = C0_F32 };
	CHECK(c0_tiff_save_f32(path, &o, data) == C0_OK);
	struct c0_tiff_reader *r;
	CHECK(c0_tiff_open(path, &r) == C0_OK);
	CHECK(c0_tiff_get_info(r)->channels == C && c0_tiff_get_info(r)->pages == C * T);
	c0_tiff_close(r);
	float plane[20];
	for (int c = 1; c <= C; c++) {
		snprintf(spec, sizeof spec, "%s:c%d", path, c);
		CHECK(c0_tiff_open(spec, &r) == C0_OK);
		if (!r)
			continue;
		const struct c0_tiff_info *in = c0_tiff_get_info(r);
		CHECK(in->pages == T && in->channel == c && in->file_pages == C * T);
		int ok = 1;
		for (int t = T - 1; t >= 0; t--) {   /* any order */
			CHECK(c0_tiff_read_f32(r, t, plane) == C0_OK);
			for (int i = 0; i < W * H; i++)
				ok &= plane[i] == (float)(100 * (c - 1) + 10 * t + i % 7);
		}
		for (int t = 0; t < T; t++) {
			CHECK(c0_tiff_read_f32(r, t, plane) == C0_OK);
			for (int i = 0; i < W * H; i++)
				ok &= plane[i] == (float)(100 * (c - 1) + 10 * t + i % 7);
		}
		CHECK_MSG(ok, "channel %d has the wrong planes", c);
		c0_tiff_close(r);
	}
	snprintf(spec, sizeof spec, "%s:c4", path);
	CHECK(c0_tiff_open(spec, &r) == C0_EINVAL && strstr(c0_errmsg(), "3 channels"));
	free(data);
}

/* A message built from the current one (the old c0_fail wrote into the
 * buffer it read from). */
static void test_message_alias(void)
{
	c0_fail(C0_EINVAL, "angle %g deg is bad", 50.0);
	CHECK(c0_fail(C0_EINVAL, "--angles: %s", c0_errmsg()) == C0_EINVAL);
	CHECK_MSG(!strcmp(c0_errmsg(), "--angles: angle 50 deg is bad"), "got '%s'", c0_errmsg());
	CHECK(c0_fail_prefix(C0_EIO, "x.tif") == C0_EIO);
	CHECK_MSG(!strcmp(c0_errmsg(), "x.tif: --angles: angle 50 deg is bad"), "got '%s'", c0_errmsg());
}

/* the share of a file's first n bytes in the kernel's page cache */
static double resident(const char *path, size_t n)
{
	const size_t pg = (size_t)sysconf(_SC_PAGESIZE), np = (n + pg - 1) / pg;
	int fd = open(path, O_RDONLY);
	void *m = fd >= 0 ? mmap(NULL, n, PROT_READ, MAP_SHARED, fd, 0) : MAP_FAILED;
	unsigned char *v = malloc(np);
	size_t in = 0;
	if (m != MAP_FAILED && v && !mincore(m, n, v))
		for (size_t i = 0; i < np; i++)
			in += v[i] & 1;
	if (m != MAP_FAILED)
		munmap(m, n);
	if (fd >= 0)
		close(fd);
	free(v);
	return (double)in / (double)np;
}

/* 1 when every plane of path reads back as v (Z planes of n), twice over:
 * the second pass starts again from the first plane */
static int read_twice(const char *path, const float *v, size_t n, int Z, int drop)
{
	struct c0_tiff_reader *r;
	if (c0_tiff_open(path, &r) != C0_OK)
		return 0;
	c0_tiff_drop_behind(r, drop);
	float *p = malloc(n * sizeof *p);
	int same = p != NULL;
	for (int pass = 0; pass < 2; pass++)
		for (int z = 0; same && z < Z; z++)
			same = c0_tiff_read_f32(r, z, p) == C0_OK && !memcmp(p, v + (size_t)z * n, n * sizeof *p);
	free(p);
	c0_tiff_close(r);
	return same;
}

/* c0_tiff_drop_behind: the planes read the same, pass after pass, and the
 * pages read are given back to the kernel (40 MB of planes: the drops go a
 * 32 MB window at a time). A file system whose pages are its storage
 * (tmpfs) keeps them whatever it is told: there only the values are checked. */
static void test_drop_behind(void)
{
	const int W = 512, H = 512, Z = 80;
	const size_t n = (size_t)W * H, win = (size_t)32 << 20;
	char path[512];
	snprintf(path, sizeof path, "%s/drop.tif", dir);
	float *v = malloc(n * Z * sizeof *v);
	for (size_t i = 0; i < n * Z; i++)
		v[i] = (float)((i * 7919) % 60000);
	struct c0_tiff_wopts o = { .width = W, .height = H, .slices = Z, .dtype = C0_U16 };
	CHECK(c0_tiff_save_f32(path, &o, v) == C0_OK);
	int fd = open(path, O_RDONLY);   /* written back: clean pages can be freed */
	CHECK(fd >= 0 && !fsync(fd));
	CHECK_MSG(read_twice(path, v, n, Z, 0), "the planes read back differently");
	const double kept = resident(path, win);
	CHECK_MSG(read_twice(path, v, n, Z, 1), "the planes read back differently when given back as read");
	const double left = resident(path, win);
	(void)posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
	const double can = resident(path, win);
	fprintf(stderr, "page cache, the first 32 MB: %.0f %% after a plain read, %.0f %% after reading with "
		"drop-behind, %.0f %% when all is given back\n", 100 * kept, 100 * left, 100 * can);
	if (can < 0.05)
		CHECK_MSG(left < 0.05, "%.0f %% of the pages read stayed in the page cache", 100 * left);
	else
		fprintf(stderr, "this file system keeps its pages (tmpfs?): drop-behind not checked\n");
	if (fd >= 0)
		close(fd);
	free(v);
}

int main(void)
{
	snprintf(dir, sizeof dir, "/tmp/c0_test_tiff_XXXXXX");
	if (!mkdtemp(dir))
		return 1;
	RUN(test_roundtrip);
	RUN(test_integer_clamp);
	RUN(test_bigtiff);
	RUN(test_deflate);
	RUN(test_deflate_strips);
	RUN(test_deflate_read);
	RUN(test_drop_behind);
	RUN(test_abort_leaves_nothing);
	RUN(test_bad_input);
	RUN(test_imagej_meta);
	RUN(test_nonfinite_output);
	RUN(test_channels);
	RUN(test_message_alias);
	char cmd[300];
	snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
	if (system(cmd)) {}
	return CHECK_DONE();
}
