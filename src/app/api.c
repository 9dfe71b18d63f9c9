/* The public calls besides c0_run (include/col0rme.h): the conf on the
 * heap, single steps, and the simulator in memory, for programs and the
 * Python package. Thin wrappers: the method lives in sim/ and stages/. */
#include "col0rme.h"
#include "app/result.h"
#include "app/pipeline_conf.h"
#include "app/steps.h"
#include "app/steps_matirf.h"
#include "app/stacks.h"
#include "app/pipeline.h"
#include "sim/sim.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct c0_run_conf *c0_run_conf_new(void)
{
	struct c0_run_conf *c = c0_alloc(1, sizeof *c);
	if (c)
		c0_run_conf_init(c);
	return c;
}

void c0_run_conf_set_progress(struct c0_run_conf *c, c0_progress_fn fn, void *user)
{
	c->progress = fn, c->progress_user = user;
}

void c0_run_conf_free(struct c0_run_conf *c)
{
	free(c);
}

static int support(const struct c0_run_conf *c, const struct c0_stage_confs *sc, struct c0_frames *f, int n,
		   struct c0_result *r, const void *arg)
{
	(void)arg;
	r->nsup = n;
	for (int i = 0; i < n; i++)
		r->sup[i] = i;
	r->pixel_nm = sc->support.grid.pixel_nm, r->srf = sc->support.grid.srf;
	int st = c->drift ? c0_progress_stage("drift") : C0_OK;
	if (!st && c->drift)
		st = c0_step_drift(r, &sc->drift, c->nangles > 0 ? &sc->bleach : NULL, f, n);
	if (!st)
		st = c0_progress_stage("support");
	return st ? st : c0_step_support(r, &sc->support, f, c->support_pool);
}

int c0_run_support(const struct c0_run_conf *c, const struct c0_stack *stacks, int n, struct c0_result **out)
{
	return c0_pipe_run("support", c, stacks, n, support, NULL, out);
}

int c0_run_matirf(const struct c0_run_conf *c, const float *const *images, int n, int h, int w, struct c0_result **out)
{
	*out = NULL;
	if (!c || !images || n < 1 || n > C0_MAX_STACKS || h < 1 || w < 1)
		return c0_fail(C0_EINVAL, "images: %d of %dx%d given, expected 1..%d images of at least 1x1", n, h, w,
			       C0_MAX_STACKS);
	for (int q = 0; q < n; q++)
		if (!images[q])
			return c0_fail(C0_EINVAL, "images: image %d is NULL", q + 1);
	struct c0_matirf_conf mc;
	c0_run_conf_matirf(c, &mc);
	int st = c0_run_conf_matirf_check(c, &mc, n);
	if (st)
		return st;
	char names[C0_MAX_STACKS][16];
	const char *np[C0_MAX_STACKS];
	int is_file[C0_MAX_STACKS] = { 0 };
	for (int q = 0; q < n; q++)
		snprintf(names[q], sizeof names[q], "image %d", q + 1), np[q] = names[q];
	struct c0_result *r;
	if ((st = c0_result_new("matirf", n, np, is_file, &r)))
		return st;
	c0_warn_assumed_optics(r, c);
	struct c0_progress_sink ps;
	c0_progress_attach(&ps, c->progress, c->progress_user);
	struct c0_matirf_raw raw;
	if (!(st = c0_progress_stage("matirf")) && !(st = c0_run_conf_matirf_raw(c, c->pixel_nm, &mc, &raw)))
		st = c0_step_matirf_raw(r, &raw, &mc, images, h, w, c->pixel_nm);
	if ((st = c0_progress_detach(&ps, st))) {
		c0_result_free(r);
		return st;
	}
	*out = r;
	return C0_OK;
}

struct c0_simulation {
	struct c0_sim_conf c;
	int z_set, ran;
	double angles[C0_MAX_ANGLES];
	struct c0_sim_result res;
	double *emitters;   /* nemitters x 4 */
};

