/* Cameras other than the plain CCD: sCMOS (per-pixel offset, gain and read
 * noise, written as the truth calibration with dark frames to practise on)
 * and EMCCD (Gamma-distributed electron multiplication). The CCD stays in
 * render.c's c0_sim_camera, untouched. */
#include "sim/sim.h"
#include "io/outdir.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/order.h"
#include "core/rng.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* the same stream ids as render.c: 3 camera, 5 the noisy pixels' choice, 6
 * their noise; new: 7 the sCMOS maps, 8 the dark frames */
#define STREAM(kind, q, i) (((uint64_t)(kind) << 56) | ((uint64_t)(q) << 40) | (uint64_t)(i))

static const char *const CAMERAS[] = { "ccd", "emccd", "scmos" };

const char *c0_sim_camera_name(int camera)
{
	return camera >= 0 && camera < 3 ? CAMERAS[camera] : "?";
}

int c0_sim_camera_parse(const char *name, int *camera)
{
	for (int k = 0; k < 3; k++)
		if (!strcmp(name, CAMERAS[k]))
			return *camera = k, C0_OK;
	return c0_fail(C0_EINVAL, "camera %s: expected ccd, emccd or scmos", name);
}

int c0_sim_camera_check(const struct c0_sim_conf *c)
{
	if (c->camera < C0_CAM_CCD || c->camera > C0_CAM_SCMOS)
		return c0_fail(C0_EINVAL, "camera: unknown camera %d", c->camera);
	if (!(c->em_gain >= 1 && c->em_gain <= 1e4))
		return c0_fail(C0_EINVAL, "em_gain %g: must be in [1, 10000]", c->em_gain);
	if (!(c->offset_sd >= 0 && c->offset_sd <= 1e3) || !(c->gain_cv >= 0 && c->gain_cv <= 0.3))
		return c0_fail(C0_EINVAL, "offset_sd %g / gain_cv %g: need 0 <= offset_sd <= 1000 ADU and 0 <= gain_cv <= 0.3",
			       c->offset_sd, c->gain_cv);
	if (!(c->read_e >= 0 && c->read_e <= 1e3) || !(c->read_spread >= 0 && c->read_spread <= 2))
		return c0_fail(C0_EINVAL, "read_e %g / read_spread %g: need 0 <= read_e <= 1000 e- and 0 <= read_spread <= 2",
			       c->read_e, c->read_spread);
	if (c->dark_frames < 0 || c->dark_frames > 100000)
		return c0_fail(C0_EINVAL, "dark_frames %d: must be 0 to 100000", c->dark_frames);
	return C0_OK;
}

void c0_sim_cam_free(struct c0_sim_cam *m)
{
	free(m->offset), free(m->gain), free(m->sd), free(m->hot);
	memset(m, 0, sizeof *m);
}

int c0_sim_cam_new(const struct c0_sim_conf *c, struct c0_sim_cam *m)
{
	memset(m, 0, sizeof *m);
	if (c->camera != C0_CAM_SCMOS)
		return C0_OK;
	const size_t n = (size_t)c->width * c->height;
	m->offset = c0_alloc(n, sizeof *m->offset);
	m->gain = c0_alloc(n, sizeof *m->gain);
	m->sd = c0_alloc(n, sizeof *m->sd);
	m->hot = c0_alloc(n, sizeof *m->hot);
	if (!m->offset || !m->gain || !m->sd || !m->hot) {
		c0_sim_cam_free(m);
		return C0_ENOMEM;
	}
	struct c0_rng r, hot;
	c0_rng_init(&r, c->seed, STREAM(7, 0, 0));
	c0_rng_init(&hot, c->seed, STREAM(5, 0, 0));   /* the same noisy pixels as the CCD's */
	for (size_t i = 0; i < n; i++) {
		double g = c->gain * (1 + c->gain_cv * c0_rng_normal(&r));
		m->gain[i] = (float)fmax(0.5 * c->gain, g);
		m->offset[i] = (float)(c->offset + c->offset_sd * c0_rng_normal(&r));
		/* read-noise sd log-normal around its median (a long tail of noisy pixels) */
		m->sd[i] = (float)(m->gain[i] * c->read_e * exp(c->read_spread * c0_rng_normal(&r)));
		m->hot[i] = c->hot_fraction > 0 && c0_rng_uniform(&hot) < c->hot_fraction;
	}
	return C0_OK;
}

double c0_sim_cam_variance(const struct c0_sim_conf *c, const struct c0_sim_cam *m, size_t i)
{
	/* Gaussian read noise, the noisy pixels' own, and the rounding to whole ADU */
	return (double)m->sd[i] * m->sd[i] + (m->hot[i] ? c->hot_sd * c->hot_sd : 0) + 1.0 / 12;
}

