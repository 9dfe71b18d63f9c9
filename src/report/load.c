/* An output directory's files for the page: report.json says which steps
 * ran, and each step's files must then be there (mean_qNN.tif may be absent
 * as a whole: runs before it was written). */
#define _POSIX_C_SOURCE 200809L
#include "report/html.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static int path_of(const struct c0_rundir *d, const char *name, char *out, size_t n)
{
	if (snprintf(out, n, "%s/%s", d->dir, name) >= (int)n)
		return c0_fail(C0_EINVAL, "%s: path too long", d->dir);
	return C0_OK;
}

static int exists(const struct c0_rundir *d, const char *name)
{
	char p[4400];
	struct stat s;
	return !path_of(d, name, p, sizeof p) && !stat(p, &s);
}

/* name as planes images of ny x nx (the size of d->grid_file) */
static int load(const struct c0_rundir *d, const char *name, int64_t planes, int ny, int nx, float **img)
{
	char p[4400];
	struct c0_tiff_info in;
	int st = path_of(d, name, p, sizeof p);
	if (!st && !exists(d, name))
		return c0_fail(C0_EIO, "%s: missing (report.json says this run wrote it)", p);
	if (st || (st = c0_tiff_load_f32(p, &in, img)))
		return st;
	if (in.width != nx || in.height != ny || in.pages != planes) {
		free(*img), *img = NULL;
		return c0_fail(C0_EINVAL, "%s: %lldx%lldx%lld, expected %dx%dx%lld (%s's grid, srf and stacks)", p,
			       (long long)in.width, (long long)in.height, (long long)in.pages, nx, ny, (long long)planes, d->grid_file);
	}
	return C0_OK;
}

/* name holds planes images of ny x nx: checked now, read when drawn */
static int check(const struct c0_rundir *d, const char *name, int64_t planes, int ny, int nx)
{
	char p[4400];
	struct c0_tiff_reader *t;
	int st = path_of(d, name, p, sizeof p);
	if (!st && !exists(d, name))
		return c0_fail(C0_EIO, "%s: missing (report.json says this run wrote it)", p);
	if (st || (st = c0_tiff_open(p, &t)))
		return st;
	const struct c0_tiff_info *in = c0_tiff_get_info(t);
	if (in->width != nx || in->height != ny || in->pages != planes)
		st = c0_fail(C0_EINVAL, "%s: %lldx%lldx%lld, expected %dx%dx%lld (%s's grid, srf and stacks)", p,
			     (long long)in->width, (long long)in->height, (long long)in->pages, nx, ny, (long long)planes, d->grid_file);
	c0_tiff_close(t);
	return st;
}

int c0_rundir_plane(const struct c0_rundir *d, const char *name, int64_t plane, float **out)
{
	char p[4400];
	struct c0_tiff_reader *t;
	int st = path_of(d, name, p, sizeof p);
	*out = NULL;
	if (st || (st = c0_tiff_open(p, &t)))
		return st;
	const struct c0_tiff_info *in = c0_tiff_get_info(t);
	if (!(*out = c0_alloc((size_t)in->width * in->height, sizeof **out)))
		st = C0_ENOMEM;
	if (!st && (st = c0_tiff_read_f32(t, plane, *out)))
		free(*out), *out = NULL;
	c0_tiff_close(t);
	return st;
}

static int read_json(struct c0_rundir *d)
{
	char p[4400];
	int st = path_of(d, "report.json", p, sizeof p);
	FILE *f = st ? NULL : fopen(p, "rb");
	if (!f)
		return st ? st : c0_fail(C0_EINVAL, "%s: not a col0rme output directory (no report.json)", d->dir);
	char *text = NULL;
	long len = fseek(f, 0, SEEK_END) ? -1 : ftell(f);
	if (len >= 0 && !fseek(f, 0, SEEK_SET) && (text = malloc((size_t)len + 1)) && fread(text, 1, (size_t)len, f) == (size_t)len) {
		text[len] = 0;
		d->rep = cJSON_Parse(text);
	}
	fclose(f);
	free(text);
	if (!d->rep || !cJSON_IsString(cJSON_GetObjectItemCaseSensitive(d->rep, "command")))
		return c0_fail(C0_EINVAL, "%s: not a col0rme report (no \"command\")", p);
	return C0_OK;
}

/* camera grid, factor, pixel and PSF from "parameters" or "support_parameters" */
static int read_grid(struct c0_rundir *d)
{
	const cJSON *r = d->rep;
	const char *sec = c0_json_at(r, "parameters.pixel_size_nm")             ? "parameters"
			  : c0_json_at(r, "intensity_parameters.pixel_size_nm") ? "intensity_parameters"
										: "support_parameters";
	char k[64];
	snprintf(k, sizeof k, "%s.pixel_size_nm", sec);
	d->grid.pixel_nm = c0_json_num(r, k, 0);
	snprintf(k, sizeof k, "%s.fwhm_nm", sec);
	d->grid.fwhm_nm = c0_json_num(r, k, 0);
	snprintf(k, sizeof k, "%s.srf", sec);
	d->grid.srf = (int)c0_json_num(r, k, 0);
	const cJSON *in = c0_json_at(r, "intensity"), *su = c0_json_at(r, "support");
	d->n = cJSON_IsArray(in) ? cJSON_GetArraySize(in) : cJSON_IsArray(su) ? cJSON_GetArraySize(su) : 0;
	if (d->n > C0_MAX_STACKS)
		return c0_fail(C0_EINVAL, "%s/report.json: %d stacks, at most %d", d->dir, d->n, C0_MAX_STACKS);
	if (d->n && !(d->grid.pixel_nm > 0 && d->grid.fwhm_nm > 0 && d->grid.srf >= 1 && d->grid.srf <= 16))
		return c0_fail(C0_EINVAL, "%s/report.json: no pixel size, FWHM and srf in \"%s\"", d->dir, sec);
	if (!d->n)
		return C0_OK;
	/* the camera grid from the first stack's file */
	char p[4400];
	struct c0_tiff_reader *t;
	const char *first = exists(d, "mean_q01.tif") || !cJSON_IsArray(in) ? "mean_q01.tif" : "background_q01.tif";
	if (!cJSON_IsArray(in) && !exists(d, first))
		return C0_OK;   /* a support run from before mean_qNN.tif: no images */
	d->grid_file = first;
	int st = path_of(d, first, p, sizeof p);
	if (!st && !exists(d, first))
		return c0_fail(C0_EIO, "%s: missing (report.json says this run wrote it)", p);
	if (st || (st = c0_tiff_open(p, &t)))
		return st;
	d->ny = (int)c0_tiff_get_info(t)->height, d->nx = (int)c0_tiff_get_info(t)->width;
	c0_tiff_close(t);
	return C0_OK;
}