enum ptype { P_INT, P_U64, P_DOUBLE, P_FLAG };
struct param { const char *name; enum ptype type; size_t off; };
#define F(name, type, field) { name, type, offsetof(struct c0_sim_conf, field) }
/* The names of sim.json's parameters; the CLI's flags with '_' for '-'. */
static const struct param params[] = {
	F("seed", P_U64, seed), F("width", P_INT, width), F("height", P_INT, height), F("frames", P_INT, frames),
	F("pixel_nm", P_DOUBLE, pixel_nm), F("fwhm_nm", P_DOUBLE, fwhm_nm), F("srf", P_INT, srf),
	F("n_glass", P_DOUBLE, tirf.n_glass), F("n_sample", P_DOUBLE, tirf.n_sample),
	F("wavelength_nm", P_DOUBLE, tirf.wavelength_nm), F("s_fraction", P_DOUBLE, tirf.s_fraction),
	F("filaments", P_INT, filaments), F("persistence_nm", P_DOUBLE, persistence_nm),
	F("density_per_um", P_DOUBLE, density_per_um), F("z_min_nm", P_DOUBLE, z_min_nm), F("z_max_nm", P_DOUBLE, z_max_nm),
	F("pairs", P_FLAG, pairs), F("pair_sep_nm", P_DOUBLE, pair_sep_nm), F("pair_dz_nm", P_DOUBLE, pair_dz_nm),
	F("bleach_order", P_INT, order), F("tau_on_ms", P_DOUBLE, tau_on_ms), F("tau_off_ms", P_DOUBLE, tau_off_ms),
	F("tau_bleach_s", P_DOUBLE, tau_bleach_s), F("fps", P_DOUBLE, fps), F("brightness", P_DOUBLE, brightness),
	F("brightness_cv", P_DOUBLE, brightness_cv), F("background", P_DOUBLE, background), F("offset", P_DOUBLE, offset),
	F("gain", P_DOUBLE, gain), F("read_noise", P_DOUBLE, read_noise), F("snr_db", P_DOUBLE, snr_db),
	F("camera", P_INT, camera), F("em_gain", P_DOUBLE, em_gain), F("offset_sd", P_DOUBLE, offset_sd),
	F("gain_cv", P_DOUBLE, gain_cv), F("read_e", P_DOUBLE, read_e), F("read_spread", P_DOUBLE, read_spread),
	F("hot_fraction", P_DOUBLE, hot_fraction), F("hot_sd", P_DOUBLE, hot_sd),
};
#undef F

static int number(const char *name, const char *s, double *v)
{
	char *end;
	errno = 0;
	*v = strtod(s, &end);
	if (end == s || *end || errno || !isfinite(*v))
		return c0_fail(C0_EINVAL, "%s \"%s\": not a number", name, s);
	return C0_OK;
}

/* A comma-separated list of at most C0_MAX_ANGLES numbers. */
static int numbers(const char *name, const char *value, double *out, int *n)
{
	*n = 0;
	for (const char *p = value; *p; ++*n) {
		char buf[64];
		size_t k = strcspn(p, ",");
		if (k >= sizeof buf || *n >= C0_MAX_ANGLES)
			return c0_fail(C0_EINVAL, "%s \"%s\": at most %d values", name, value, C0_MAX_ANGLES);
		memcpy(buf, p, k), buf[k] = 0;
		if (number(name, buf, &out[*n]))
			return C0_EINVAL;
		p += k + (p[k] == ',');
	}
	return C0_OK;
}

int c0_simulation_new(struct c0_simulation **out)
{
	*out = c0_alloc(1, sizeof **out);
	if (!*out)
		return C0_ENOMEM;
	c0_sim_defaults(&(*out)->c);
	return C0_OK;
}

