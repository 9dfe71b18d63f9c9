/* The result of a run: its arrays, its report, and the accessors of the
 * public API (include/col0rme.h). */
#include "app/result.h"
#include "core/err.h"
#include "core/mem.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int c0_result_new(const char *command, int n, const char *const *names, const int *is_file, struct c0_result **out)
{
	*out = NULL;
	if (n < 1 || n > C0_MAX_STACKS)
		return c0_fail(C0_EINVAL, "stacks: %d given, expected 1..%d", n, C0_MAX_STACKS);
	struct c0_result *r = c0_alloc(1, sizeof *r);
	if (!r || !(r->names = c0_alloc((size_t)n, sizeof *r->names)) || !(r->rep = c0_report_new(command, 0, NULL))) {
		c0_result_free(r);
		return C0_ENOMEM;
	}
	r->n = n;
	for (int i = 0; i < n; i++) {
		snprintf(r->names[i], sizeof r->names[i], "%s", names[i]);
		r->paths[i] = is_file[i] ? r->names[i] : NULL;
	}
	r->timings = cJSON_AddObjectToObject(r->rep, "timings_s");
	*out = r;
	return C0_OK;
}

void c0_result_set_argv(struct c0_result *r, int argc, char **argv)
{
	cJSON *a = cJSON_CreateArray();
	for (int i = 0; i < argc; i++)
		cJSON_AddItemToArray(a, cJSON_CreateString(argv[i]));
	cJSON_ReplaceItemInObject(r->rep, "argv", a);
}

void c0_result_warn(struct c0_result *r, const char *fmt, ...)
{
	char msg[512];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(msg, sizeof msg, fmt, ap);
	va_end(ap);
	cJSON *w = cJSON_GetObjectItem(r->rep, "warnings");
	if (!w)
		w = cJSON_AddArrayToObject(r->rep, "warnings");
	cJSON_AddItemToArray(w, cJSON_CreateString(msg));
}

void c0_result_free(struct c0_result *r)
{
	if (!r)
		return;
	for (int k = 0; r->sres && k < r->nsup; k++)
		c0_support_result_free(&r->sres[k]);
	free(r->cal_offset), free(r->cal_scale), free(r->cal_noise);
	for (int q = 0; q < C0_MAX_STACKS; q++)
		free(r->cal_noise_q[q]);
	for (int q = 0; q < r->n; q++) {
		if (r->ires)
			c0_intensity_result_free(&r->ires[q]);
		if (r->corrected)
			free(r->corrected[q]);
	}
	for (int q = 0; q < C0_MAX_STACKS; q++)
		free(r->xs[q]), free(r->xnoise[q]);
	c0_pixlist_free(&r->pl);
	free(r->sres), free(r->ires), free(r->corrected), free(r->mask), free(r->names), free(r->json);
	c0_drift_free(r->drift), free(r->render), free(r->mean);
	c0_matirf_result_free(&r->vol), c0_matirf_result_free(&r->base);
	free(r->vol_dense), free(r->base_dense);
	cJSON_Delete(r->rep);
	free(r);
}

int c0_result_nstacks(const struct c0_result *r)
{
	return r->n;
}

static void dims(int *h, int *w, int hv, int wv)
{
	if (h)
		*h = hv;
	if (w)
		*w = wv;
}

const uint8_t *c0_result_support(const struct c0_result *r, int *h, int *w)
{
	dims(h, w, r->Ly, r->Lx);
	return r->mask;
}

const float *c0_result_intensity(const struct c0_result *r, int q, int *h, int *w)
{
	if (!r->ires || q < 0 || q >= r->n)
		return NULL;
	dims(h, w, r->ires[q].Ly, r->ires[q].Lx);
	struct c0_intensity_result *s = &((struct c0_result *)r)->ires[q];   /* the cache is not const to its callers */
	float *x = s->x || !r->xs[q] ? NULL : c0_alloc((size_t)r->Ly * r->Lx, sizeof *x);
	if (x) {
		c0_result_x_rows(r, q, 0, r->Ly, x);   /* from xs, s->x being NULL */
		s->x = x;
	}
	return s->x;
}

const float *c0_result_background(const struct c0_result *r, int q, int *h, int *w)
{
	if (!r->ires || q < 0 || q >= r->n)
		return NULL;
	dims(h, w, r->ires[q].Ny, r->ires[q].Nx);
	return r->ires[q].b;
}

/* the whole volume, made from its columns on the first call and kept in
 * *dense (the result is const to its callers, the cache is not) */
static const float *vol(const struct c0_matirf_result *v, float **dense, int *nz, int *h, int *w)
{
	if (nz)
		*nz = v->nz;
	dims(h, w, v->ny, v->nx);
	if (v->f && !*dense)
		*dense = c0_matirf_dense(v);
	return *dense;
}

const float *c0_result_volume(const struct c0_result *r, int *nz, int *h, int *w)
{
	return vol(&r->vol, &((struct c0_result *)r)->vol_dense, nz, h, w);
}

const float *c0_result_baseline_volume(const struct c0_result *r, int *nz, int *h, int *w)
{
	return vol(&r->base, &((struct c0_result *)r)->base_dense, nz, h, w);
}

const float *c0_result_depth(const struct c0_result *r, int *h, int *w)
{
	dims(h, w, r->vol.ny, r->vol.nx);
	return r->vol.depth;
}

const double *c0_result_z_nm(const struct c0_result *r, int *nz)
{
	if (nz)
		*nz = r->vol.nz;
	return r->vol.z_nm;
}

const char *c0_result_report_json(const struct c0_result *r)
{
	struct c0_result *m = (struct c0_result *)r;   /* the text is a cache of the report */
	if (!m->json)
		m->json = cJSON_Print(r->rep);
	return m->json;
}

void c0_result_x_rows(const struct c0_result *r, int q, int y0, int y1, float *buf)
{
	const size_t W = (size_t)r->Lx;
	if (r->ires[q].x) {
		memcpy(buf, r->ires[q].x + y0 * W, (size_t)(y1 - y0) * W * sizeof *buf);
		return;
	}
	memset(buf, 0, (size_t)(y1 - y0) * W * sizeof *buf);
	for (size_t k = r->pl.row[y0]; k < r->pl.row[y1]; k++)
		buf[r->pl.pix[k] - y0 * W] = r->xs[q][k];
}

float c0_result_x_at(const struct c0_result *r, int q, size_t k)
{
	return r->xs[q] ? r->xs[q][k] : r->ires[q].x[r->pl.pix[k]];
}

double c0_result_x_sum(const struct c0_result *r, int q)
{
	double s = 0;   /* the zeros off the support add nothing */
	if (r->xs[q])
		for (size_t k = 0; k < r->pl.M; k++)
			s += r->xs[q][k];
	else
		for (size_t i = 0; i < (size_t)r->Ly * r->Lx; i++)
			s += r->ires[q].x[i];
	return s;
}

int c0_result_drift_moved(const struct c0_result *r)
{
	struct c0_drift_info di;
	if (!r->drift)
		return 0;
	c0_drift_get_info(r->drift, &di);
	return di.corrected[0] || di.corrected[1];
}

const float *c0_result_noise(const struct c0_result *r, int i)
{
	return r->cal_noise_q[i] ? r->cal_noise_q[i] : r->cal_noise;
}
