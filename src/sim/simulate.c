/* The whole simulation: structure, one acquisition per angle, ground truth. */
#define _POSIX_C_SOURCE 200809L
#include "sim/sim.h"
#include "io/outdir.h"
#include "io/tiff.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define BLOCK 16   /* frames rendered in parallel, written in order */

void c0_sim_result_free(struct c0_sim_result *r)
{
	free(r->em);
	for (int q = 0; q < C0_MAX_ANGLES; q++)
		free(r->angle[q].mean_on), free(r->stack[q]);
	memset(r, 0, sizeof *r);
}

/* var of the noise-free ADU over all pixels and frames; per-frame partial
 * sums reduced in frame order, so the result does not depend on threads */
static double noisefree_variance(const struct c0_sim_conf *c, const struct c0_sim_scene *s)
{
	const size_t n = (size_t)c->width * c->height;
	double *s1 = c0_alloc((size_t)c->frames, sizeof *s1), *s2 = c0_alloc((size_t)c->frames, sizeof *s2);
	if (!s1 || !s2) {
		free(s1), free(s2);
		return NAN;
	}
	int fail = 0;
#pragma omp parallel
	{
		double *ph = malloc(n * sizeof *ph);
		if (!ph) {
#pragma omp atomic write
			fail = 1;
		}
#pragma omp for schedule(dynamic, 4)
		for (int t = 0; t < c->frames; t++) {
			if (!ph)
				continue;
			c0_sim_render(s, t, ph);
			double a = 0, b = 0;
			for (size_t i = 0; i < n; i++) {
				double v = c->gain * ph[i] + c->offset;
				a += v, b += v * v;
			}
			s1[t] = a, s2[t] = b;
		}
		free(ph);
	}
	double a = 0, b = 0, N = (double)n * c->frames;
	for (int t = 0; t < c->frames; t++)
		a += s1[t], b += s2[t];
	free(s1), free(s2);
	return fail ? NAN : b / N - (a / N) * (a / N);
}

/* To the TIFF at path, or with path NULL into mem (frames x H x W). */
static int write_stack(const struct c0_sim_conf *c, const struct c0_sim_cam *cam, int q, const struct c0_sim_scene *s, double read_noise,
		       const char *path, float *mem, struct c0_progress *pr, double done0)
{
	const size_t n = (size_t)c->width * c->height;
	struct c0_tiff_wopts o = { .width = c->width, .height = c->height, .frames = c->frames, .dtype = C0_U16,
				   .pixel_size_nm = c->pixel_nm, .frame_interval_s = 1 / c->fps, .software = "col0rme simulate" };
	struct c0_tiff_writer *w = NULL;
	int st = path ? c0_tiff_create(path, &o, &w) : C0_OK;
	if (st)
		return st;
	float *adu = mem ? NULL : c0_alloc(n * BLOCK, sizeof *adu);
	double *ph = c0_alloc(n * BLOCK, sizeof *ph);
	if ((!adu && !mem) || !ph)
		st = C0_ENOMEM;
	for (int t0 = 0; !st && t0 < c->frames; t0 += BLOCK) {
		int nb = c->frames - t0 < BLOCK ? c->frames - t0 : BLOCK;
		float *a = mem ? mem + (size_t)t0 * n : adu;
#pragma omp parallel for schedule(dynamic, 1)
		for (int b = 0; b < nb; b++) {
			c0_sim_render(s, t0 + b, ph + b * n);
			c0_sim_expose(c, cam, q, t0 + b, read_noise, ph + b * n, a + b * n);
		}
		for (int b = 0; b < nb && !st && w; b++)
			st = c0_tiff_write_plane(w, a + b * n);
		c0_progress_update(pr, done0 + t0 + nb);
	}
	free(adu), free(ph);
	if (!w)
		return st;
	if (st) {
		c0_tiff_abort(w);
		return st;
	}
	return c0_tiff_commit(w);
}

static int save(struct c0_outdir *out, const char *name, int w, int h, double px, enum c0_dtype t, const float *v)
{
	struct c0_tiff_wopts o = { .width = w, .height = h, .dtype = t, .pixel_size_nm = px, .software = "col0rme simulate" };
	return c0_tiff_save_f32(c0_outdir_file(out, name), &o, v);
}