int c0_simulation_set(struct c0_simulation *s, const char *name, const char *value)
{
	if (!name || !value)
		return c0_fail(C0_EINVAL, "simulation parameter: name and value needed");
	if (s->ran)
		return c0_fail(C0_EINVAL, "%s: the simulation has already run", name);
	double v;
	if (!strcmp(name, "angles") || !strcmp(name, "nangles")) {
		int n;
		if (numbers(name, value, s->angles, &n))
			return C0_EINVAL;
		v = n ? s->angles[n - 1] : 0;
		if (!strcmp(name, "nangles")) {
			if (n != 1 || v != floor(v) || v < 1 || v > C0_MAX_ANGLES)
				return c0_fail(C0_EINVAL, "nangles \"%s\": need a whole number 1..%d", value, C0_MAX_ANGLES);
			c0_sim_default_angles(&s->c, (int)v);
			return C0_OK;
		}
		if (n < 1)
			return c0_fail(C0_EINVAL, "angles \"%s\": need at least one angle (deg)", value);
		memcpy(s->c.angles, s->angles, sizeof(double) * n);
		s->c.nangles = n;
		return C0_OK;
	}
	if (!strcmp(name, "bleach_order")) {   /* by name, as in sim.json */
		static const char *orders[] = { "sequential", "interleaved", "restart" };
		for (int k = 0; k < 3; k++)
			if (!strcmp(value, orders[k])) {
				s->c.order = k;
				return C0_OK;
			}
		return c0_fail(C0_EINVAL, "bleach_order \"%s\": expected sequential, interleaved or restart", value);
	}
	if (!strcmp(name, "camera") && !(value[0] >= '0' && value[0] <= '9'))   /* by name, as in sim.json */
		return c0_sim_camera_parse(value, &s->c.camera);
	if (!strcmp(name, "gaps_s")) {
		int n;
		if (numbers(name, value, s->c.gap_s, &n))
			return C0_EINVAL;
		s->c.ngaps = n;
		return C0_OK;
	}
	for (size_t i = 0; i < sizeof params / sizeof *params; i++) {
		if (strcmp(name, params[i].name))
			continue;
		if (number(name, value, &v))
			return C0_EINVAL;
		void *dst = (char *)&s->c + params[i].off;
		if (params[i].type != P_DOUBLE && (v != floor(v) || v < 0 || v > 2147483647.0))
			return c0_fail(C0_EINVAL, "%s \"%s\": need a whole number >= 0", name, value);
		switch (params[i].type) {
		case P_DOUBLE: *(double *)dst = v; break;
		case P_U64: *(uint64_t *)dst = (uint64_t)v; break;
		case P_INT: *(int *)dst = (int)v; break;
		case P_FLAG: *(int *)dst = v != 0; break;
		}
		return C0_OK;
	}
	return c0_fail(C0_EINVAL, "%s: no such simulation parameter", name);
}

double c0_simulation_get(const struct c0_simulation *s, const char *name)
{
	for (size_t i = 0; i < sizeof params / sizeof *params; i++) {
		if (strcmp(name, params[i].name))
			continue;
		const void *src = (const char *)&s->c + params[i].off;
		switch (params[i].type) {
		case P_DOUBLE: return *(const double *)src;
		case P_U64: return (double)*(const uint64_t *)src;
		default: return *(const int *)src;
		}
	}
	return NAN;
}

int c0_simulation_run(struct c0_simulation *s)
{
	if (s->ran)
		return c0_fail(C0_EINVAL, "simulation: has already run");
	int st = c0_sim_check(&s->c);
	if (!st)
		st = c0_simulate(&s->c, NULL, &s->res);
	if (!st && !(s->emitters = c0_alloc((size_t)s->res.nemitters * 4 + 1, sizeof(double))))
		st = C0_ENOMEM;
	if (st) {
		c0_sim_result_free(&s->res);
		return st;
	}
	for (int e = 0; e < s->res.nemitters; e++) {
		const struct c0_emitter *m = &s->res.em[e];
		double *o = s->emitters + 4 * (size_t)e;
		o[0] = m->x, o[1] = m->y, o[2] = m->z, o[3] = m->brightness;
	}
	s->ran = 1;
	return C0_OK;
}

const float *c0_simulation_stack(const struct c0_simulation *s, int q, int *frames, int *h, int *w)
{
	if (!s->ran || q < 0 || q >= s->c.nangles)
		return NULL;
	*frames = s->c.frames, *h = s->c.height, *w = s->c.width;
	return s->res.stack[q];
}

const double *c0_simulation_angles(const struct c0_simulation *s, int *n)
{
	*n = s->c.nangles;
	return s->c.angles;
}

const double *c0_simulation_emitters(const struct c0_simulation *s, int *n)
{
	*n = s->ran ? s->res.nemitters : 0;
	return s->ran ? s->emitters : NULL;
}

void c0_simulation_free(struct c0_simulation *s)
{
	if (!s)
		return;
	c0_sim_result_free(&s->res);
	free(s->emitters);
	free(s);
}
