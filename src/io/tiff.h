/* TIFF stacks through libtiff.
 *
 * Reading streams one plane at a time (nothing needs the whole stack in
 * memory) and converts any supported sample type to float or double.
 * Writing produces ImageJ hyperstacks (calibrated, Fiji opens them as such)
 * under a temporary name that is renamed on success, so a failure never
 * leaves a half-written file. */
#pragma once
#include <stddef.h>
#include <stdint.h>

enum c0_dtype { C0_U8, C0_U16, C0_U32, C0_I16, C0_I32, C0_F32, C0_F64 };

const char *c0_dtype_name(enum c0_dtype t);
size_t c0_dtype_size(enum c0_dtype t);

struct c0_tiff_info {
	int64_t width, height;
	int64_t pages;                 /* planes in the file */
	int64_t channels, slices, frames; /* ImageJ hyperstack shape, 1 if absent */
	enum c0_dtype dtype;
	double pixel_size_nm;          /* 0 when the file has no calibration */
	double z_spacing_nm;           /* 0 when absent */
	char unit[16];                 /* calibration unit as written in the file */
	int bigtiff, big_endian, tiled;
	char compression[16];
	int imagej, ome;
	int channel;                   /* 1-based channel this reader shows (pages = its frames), 0: the whole file */
	int64_t file_pages;            /* planes in the file, all channels */
};

struct c0_tiff_reader;

/* path may name one channel of a multi-channel file as FILE:cK (K 1-based;
 * used only when no file is called that): the reader then shows that
 * channel's planes in order as its pages. Channels come from the ImageJ
 * description (channels=, planes in CZT order) or the OME-XML (SizeC with
 * its DimensionOrder; several Image series of one size count as channels). */
int c0_tiff_open(const char *path, struct c0_tiff_reader **out);
/* Splits FILE:cK into FILE and K; returns 0 (channel 0) when path has no such suffix. */
int c0_tiff_channel_spec(const char *path, char *file, size_t n);
/* Shows channel k (1-based) only; 0 shows the whole file again. */
int c0_tiff_select_channel(struct c0_tiff_reader *r, int k);
/* Reading float samples refuses NaN and infinity (naming the frame and the
 * pixel) unless this is called ('info' describes such files). */
void c0_tiff_allow_nonfinite(struct c0_tiff_reader *r);
/* on: the file's planes, once read whole, are given back to the kernel's
 * page cache as the reading goes on (posix_fadvise DONTNEED), for files that
 * will not all stay cached: what is read is the same. Off by default. */
void c0_tiff_drop_behind(struct c0_tiff_reader *r, int on);
/* Reads from memory (the buffer must outlive the reader); name is for messages. */
int c0_tiff_open_mem(const void *data, size_t size, const char *name, struct c0_tiff_reader **out);
const struct c0_tiff_info *c0_tiff_get_info(const struct c0_tiff_reader *r);
/* Plane `page` (0-based) into dst (width*height values, row-major). Sequential
 * access is cheapest; any order works. */
int c0_tiff_read_f32(struct c0_tiff_reader *r, int64_t page, float *dst);
int c0_tiff_read_f64(struct c0_tiff_reader *r, int64_t page, double *dst);
/* Rows y0 .. y0+ny-1 of plane `page` into dst (ny*width values): only the
 * strips or tiles that hold them are read. */
int c0_tiff_read_rows_f32(struct c0_tiff_reader *r, int64_t page, int64_t y0, int64_t ny, float *dst);
void c0_tiff_close(struct c0_tiff_reader *r);

/* Whole-file convenience: allocates pages*height*width floats. */
int c0_tiff_load_f32(const char *path, struct c0_tiff_info *info, float **data);

struct c0_tiff_wopts {
	int64_t width, height;
	int64_t channels, slices, frames;  /* 0 is taken as 1; planes in XYCZT order */
	enum c0_dtype dtype;               /* C0_U8, C0_U16 or C0_F32 */
	double pixel_size_nm;              /* 0: uncalibrated */
	double z_spacing_nm;               /* 0: not written */
	double z_origin_nm;                /* z of the first plane (with z_spacing_nm), ImageJ's zorigin */
	double frame_interval_s;           /* 0: not written */
	double display_min, display_max;   /* both 0: not written */
	int bigtiff;                       /* 1: force BigTIFF; 0: only when needed */
	const char *software;              /* Software tag, e.g. the command line */
	/* 1: deflate (zlib) in strips of about 1 MiB, which ImageJ, Fiji and
	 * tifffile read; pays for mostly-zero planes (a volume on a sparse
	 * support: 5.4 GB of floats in 0.1 GB) */
	int deflate;
	/* with deflate, a bound on the bytes written (0: the uncompressed size),
	 * which decides BigTIFF: classic TIFF where it fits, as ImageJ reads no BigTIFF */
	int64_t max_bytes;
};

struct c0_tiff_writer;

/* The planes o declares (channels x slices x frames, each at least 1), and
 * their uncompressed bytes. */
int64_t c0_tiff_planes(const struct c0_tiff_wopts *o);
int64_t c0_tiff_raw_bytes(const struct c0_tiff_wopts *o);
/* BigTIFF is chosen by this rule: classic TIFF offsets end at 4 GiB. */
int c0_tiff_needs_bigtiff(int64_t data_bytes);
int c0_tiff_create(const char *path, const struct c0_tiff_wopts *o, struct c0_tiff_writer **out);
/* Planes are given as float and converted (rounded and clamped for integers). */
int c0_tiff_write_plane(struct c0_tiff_writer *w, const float *plane);
/* Closes and renames into place; fails if not every plane was written. */
int c0_tiff_commit(struct c0_tiff_writer *w);
/* Closes and deletes the temporary file. */
void c0_tiff_abort(struct c0_tiff_writer *w);

/* Whole-array convenience with display range from the data. */
int c0_tiff_save_f32(const char *path, const struct c0_tiff_wopts *o, const float *data);
