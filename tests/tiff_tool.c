/* Test helper for the tifffile interop test.
 *   tiff_tool dump IN.tif OUT.raw   info as JSON on stdout, all pages as float64 LE
 *   tiff_tool write OUT.tif DTYPE W H C Z T PIXEL_NM DZ_NM BIGTIFF
 *       writes value(i) = pattern of the flat index i (see the Python side) */
#include "io/tiff.h"
#include "core/err.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double pattern(const char *dtype, long i)
{
	if (!strcmp(dtype, "uint8")) return (double)((i * 7) % 256);
	if (!strcmp(dtype, "uint16")) return (double)((i * 7919) % 65536);
	return i * 0.25 - 100.0;
}

int main(int argc, char **argv)
{
	if (argc == 4 && !strcmp(argv[1], "dump")) {
		struct c0_tiff_reader *r;
		if (c0_tiff_open(argv[2], &r)) {
			fprintf(stderr, "%s\n", c0_errmsg());
			return 1;
		}
		const struct c0_tiff_info *in = c0_tiff_get_info(r);
		size_t n = (size_t)in->width * in->height;
		double *p = malloc(n * sizeof *p);
		FILE *f = fopen(argv[3], "wb");
		int rc = 0;
		for (int64_t k = 0; k < in->pages && !rc; k++) {
			if (c0_tiff_read_f64(r, k, p)) {
				fprintf(stderr, "%s\n", c0_errmsg());
				rc = 1;
			} else
				fwrite(p, sizeof *p, n, f);
		}
		fclose(f);
		printf("{\"width\":%lld,\"height\":%lld,\"pages\":%lld,\"channels\":%lld,\"slices\":%lld,\"frames\":%lld,"
		       "\"dtype\":\"%s\",\"pixel_size_nm\":%.9g,\"z_spacing_nm\":%.9g,\"bigtiff\":%d,\"big_endian\":%d,"
		       "\"tiled\":%d,\"compression\":\"%s\"}\n",
		       (long long)in->width, (long long)in->height, (long long)in->pages, (long long)in->channels,
		       (long long)in->slices, (long long)in->frames, c0_dtype_name(in->dtype), in->pixel_size_nm,
		       in->z_spacing_nm, in->bigtiff, in->big_endian, in->tiled, in->compression);
		free(p);
		c0_tiff_close(r);
		return rc;
	}
	if (argc == 12 && !strcmp(argv[1], "write")) {
		const char *dt = argv[3];
		struct c0_tiff_wopts o = { .width = atol(argv[4]), .height = atol(argv[5]), .channels = atol(argv[6]),
					   .slices = atol(argv[7]), .frames = atol(argv[8]), .pixel_size_nm = atof(argv[9]),
					   .z_spacing_nm = atof(argv[10]), .bigtiff = atoi(argv[11]), .software = "tiff_tool" };
		o.dtype = !strcmp(dt, "uint8") ? C0_U8 : !strcmp(dt, "uint16") ? C0_U16 : C0_F32;
		long n = (long)(o.width * o.height * o.channels * o.slices * o.frames);
		float *v = malloc(sizeof(float) * (size_t)n);
		for (long i = 0; i < n; i++)
			v[i] = (float)pattern(dt, i);
		int st = c0_tiff_save_f32(argv[2], &o, v);
		free(v);
		if (st)
			fprintf(stderr, "%s\n", c0_errmsg());
		return st ? 1 : 0;
	}
	fprintf(stderr, "usage: tiff_tool dump IN OUT | write OUT DTYPE W H C Z T PX DZ BIG\n");
	return 2;
}
