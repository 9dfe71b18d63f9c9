#include "io/frames.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int sums_new(struct c0_frames *f)
{
	if (!(f->sum = c0_alloc((size_t)f->count, sizeof *f->sum))) {
		c0_frames_close(f);
		return C0_ENOMEM;
	}
	for (int64_t t = 0; t < f->count; t++)
		f->sum[t] = NAN;
	return C0_OK;
}

/* rows y0.. of the calibration, in place */
static void calibrate(const struct c0_frames *f, int y0, int ny, float *v)
{
	const size_t o = (size_t)y0 * f->width, n = (size_t)ny * f->width;
	if (f->cal_offset)
		for (size_t i = 0; i < n; i++)
			v[i] -= f->cal_offset[o + i];
	if (f->cal_scale)
		for (size_t i = 0; i < n; i++)
			v[i] *= f->cal_scale[o + i];
}

/* v's 8 interleaved parts' sum, its values also added to c where cols (a
 * constant at each call, so that each caller's loop has no test in it);
 * *ok cleared unless every value passed the bound below */
static inline __attribute__((always_inline)) double sum_parts(const float *v, size_t n, int cols, double *c, int *ok)
{
	const float K = 4194304.f, M = 12582912.f;   /* 2^22, 1.5 2^23 */
	double p[8] = { 0 }, s = 0;
	int good = 1;
	size_t i = 0;
	for (; i + 8 <= n; i += 8)
		for (int k = 0; k < 8; k++) {
			const float u = v[i + k];
			p[k] += u;
			if (cols)
				c[i + k] += u;
			good &= (fabsf(u) <= K) & ((u + M) - M == u);
		}
	for (int k = 0; k < 8; k++)
		s += p[k];
	for (; i < n; i++) {
		s += v[i], good &= (fabsf(v[i]) <= K) & ((v[i] + M) - M == v[i]);
		if (cols)
			c[i] += v[i];
	}
	*ok &= good;
	return s;
}

static double sum_in_order(const float *v, size_t n)
{
	double s = 0;
	for (size_t i = 0; i < n; i++)
		s += v[i];
	return s;
}

/* The sum of v in double, as added in order. Where all values are integers
 * of at most 2^22 in magnitude (n < 2^28) every partial sum is exact, so
 * any order gives that sum bit for bit (uint8/16 frames, uncalibrated):
 * then it comes from 8 interleaved parts (vectorised, and one pass over v
 * with the test); otherwise v is added again in order. In that range
 * v + M - M (float) rounds v to an integer; NaN and infinity fail the bound. */
C0_HOT_SAME static double sum_floats(const float *v, size_t n)
{
	int ok = n < ((size_t)1 << 28);
	const double s = sum_parts(v, n, 0, NULL, &ok);
	return ok ? s : sum_in_order(v, n);
}

/* A row's sum as sum_floats gives it, its values added to the column sums
 * c in the same pass; *exact cleared unless the row took the exact path
 * (element by element, without FMA: the same bits in every build) */
C0_HOT_SAME static double row_sum(const float *v, int n, double *c, int *exact)
{
	int ok = 1;
	const double s = sum_parts(v, (size_t)n, 1, c, &ok);
	*exact &= ok;
	return ok ? s : sum_in_order(v, (size_t)n);
}

static void note_sum(struct c0_frames *f, int64_t t, const float *v)
{
	if (!isnan(f->sum[t]))
		return;   /* noted by an earlier pass: the same raw frame */
	const size_t n = (size_t)f->height * f->width;
	if (!f->rows) {
		f->sum[t] = sum_floats(v, n);
		return;
	}
	/* one pass: the rows' sums and the columns'; where every row's values
	 * are exact integers so is every partial sum of the frame's, and the
	 * rows' sums add up to sum_floats's bit for bit */
	double *r = f->rows + (size_t)t * f->height, *c = f->cols + (size_t)t * f->width, s = 0;
	int exact = n < ((size_t)1 << 28);
	memset(c, 0, (size_t)f->width * sizeof *c);
	for (int y = 0; y < f->height; y++)
		s += r[y] = row_sum(v + (size_t)y * f->width, f->width, c, &exact);
	f->sum[t] = exact ? s : sum_floats(v, n);
}