static int write_truth(const struct c0_sim_conf *c, struct c0_outdir *out, const struct c0_sim_result *res,
		       double *const *bg)
{
	const int r = c->srf, FW = c->width * r, FH = c->height * r, nq = c->nangles;
	const double fp = c->pixel_nm / r;
	const size_t nf = (size_t)FW * FH;
	float *img = c0_alloc(nf, sizeof *img);
	double *zw = c0_alloc(nf, sizeof *zw), *ww = c0_alloc(nf, sizeof *ww);
	int st = img && zw && ww ? C0_OK : C0_ENOMEM;
	char name[64];
	for (int q = 0; q < nq && !st; q++) {
		const double p = res->angle[q].p_per_nm;
		memset(img, 0, nf * sizeof *img);
		for (int e = 0; e < res->nemitters; e++) {
			const struct c0_emitter *m = &res->em[e];
			size_t i = (size_t)(m->y / fp) * FW + (size_t)(m->x / fp);
			img[i] += (float)(c->gain * m->brightness * res->angle[q].i0_rel * exp(-p * m->z) * res->angle[q].mean_on[e]);
		}
		snprintf(name, sizeof name, "truth_intensity_q%02d.tif", q + 1);
		st = save(out, name, FW, FH, fp, C0_F32, img);
		if (st)
			break;
		float *b = img;   /* reuse the buffer for the coarse background */
		for (int i = 0; i < c->width * c->height; i++)
			b[i] = (float)(c->offset + c->gain * bg[q][i]);
		snprintf(name, sizeof name, "truth_background_q%02d.tif", q + 1);
		st = save(out, name, c->width, c->height, c->pixel_nm, C0_F32, b);
	}
	if (!st) {
		/* depth: brightness-weighted mean z of the emitters seen in each fine pixel */
		for (int e = 0; e < res->nemitters; e++) {
			const struct c0_emitter *m = &res->em[e];
			double seen = 0;
			for (int q = 0; q < nq; q++)
				seen += res->angle[q].mean_on[e];
			if (seen <= 0)
				continue;
			size_t i = (size_t)(m->y / fp) * FW + (size_t)(m->x / fp);
			zw[i] += m->brightness * m->z;
			ww[i] += m->brightness;
		}
		for (size_t i = 0; i < nf; i++)
			img[i] = ww[i] > 0 ? (float)(zw[i] / ww[i]) : 0;
		st = save(out, "truth_depth.tif", FW, FH, fp, C0_F32, img);
	}
	if (!st) {
		for (size_t i = 0; i < nf; i++)
			img[i] = ww[i] > 0;
		st = save(out, "truth_support.tif", FW, FH, fp, C0_U8, img);
	}
	free(img), free(zw), free(ww);
	return st;
}

static int write_csv(const struct c0_sim_conf *c, struct c0_outdir *out, const struct c0_sim_result *res)
{
	size_t cap = (size_t)res->nemitters * (64 + 12 * c->nangles) + 256, k = 0;
	char *buf = c0_alloc(cap, 1);
	if (!buf)
		return C0_ENOMEM;
	k += (size_t)snprintf(buf + k, cap - k, "x_nm,y_nm,z_nm,brightness");
	for (int q = 0; q < c->nangles; q++)
		k += (size_t)snprintf(buf + k, cap - k, ",on_q%02d", q + 1);
	k += (size_t)snprintf(buf + k, cap - k, "\n");
	for (int e = 0; e < res->nemitters; e++) {
		const struct c0_emitter *m = &res->em[e];
		k += (size_t)snprintf(buf + k, cap - k, "%.3f,%.3f,%.3f,%.3f", m->x, m->y, m->z, m->brightness);
		for (int q = 0; q < c->nangles; q++)
			k += (size_t)snprintf(buf + k, cap - k, ",%.6f", res->angle[q].mean_on[e]);
		k += (size_t)snprintf(buf + k, cap - k, "\n");
	}
	int st = k < cap ? c0_write_file_named(out, "emitters.csv", buf, k) : c0_fail(C0_ENOMEM, "emitters.csv: buffer too small");
	free(buf);
	return st;
}

/* drift_truth.csv: the sample's displacement per frame (nm) */
static int write_drift(const struct c0_sim_conf *c, struct c0_outdir *out)
{
	size_t cap = (size_t)c->nangles * c->frames * 64 + 64, k = 0;
	char *buf = c0_alloc(cap, 1);
	double *dx = c0_alloc((size_t)c->frames, sizeof *dx), *dy = c0_alloc((size_t)c->frames, sizeof *dy);
	int st = buf && dx && dy ? C0_OK : C0_ENOMEM;
	if (!st) {
		k += (size_t)snprintf(buf + k, cap - k, "stack,frame,dx_nm,dy_nm\n");
		for (int q = 0; q < c->nangles; q++) {
			c0_sim_drift(c, q, dx, dy);
			for (int t = 0; t < c->frames; t++)
				k += (size_t)snprintf(buf + k, cap - k, "%d,%d,%.3f,%.3f\n", q + 1, t + 1, dx[t], dy[t]);
		}
		st = k < cap ? c0_write_file_named(out, "drift_truth.csv", buf, k) : c0_fail(C0_ENOMEM, "drift_truth.csv: buffer too small");
	}
	free(buf), free(dx), free(dy);
	return st;
}