static int load_stacks(struct c0_rundir *d)
{
	const int ny = d->ny, nx = d->nx, Ly = ny * d->grid.srf, Lx = nx * d->grid.srf;
	const int inten = c0_json_at(d->rep, "intensity") != NULL;
	int means = 0, st = C0_OK;
	for (int q = 0; q < d->n && !means; q++) {   /* all or none (runs before mean_qNN.tif have none) */
		char name[64];
		snprintf(name, sizeof name, "mean_q%02d.tif", q + 1);
		means = exists(d, name);
	}
	for (int q = 0; q < d->n && !st; q++) {
		char name[64];
		if (means) {
			snprintf(name, sizeof name, "mean_q%02d.tif", q + 1);
			st = load(d, name, 1, ny, nx, &d->mean[q]);
		}
		if (!st && inten) {
			snprintf(name, sizeof name, "intensity_q%02d.tif", q + 1);
			st = check(d, name, 1, Ly, Lx);
		}
		if (!st && inten) {
			snprintf(name, sizeof name, "background_q%02d.tif", q + 1);
			st = load(d, name, 1, ny, nx, &d->bg[q]);
		}
	}
	d->inten = !st && inten;
	if (!st && c0_json_at(d->rep, "render") && !(st = check(d, "render.tif", d->n, Ly, Lx)))
		d->render = 1;
	return st;
}

/* PREFIXdepth.tif and the sum over depth of PREFIXvolume.tif (read plane by plane) */
static int load_depth(struct c0_rundir *d, const char *prefix, struct c0_depthmap *m)
{
	char name[64], p[4400];
	snprintf(name, sizeof name, "%svolume.tif", prefix);
	int st = path_of(d, name, p, sizeof p);
	if (!st && !exists(d, name))
		return c0_fail(C0_EIO, "%s: missing (report.json says this run wrote it)", p);
	struct c0_tiff_reader *t;
	if (st || (st = c0_tiff_open(p, &t)))
		return st;
	const struct c0_tiff_info *in = c0_tiff_get_info(t);
	m->ny = (int)in->height, m->nx = (int)in->width, m->pixel_nm = in->pixel_size_nm;
	const size_t L = (size_t)m->ny * m->nx;
	float *plane = c0_alloc(L, sizeof *plane);
	m->total = c0_alloc(L, sizeof *m->total);
	st = plane && m->total ? C0_OK : C0_ENOMEM;
	for (int64_t z = 0; z < in->pages && !st; z++) {
		st = c0_tiff_read_f32(t, z, plane);
		for (size_t i = 0; i < L && !st; i++)
			m->total[i] += plane[i];
	}
	free(plane);
	c0_tiff_close(t);
	snprintf(name, sizeof name, "%sdepth.tif", prefix);
	return st ? st : load(d, name, 1, m->ny, m->nx, &m->depth);
}

int c0_rundir_load(struct c0_rundir *d, const char *dir)
{
	memset(d, 0, sizeof *d);
	d->dir = dir;
	int st = read_json(d);
	if (!st)
		st = read_grid(d);
	if (!st && d->n && d->ny)
		st = load_stacks(d);
	const cJSON *z = c0_json_at(d->rep, "z_nm");
	if (!st && cJSON_IsArray(z) && cJSON_GetArraySize(z) > 0) {
		int nz = cJSON_GetArraySize(z);
		double a = cJSON_GetArrayItem(z, 0)->valuedouble, b = cJSON_GetArrayItem(z, nz - 1)->valuedouble;
		double dz = nz > 1 ? (b - a) / (nz - 1) : 2 * a;
		d->z0 = a - dz / 2, d->z1 = b + dz / 2;
	}
	if (!st && c0_json_at(d->rep, "matirf"))
		st = load_depth(d, "", &d->vol);
	if (!st && c0_json_at(d->rep, "baseline_matirf"))
		st = load_depth(d, "baseline_", &d->base);
	if (st)
		c0_rundir_free(d);
	return st;
}

void c0_rundir_free(struct c0_rundir *d)
{
	for (int q = 0; q < C0_MAX_STACKS; q++)
		free(d->mean[q]), free(d->bg[q]), free(d->err[q]);
	free(d->vol.depth), free(d->vol.total), free(d->base.depth), free(d->base.total);
	cJSON_Delete(d->rep);
	memset(d, 0, sizeof *d);
}