int c0_frames_keep_profiles(struct c0_frames *f)
{
	if (f->rows)
		return C0_OK;
	f->rows = c0_alloc((size_t)f->count * f->height, sizeof *f->rows);
	f->cols = c0_alloc((size_t)f->count * f->width, sizeof *f->cols);
	if (!f->rows || !f->cols) {
		free(f->rows), free(f->cols), f->rows = f->cols = NULL;
		return C0_ENOMEM;
	}
	for (int64_t t = 0; t < f->count; t++)   /* the sums noted so far have no profiles */
		f->sum[t] = NAN;
	return C0_OK;
}

void c0_frames_drop_behind(struct c0_frames *f, int on)
{
	if (f->tiff)
		c0_tiff_drop_behind(f->tiff, on);
}

int c0_frames_open(struct c0_frames *f, const char *path)
{
	memset(f, 0, sizeof *f);
	int st = c0_tiff_open(path, &f->tiff);
	if (st)
		return st;
	const struct c0_tiff_info *in = c0_tiff_get_info(f->tiff);
	if (in->width > 1 << 20 || in->height > 1 << 20) {
		c0_frames_close(f);
		return c0_fail(C0_EUNSUPPORTED, "%s: %lldx%lld frames are too large", path, (long long)in->width,
			       (long long)in->height);
	}
	f->count = in->pages, f->height = (int)in->height, f->width = (int)in->width;
	f->pixel_nm = in->pixel_size_nm;
	snprintf(f->name, sizeof f->name, "%s", path);
	return sums_new(f);
}

int c0_frames_wrap(struct c0_frames *f, const float *data, int64_t count, int height, int width, double pixel_nm,
		   const char *name)
{
	memset(f, 0, sizeof *f);
	snprintf(f->name, sizeof f->name, "%s", name);
	if (!data || count < 1 || height < 1 || width < 1)
		return c0_fail(C0_EINVAL, "%s: %lld frames of %dx%d pixels at %p: need data and positive sizes", name,
			       (long long)count, width, height, (const void *)data);
	f->data = data, f->count = count, f->height = height, f->width = width, f->pixel_nm = pixel_nm;
	return sums_new(f);
}

int c0_frames_read(struct c0_frames *f, int64_t t, float *dst)
{
	if (f->tiff) {
		int st = c0_tiff_read_f32(f->tiff, t, dst);
		if (!st)
			calibrate(f, 0, f->height, dst), note_sum(f, t, dst);
		return st;
	}
	if (t < 0 || t >= f->count)
		return c0_fail(C0_EINVAL, "%s: frame %lld out of 0..%lld", f->name, (long long)t, (long long)f->count - 1);
	const size_t n = (size_t)f->height * f->width;
	memcpy(dst, f->data + (size_t)t * n, n * sizeof *dst);
	for (size_t i = 0; i < n; i++)   /* as for float files: NaN or infinity would poison every sum */
		if (!isfinite(dst[i]))
			return c0_fail(C0_EINVAL, "%s: frame %lld, pixel (x %zu, y %zu) is %s; non-finite pixels are not supported",
				       f->name, (long long)t + 1, i % (size_t)f->width, i / (size_t)f->width,
				       isnan(dst[i]) ? "NaN" : "infinite");
	calibrate(f, 0, f->height, dst);
	note_sum(f, t, dst);
	return C0_OK;
}

