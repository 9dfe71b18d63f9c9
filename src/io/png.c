#include "io/png.h"
#include "io/atomic.h"
#include "core/err.h"

#include <errno.h>
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <string.h>

int c0_png_write_rgb(const char *path, int w, int h, const uint8_t *rgb)
{
	if (w <= 0 || h <= 0)
		return c0_fail(C0_EINVAL, "%s: empty image", path);
	char tmp[4096];
	c0_tmp_name(path, tmp, sizeof tmp);
	FILE *f = fopen(tmp, "wb");
	if (!f)
		return c0_fail(C0_EIO, "%s: cannot create: %s", path, strerror(errno));
	png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
	png_infop info = png ? png_create_info_struct(png) : NULL;
	if (!info || setjmp(png_jmpbuf(png))) {
		png_destroy_write_struct(&png, info ? &info : NULL);
		fclose(f);
		remove(tmp);
		return c0_fail(C0_EIO, "%s: PNG write failed%s%s", path, errno ? ": " : "", errno ? strerror(errno) : "");
	}
	errno = 0;
	png_init_io(png, f);
	png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
		     PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
	png_write_info(png, info);
	for (int y = 0; y < h; y++)
		png_write_row(png, (png_const_bytep)(rgb + (size_t)y * w * 3));
	png_write_end(png, info);
	png_destroy_write_struct(&png, &info);
	if (fclose(f)) {
		remove(tmp);
		return c0_fail(C0_EIO, "%s: write failed: %s", path, strerror(errno));
	}
	return c0_commit_file(tmp, path);
}
