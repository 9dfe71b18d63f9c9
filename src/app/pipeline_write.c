/* Writing a result: the files of `col0rme run` (and of the single steps),
 * each calibrated, through an output directory that is rolled back on
 * failure. */
#include "app/pipeline_write.h"
#include "app/result.h"
#include "app/render.h"
#include "app/depthcode.h"
#include "app/drift_out.h"
#include "io/png.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Fine-grid files (intensities, rx, support, depth, render) past this size
 * are written deflated: they live on the support, whose pixels are ~0.1 %
 * of the grid at 2048 x 2048 camera pixels, and their zeros shrink a
 * hundredfold and more (a 2048^2 x 5 angles run wrote 3.4 GB, 8 MB of it the
 * deflated volume). Smaller ones (the demo's) stay plain strips. Dense
 * camera-grid files (means, backgrounds, error maps) are never deflated. */
#define C0_FINE_DEFLATE_BYTES (32LL << 20)

static struct c0_tiff_wopts fine_deflate(struct c0_tiff_wopts o)
{
	o.deflate |= c0_tiff_raw_bytes(&o) > C0_FINE_DEFLATE_BYTES;
	return o;
}

/* A stack of n planes written one at a time, each made by make(arg, k,
 * plane): one plane in memory. lo..hi: the values' range, the display range
 * c0_tiff_save_f32 would set (none when lo > hi). */
typedef int (*plane_fn)(const void *arg, int k, float *plane);

static int save_planes(const char *path, struct c0_tiff_wopts o, float lo, float hi, plane_fn make, const void *arg)
{
	if (lo <= hi)
		o.display_min = lo, o.display_max = hi > lo ? hi : lo + 1;
	float *plane = c0_alloc((size_t)o.height * o.width, sizeof *plane);
	struct c0_tiff_writer *w = NULL;
	int st = plane ? c0_tiff_create(path, &o, &w) : C0_ENOMEM;
	for (int k = 0; !st && k < o.slices; k++)
		if (!(st = make(arg, k, plane)))
			st = c0_tiff_write_plane(w, plane);
	free(plane);
	if (st) {
		c0_tiff_abort(w);
		return st;
	}
	return c0_tiff_commit(w);
}

static int render_plane(const void *r, int q, float *plane)
{
	return c0_render_plane(r, q, plane);
}

/* render.tif plane by plane, each made as it is written (app/render.c) */
static int write_render(const struct c0_result *r, struct c0_outdir *out)
{
	struct c0_tiff_wopts o = { .width = r->Lx, .height = r->Ly, .slices = r->n, .dtype = C0_F32,
				   .pixel_size_nm = r->pixel_nm / r->srf, .software = "col0rme" };
	return save_planes(c0_outdir_file(out, "render.tif"), fine_deflate(o), r->render_lo, r->render_hi, render_plane, r);
}

/* support.tif (the union of the masks) and rx.tif (one plane per support stack) */
static int write_support(const struct c0_result *r, struct c0_outdir *out)
{
	const size_t L = (size_t)r->Ly * r->Lx;
	float *img = c0_alloc(L * (size_t)r->nsup, sizeof *img);
	if (!img)
		return C0_ENOMEM;
	for (size_t i = 0; i < L; i++)
		img[i] = r->mask[i];
	struct c0_tiff_wopts o = { .width = r->Lx, .height = r->Ly, .dtype = C0_U8,
				   .pixel_size_nm = r->pixel_nm / r->srf, .software = "col0rme" };
	struct c0_tiff_wopts od = fine_deflate(o);
	int st = c0_tiff_save_f32(c0_outdir_file(out, "support.tif"), &od, img);
	if (!st) {
		for (int k = 0; k < r->nsup; k++)
			memcpy(img + k * L, r->sres[k].rx, L * sizeof *img);
		o.dtype = C0_F32;
		o.slices = r->nsup;
		od = fine_deflate(o);
		st = c0_tiff_save_f32(c0_outdir_file(out, "rx.tif"), &od, img);
	}
	free(img);
	return st;
}

/* intensity_qNN.tif from x, or from the support's values (app/result.h)
 * through one plane, and background_qNN.tif */
static int write_intensity(const struct c0_result *r, struct c0_outdir *out)
{
	float *plane = NULL;
	int st = C0_OK;
	for (int i = 0; !st && i < r->n; i++) {
		const struct c0_intensity_result *s = &r->ires[i];
		char name[64];
		struct c0_tiff_wopts o = { .width = s->Lx, .height = s->Ly, .dtype = C0_F32,
					   .pixel_size_nm = r->pixel_nm / r->srf, .software = "col0rme" };
		if (!s->x && !plane && !(plane = c0_alloc((size_t)s->Ly * s->Lx, sizeof *plane))) {
			st = C0_ENOMEM;
			break;
		}
		if (!s->x)
			c0_result_x_rows(r, i, 0, s->Ly, plane);
		snprintf(name, sizeof name, "intensity_q%02d.tif", i + 1);
		const struct c0_tiff_wopts od = fine_deflate(o);
		if ((st = c0_tiff_save_f32(c0_outdir_file(out, name), &od, s->x ? s->x : plane)))
			break;
		o.width = s->Nx, o.height = s->Ny, o.pixel_size_nm = r->pixel_nm;
		snprintf(name, sizeof name, "background_q%02d.tif", i + 1);
		st = c0_tiff_save_f32(c0_outdir_file(out, name), &o, s->b);
	}
	free(plane);
	return st;
}

/* mean_qNN.tif: each stack's temporal mean (camera grid), from the
 * intensity step or, without it, the support step (report.html's error map
 * and mean images read them); a pooled support's mean is no stack's */
static int write_means(const struct c0_result *r, struct c0_outdir *out)
{
	const int ny = r->Ly / r->srf, nx = r->Lx / r->srf, nk = r->mean ? r->n : r->npool ? 0 : r->nsup;
	const size_t L = (size_t)ny * nx;
	float *img = r->mean ? NULL : c0_alloc(L, sizeof *img);
	int st = r->mean || img ? C0_OK : C0_ENOMEM;
	for (int k = 0; k < nk && !st; k++) {
		char name[64];
		struct c0_tiff_wopts o = { .width = nx, .height = ny, .dtype = C0_F32, .pixel_size_nm = r->pixel_nm,
					   .software = "col0rme" };
		for (size_t p = 0; img && p < L; p++)
			img[p] = (float)r->sres[k].mean[p];
		snprintf(name, sizeof name, "mean_q%02d.tif", (r->mean ? k : r->sup[k]) + 1);
		st = c0_tiff_save_f32(c0_outdir_file(out, name), &o, r->mean ? r->mean + k * L : img);
	}
	free(img);
	return st;
}

/* A volume past this many bytes whose columns cover less than half the grid
 * is written deflated: mostly-zero planes shrink a hundredfold and more. */
#define C0_VOLUME_DEFLATE_BYTES (256LL << 20)

/* Deflate for a large, mostly-zero volume, and a bound on its file: at
 * most 10 bytes a column value (4 literals of at most 9 bits, and the zero
 * run it breaks resumed by a match of at most 31 bits), the zeros at 50:1
 * (deflate reaches 1000:1 on them) and 64 bytes a strip. A bound too low
 * only makes libtiff refuse the write past 4 GiB, never a broken file. */
static void volume_deflate(const struct c0_matirf_result *v, struct c0_tiff_wopts *o)
{
	const size_t np = (size_t)v->ny * v->nx, plane = np * sizeof(float);
	if (!((int64_t)(plane * v->nz) > C0_VOLUME_DEFLATE_BYTES && (size_t)v->M < np / 2))
		return;
	o->deflate = 1;
	o->max_bytes = (int64_t)v->nz * (int64_t)(10.0 * v->M + plane / 50.0 + 64.0 * v->ny) + (1 << 20);
}

/* The volume, plane by plane from its columns (stages/matirf.h): one
 * plane in memory, never the whole grid times the depth bins. The display
 * range is the values' (0 among them when some pixel is off the columns),
 * as c0_tiff_save_f32 would set it. */
static int volume_plane(const void *v, int j, float *plane)
{
	c0_matirf_plane(v, j, plane);
	return C0_OK;
}

static int save_volume(const char *path, struct c0_tiff_wopts o, const struct c0_matirf_result *v)
{
	const size_t np = (size_t)v->ny * v->nx, n = (size_t)v->M * v->nz;
	volume_deflate(v, &o);
	float lo = (size_t)v->M < np ? 0 : INFINITY, hi = (size_t)v->M < np ? 0 : -INFINITY;
	for (size_t i = 0; i < n; i++) {
		if (v->f[i] < lo) lo = v->f[i];
		if (v->f[i] > hi) hi = v->f[i];
	}
	return save_planes(path, o, lo, hi, volume_plane, v);
}

/* PREFIXvolume.tif, PREFIXdepth.tif (each column's fitted depth; the baseline's: its mean) and PREFIXdepth.png */
static int write_volume(const struct c0_result *r, const struct c0_matirf_result *v, double pixel_nm,
			const char *prefix, struct c0_outdir *out)
{
	char name[128];
	struct c0_tiff_wopts o = { .width = v->nx, .height = v->ny, .slices = v->nz, .dtype = C0_F32,
				   .pixel_size_nm = pixel_nm, .z_spacing_nm = r->dz_nm, .z_origin_nm = r->z0_nm + r->dz_nm / 2,
				   .software = "col0rme" };
	snprintf(name, sizeof name, "%svolume.tif", prefix);
	int st = save_volume(c0_outdir_file(out, name), o, v);
	if (st)
		return st;
	o.slices = 1;
	snprintf(name, sizeof name, "%sdepth.tif", prefix);
	const struct c0_tiff_wopts od = fine_deflate(o);
	if ((st = c0_tiff_save_f32(c0_outdir_file(out, name), &od, v->depth)))
		return st;
	uint8_t *rgb;
	int w, h;
	if ((st = c0_depthcode(v->f, v->pixel, (size_t)v->M, v->nz, v->ny, v->nx, r->z0_nm, r->z0_nm + v->nz * r->dz_nm, &rgb, &w, &h)))
		return st;
	snprintf(name, sizeof name, "%sdepth.png", prefix);
	st = c0_png_write_rgb(c0_outdir_file(out, name), w, h, rgb);
	free(rgb);
	if (!st && v->background) {       /* estimated jointly (standard MA-TIRF path) */
		snprintf(name, sizeof name, "%sbackground.tif", prefix);
		st = c0_tiff_save_f32(c0_outdir_file(out, name), &o, v->background);
	}
	return st;
}

/* drift.csv (nm per frame) and drift.png */
static int write_drift(const struct c0_result *r, struct c0_outdir *out)
{
	char *csv;
	size_t len;
	int st = c0_drift_csv(r->drift, r->pixel_nm, &csv, &len);
	if (st)
		return st;
	st = c0_write_file_named(out, "drift.csv", csv, len);
	free(csv);
	uint8_t *rgb;
	int w, h;
	if (!st && !(st = c0_drift_plot(r->drift, r->pixel_nm, &rgb, &w, &h))) {
		st = c0_png_write_rgb(c0_outdir_file(out, "drift.png"), w, h, rgb);
		free(rgb);
	}
	return st;
}

int c0_result_write_to(const struct c0_result *r, struct c0_outdir *out)
{
	int st = C0_OK;
	c0_mem_stage("writing");
	if (r->drift)
		st = write_drift(r, out);
	if (!st && r->render_sd_nm > 0)
		st = write_render(r, out);
	if (!st && r->sres)
		st = write_support(r, out);
	if (!st && r->ires)
		st = write_intensity(r, out);
	if (!st && (r->mean || r->sres))
		st = write_means(r, out);
	if (!st && r->vol.f)
		st = write_volume(r, &r->vol, r->vol_pixel_nm, "", out);
	if (!st && r->base.f)
		st = write_volume(r, &r->base, r->pixel_nm, "baseline_", out);
	if (!st)
		st = c0_report_write(r->rep, c0_outdir_file(out, "report.json"));
	if (!st)   /* the page, from the files just written (report/html.h) */
		st = c0_report_html(out->stage);
	if (st == C0_ENOMEM && !strstr(c0_errmsg(), "out of memory"))
		c0_mem_fail(0);
	c0_mem_stage(NULL);
	return st;
}

int c0_result_write(const struct c0_result *r, const char *outdir, int force)
{
	struct c0_outdir out;
	int st = c0_outdir_check_inputs(outdir, r->paths, r->n);
	if (!st)
		st = c0_outdir_open(&out, outdir, force);
	if (st)
		return st;
	return c0_outdir_finish(&out, c0_result_write_to(r, &out));
}