double c0_sim_cam_median_sd(const struct c0_sim_conf *c, const struct c0_sim_cam *m)
{
	return c0_median_of(m->sd, (size_t)c->width * c->height);
}

/* Gamma(k, 1) for a whole k >= 1 (Marsaglia and Tsang 2000) */
static double gamma_k(struct c0_rng *r, double k)
{
	const double d = k - 1.0 / 3, cc = 1 / sqrt(9 * d);
	for (;;) {
		double x, v;
		do {
			x = c0_rng_normal(r);
			v = 1 + cc * x;
		} while (v <= 0);
		v = v * v * v;
		double u = c0_rng_uniform(r);
		if (u < 1 - 0.0331 * x * x * x * x || log(u) < 0.5 * x * x + d * (1 - v + log(v)))
			return d * v;
	}
}

static float to_adu(double v)
{
	v = nearbyint(v);
	return (float)(v < 0 ? 0 : v > 65535 ? 65535 : v);
}

void c0_sim_expose(const struct c0_sim_conf *c, const struct c0_sim_cam *m, int q, int t, double read_noise,
		   const double *ph, float *adu)
{
	if (c->camera == C0_CAM_CCD) {
		c0_sim_camera(c, q, t, read_noise, ph, adu);
		return;
	}
	struct c0_rng r, hot, hn;
	c0_rng_init(&r, c->seed, STREAM(3, q, t));
	c0_rng_init(&hot, c->seed, STREAM(5, 0, 0));
	c0_rng_init(&hn, c->seed, STREAM(6, q, t));
	for (size_t i = 0; i < (size_t)c->width * c->height; i++) {
		uint64_t k = c0_rng_poisson(&r, ph[i]);
		double v;
		if (c->camera == C0_CAM_SCMOS) {
			v = m->gain[i] * (double)k + m->offset[i] + m->sd[i] * c0_rng_normal(&r);
			if (m->hot[i])
				v += c->hot_sd * c0_rng_normal(&hn);
		} else {
			/* EMCCD: k electrons multiplied into Gamma(k, G) (excess noise factor sqrt 2), read
			 * out with the amplifier's noise, which the gain divides when referred to photons */
			double e = k ? gamma_k(&r, (double)k) : 0;
			v = c->gain * e + c->offset + read_noise / c->em_gain * c0_rng_normal(&r);
			if (c->hot_fraction > 0 && c0_rng_uniform(&hot) < c->hot_fraction)
				v += c->hot_sd * c0_rng_normal(&hn);
		}
		adu[i] = to_adu(v);
	}
}

static int save_map(struct c0_outdir *out, const struct c0_sim_conf *c, const char *name, const float *v)
{
	struct c0_tiff_wopts o = { .width = c->width, .height = c->height, .dtype = C0_F32, .pixel_size_nm = c->pixel_nm,
				   .software = "col0rme simulate" };
	return c0_tiff_save_f32(c0_outdir_file(out, name), &o, v);
}

int c0_sim_write_camera(const struct c0_sim_conf *c, const struct c0_sim_cam *m, struct c0_outdir *out)
{
	if (c->camera != C0_CAM_SCMOS)
		return C0_OK;
	const size_t n = (size_t)c->width * c->height;
	float *v = c0_alloc(n, sizeof *v);
	if (!v)
		return C0_ENOMEM;
	for (size_t i = 0; i < n; i++)
		v[i] = (float)c0_sim_cam_variance(c, m, i);
	int st = save_map(out, c, "calib_offset.tif", m->offset);
	if (!st)
		st = save_map(out, c, "calib_variance.tif", v);
	if (!st)
		st = save_map(out, c, "calib_gain.tif", m->gain);
	struct c0_tiff_wopts o = { .width = c->width, .height = c->height, .frames = c->dark_frames, .dtype = C0_U16,
				   .pixel_size_nm = c->pixel_nm, .frame_interval_s = 1 / c->fps, .software = "col0rme simulate" };
	struct c0_tiff_writer *w = NULL;
	if (!st && c->dark_frames > 0)
		st = c0_tiff_create(c0_outdir_file(out, "dark.tif"), &o, &w);
	for (int t = 0; !st && w && t < c->dark_frames; t++) {
		struct c0_rng r, hn;
		c0_rng_init(&r, c->seed, STREAM(8, 0, t));
		c0_rng_init(&hn, c->seed, STREAM(8, 1, t));
		for (size_t i = 0; i < n; i++)
			v[i] = to_adu(m->offset[i] + m->sd[i] * c0_rng_normal(&r) + (m->hot[i] ? c->hot_sd * c0_rng_normal(&hn) : 0));
		st = c0_tiff_write_plane(w, v);
	}
	if (w)
		st = st ? (c0_tiff_abort(w), st) : c0_tiff_commit(w);
	free(v);
	return st;
}