int c0_frames_read_rows(struct c0_frames *f, int64_t t, int y0, int ny, float *dst)
{
	int st;
	if (f->tiff)
		st = c0_tiff_read_rows_f32(f->tiff, t, y0, ny, dst);
	else if (t < 0 || t >= f->count || y0 < 0 || ny < 1 || y0 + ny > f->height)
		return c0_fail(C0_EINVAL, "%s: frame %lld rows %d..%d out of range", f->name, (long long)t, y0, y0 + ny - 1);
	else {
		const size_t n = (size_t)f->height * f->width;
		memcpy(dst, f->data + (size_t)t * n + (size_t)y0 * f->width, (size_t)ny * f->width * sizeof *dst);
		st = C0_OK;
	}
	if (!st)
		calibrate(f, y0, ny, dst);
	if (!st && y0 == 0 && ny == f->height)
		note_sum(f, t, dst);
	return st;
}

int c0_frames_sums(struct c0_frames *f, const double **sums)
{
	*sums = NULL;
	float *v = NULL;
	int st = C0_OK;
	for (int64_t t = 0; t < f->count && !st; t++) {
		if (!isnan(f->sum[t]))
			continue;
		if (!v && !(v = malloc((size_t)f->width * f->height * sizeof *v)))
			st = C0_ENOMEM;
		else
			st = c0_frames_read(f, t, v);
	}
	free(v);
	if (!st)
		*sums = f->sum;
	return st;
}

int c0_frames_profiles(struct c0_frames *f, const double **sums, const double **rows, const double **cols)
{
	*rows = *cols = NULL;
	int st = f->rows ? c0_frames_sums(f, sums) : c0_fail(C0_EINVAL, "%s: no frame profiles kept", f->name);
	if (!st)
		*rows = f->rows, *cols = f->cols;
	return st;
}

void c0_frames_close(struct c0_frames *f)
{
	if (f->tiff)
		c0_tiff_close(f->tiff);
	free(f->sum), free(f->rows), free(f->cols);
	f->tiff = NULL, f->data = NULL, f->sum = f->rows = f->cols = NULL;
}

void c0_frames_expand_free(char **names, int n)
{
	for (int i = 0; names && i < n; i++)
		free(names[i]);
	free(names);
}

static int add(char **names, int *n, int max, const char *path, int k)
{
	if (*n >= max)
		return c0_fail(C0_EINVAL, "%s: more than %d stacks in all (one per angle)", path, max);
	size_t l = strlen(path) + 16;
	if (!(names[*n] = malloc(l)))
		return C0_ENOMEM;
	snprintf(names[*n], l, k ? "%s:c%d" : "%s", path, k);
	(*n)++;
	return C0_OK;
}

int c0_frames_expand(char *const *paths, int n, int channel, int max, char ***out, int *nout)
{
	*out = NULL, *nout = 0;
	if (channel < 0)
		return c0_fail(C0_EINVAL, "channel %d: channels are numbered from 1 (0: all)", channel);
	char **names = calloc((size_t)(max > 0 ? max : 1), sizeof *names);
	if (!names)
		return C0_ENOMEM;
	int st = C0_OK, k = 0;
	for (int i = 0; i < n && !st; i++) {
		struct c0_tiff_reader *r;
		if ((st = c0_tiff_open(paths[i], &r)))
			break;
		const struct c0_tiff_info *in = c0_tiff_get_info(r);
		int64_t nc = in->channel ? 1 : in->channels;
		/* channels of one plane each: a stack that a writer labelled by
		 * channel (tifffile does so for 3D arrays), unless one is asked for */
		if (!channel && nc > 1 && in->file_pages / nc < 2)
			nc = 1;
		c0_tiff_close(r);
		if (channel > nc)
			st = c0_fail(C0_EINVAL, "channel %d: %s has %lld channel%s", channel, paths[i], (long long)nc, nc == 1 ? "" : "s");
		else if (nc == 1)
			st = add(names, &k, max, paths[i], 0);
		for (int c = channel ? channel : 1; !st && nc > 1 && c <= (channel ? channel : nc); c++)
			st = add(names, &k, max, paths[i], c);
	}
	if (st) {
		c0_frames_expand_free(names, k);
		return st;
	}
	*out = names, *nout = k;
	return C0_OK;
}