int c0_simulate(const struct c0_sim_conf *c, struct c0_outdir *out, struct c0_sim_result *res)
{
	memset(res, 0, sizeof *res);
	double t0 = c0_now();
	int st = c0_sim_check(c);
	if (!st)
		st = c0_sim_structure(c, &res->em, &res->nemitters);
	if (st)
		return st;
	double *bg[C0_MAX_ANGLES] = { 0 };
	struct c0_sim_cam cam;
	if ((st = c0_sim_cam_new(c, &cam)))
		return st;
	const double cam_sd = c->camera == C0_CAM_SCMOS ? c0_sim_cam_median_sd(c, &cam) : 0;
	struct c0_progress pr;
	c0_progress_begin(&pr, "simulate", (double)c->nangles * c->frames * (c->snr_db > 0 ? 2 : 1));
	double done = 0;
	res->bleach_rate = c0_sim_bleach_rate(c);
	const double p_on = c->tau_on_ms / (c->tau_on_ms + c->tau_off_ms);
	for (int q = 0; q < c->nangles && !st; q++) {
		struct c0_sim_angle *a = &res->angle[q];
		c0_sim_excitation(c, q, &a->p_per_nm, &a->i0_rel);
		a->depth_nm = a->p_per_nm > 0 ? 1 / a->p_per_nm : INFINITY;
		a->t_start_s = (double)c0_sim_slot(c, q, 0) / c->fps;
		struct c0_sim_scene *s;
		if ((st = c0_sim_scene_new(c, res->em, res->nemitters, q, &s)))
			break;
		a->mean_on = c0_alloc((size_t)res->nemitters, sizeof(double));
		bg[q] = c0_alloc((size_t)c->width * c->height, sizeof(double));
		if (!a->mean_on || !bg[q]) {
			c0_sim_scene_free(s);
			st = C0_ENOMEM;
			break;
		}
		const float *on = c0_sim_scene_onfrac(s);
		double all = 0;
		for (int e = 0; e < res->nemitters; e++) {
			double m = 0;
			for (int t = 0; t < c->frames; t++)
				m += on[(size_t)t * res->nemitters + e];
			a->mean_on[e] = m / c->frames;
			all += a->mean_on[e];
		}
		a->bleach_factor = all / res->nemitters / p_on;
		memcpy(bg[q], c0_sim_scene_background(s), sizeof(double) * c->width * c->height);
		a->read_noise = c->read_noise;
		double var = NAN;
		if (c->snr_db > 0) {
			var = noisefree_variance(c, s);
			a->read_noise = sqrt(var / pow(10, c->snr_db / 10));
			done += c->frames;
		}
		const double rn = a->read_noise;   /* what the camera uses; an sCMOS reports its median */
		if (c->camera == C0_CAM_SCMOS)
			a->read_noise = cam_sd;
		a->snr_db = a->read_noise > 0 && var == var ? 10 * log10(var / (a->read_noise * a->read_noise)) : INFINITY;
		char name[64];
		snprintf(name, sizeof name, "stack_q%02d.tif", q + 1);
		if (!out && !(res->stack[q] = c0_alloc((size_t)c->frames * c->width * c->height, sizeof(float))))
			st = C0_ENOMEM;
		else
			st = write_stack(c, &cam, q, s, rn, out ? c0_outdir_file(out, name) : NULL, res->stack[q], &pr, done);
		done += c->frames;
		c0_sim_scene_free(s);
	}
	c0_progress_end(&pr);
	if (!st && out)
		st = write_truth(c, out, res, bg);
	if (!st && out)
		st = write_csv(c, out, res);
	if (!st && out)
		st = c0_sim_write_camera(c, &cam, out);
	c0_sim_cam_free(&cam);
	if (!st && (c->drift_nm[0] != 0 || c->drift_nm[1] != 0))
		st = write_drift(c, out);
	for (int q = 0; q < C0_MAX_ANGLES; q++)
		free(bg[q]);
	res->seconds = c0_now() - t0;
	return st;
}
