/* A stack of frames to stream, from a TIFF file or from a float32 array in
 * memory (T x H x W, row-major), read one frame at a time either way. */
#pragma once
#include "io/tiff.h"

#include <stdint.h>

struct c0_frames {
	int64_t count;                 /* frames */
	int height, width;
	double pixel_nm;               /* 0: uncalibrated */
	char name[256];                /* the path, or what the caller named the array (messages) */
	struct c0_tiff_reader *tiff;   /* a file, or */
	const float *data;             /* an array the caller owns */
	double *sum;                   /* count sums of the raw frames, NaN until one is read whole */
	double *rows, *cols;           /* NULL, or count x height row sums and count x width column sums
				    * (c0_frames_keep_profiles), with sum */
	const float *cal_offset;       /* NULL, or height x width: subtracted from every frame read (camera dark level) */
	const float *cal_scale;        /* NULL, or height x width: then multiplied (per-pixel gain made even) */
};

int c0_frames_open(struct c0_frames *f, const char *path);
/* Wraps data without copying; it must outlive f. */
int c0_frames_wrap(struct c0_frames *f, const float *data, int64_t count, int height, int width, double pixel_nm,
		   const char *name);
/* With cal_offset / cal_scale set (the caller owns them), frames are read as
 * (raw - offset) * scale, the sums too. */
/* Frame t (0-based) into dst (height x width values). Every whole-frame
 * read also notes the frame's sum, so that a later pass that only needs
 * the sums (bleaching) does not read the stack again. */
int c0_frames_read(struct c0_frames *f, int64_t t, float *dst);
/* Rows y0..y0+ny-1 of frame t into dst (ny x width): a file reads only the
 * strips that hold them (each MPI rank reads its own rows). */
int c0_frames_read_rows(struct c0_frames *f, int64_t t, int y0, int ny, float *dst);
/* The raw sum of every frame (the sum of its values, as floats, in double,
 * in pixel order), reading only the frames that no pass has read whole. */
int c0_frames_sums(struct c0_frames *f, const double **sums);
/* From now on every whole-frame read also notes the frame's row and column
 * sums (the frames read before are read again for them). */
int c0_frames_keep_profiles(struct c0_frames *f);
/* A file's frames given back to the kernel's page cache as they are read
 * (c0_tiff_drop_behind); nothing for an array. */
void c0_frames_drop_behind(struct c0_frames *f, int on);
/* The sums, row sums and column sums of every frame (count, count x height,
 * count x width), reading the frames not yet read whole since
 * c0_frames_keep_profiles. */
int c0_frames_profiles(struct c0_frames *f, const double **sums, const double **rows, const double **cols);
void c0_frames_close(struct c0_frames *f);
/* Multi-channel files (ImageJ channels=, OME SizeC or series) as one stack
 * per channel: a path whose file has C > 1 channels of several planes each
 * becomes PATH:c1 .. PATH:cC, in order (or PATH:cK only when channel K >= 1;
 * channels of one plane each are read as one stack unless K is given). *out (allocated,
 * free with c0_frames_expand_free) gets at most max names. */
int c0_frames_expand(char *const *paths, int n, int channel, int max, char ***out, int *nout);
void c0_frames_expand_free(char **names, int n);
