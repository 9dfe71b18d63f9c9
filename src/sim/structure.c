/* Sample structures: worm-like-chain filaments in 3D, or a CSV of emitters. */
#define _POSIX_C_SOURCE 200809L
#include "sim/sim.h"
#include "optics/grid.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/rng.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void c0_sim_default_angles(struct c0_sim_conf *c, int n)
{
	double ac = c0_tirf_critical_deg(&c->tirf);
	double lo = c->tirf.n_glass * sin((ac + 0.3) * C0_PI / 180), hi = c->tirf.n_glass * sin(70 * C0_PI / 180);
	c->nangles = n;
	for (int q = 0; q < n; q++) {
		double na = n > 1 ? lo + (hi - lo) * q / (n - 1) : lo;
		c->angles[q] = asin(na / c->tirf.n_glass) * 180 / C0_PI;
	}
}

void c0_sim_defaults(struct c0_sim_conf *c)
{
	*c = (struct c0_sim_conf){
		.seed = 1, .width = 64, .height = 64, .frames = 500, .pixel_nm = 100, .fwhm_nm = 229, .srf = 4,
		.tirf = C0_TIRF_DEFAULTS, .filaments = 5, .persistence_nm = 4000, .density_per_um = 250, .label_radius_nm = 15,
		.z_min_nm = 0, .z_max_nm = 400, .pair_sep_nm = 120, .pair_dz_nm = 100, .tau_on_ms = 20, .tau_off_ms = 40, .tau_bleach_s = 35, .fps = 100,
		.brightness = 300, .brightness_cv = 0.3, .background = 40, .offset = 100, .gain = 1,
		.read_noise = 0, .snr_db = 14.75, .hot_fraction = 0, .hot_sd = 30,
		.camera = C0_CAM_CCD, .em_gain = 100, .offset_sd = 2, .gain_cv = 0.03, .read_e = 1.5, .read_spread = 0.45,
		.dark_frames = 200,
	};
	c0_sim_default_angles(c, 5);
}

static const char *const ORDERS[] = { "sequential", "interleaved", "restart" };

const char *c0_sim_order_name(int order)
{
	return order >= 0 && order < 3 ? ORDERS[order] : "?";
}

int c0_sim_order_parse(const char *name, int *order)
{
	for (int k = 0; k < 3; k++)
		if (!strcmp(name, ORDERS[k]))
			return *order = k, C0_OK;
	return c0_fail(C0_EINVAL, "bleach_order %s: expected sequential, interleaved or restart", name);
}

int c0_sim_add_repeat(struct c0_sim_conf *c)
{
	if (!c->repeat_first)
		return C0_OK;
	if (c->nangles < 1 || c->nangles >= C0_MAX_ANGLES)
		return c0_fail(C0_EINVAL, "angles: %d angles leave no room for the repeat of the first (at most %d stacks)", c->nangles,
			       C0_MAX_ANGLES);
	c->angles[c->nangles++] = c->angles[0];
	return C0_OK;
}

int c0_sim_check(const struct c0_sim_conf *c)
{
	if (c->width < 8 || c->height < 8)
		return c0_fail(C0_EINVAL, "width %d / height %d: at least 8x8 pixels", c->width, c->height);
	if (c->frames < 1)
		return c0_fail(C0_EINVAL, "frames %d: must be at least 1", c->frames);
	int st = c0_grid_check(&(struct c0_grid){ c->pixel_nm, c->fwhm_nm, c->srf });
	if (st)
		return st;
	if (c->nangles < 1 || c->nangles > C0_MAX_ANGLES)
		return c0_fail(C0_EINVAL, "angles: need 1..%d angles", C0_MAX_ANGLES);
	if ((st = c0_tirf_check(&c->tirf)))
		return st;
	for (int q = 0; q < c->nangles; q++)   /* below the critical angle: an epi stack */
		if (!(c->angles[q] >= 0 && c->angles[q] < 90))
			return c0_fail(C0_EINVAL, "angles: %g is not an incidence angle in [0, 90) degrees", c->angles[q]);
	if (c->order < C0_ORDER_SEQUENTIAL || c->order > C0_ORDER_RESTART)
		return c0_fail(C0_EINVAL, "bleach_order: unknown order %d", c->order);
	if (c->ngaps && c->order != C0_ORDER_SEQUENTIAL)
		return c0_fail(C0_EINVAL, "gaps_s: only with the sequential acquisition order");
	if (c->ngaps > 1 && c->ngaps != c->nangles - 1)
		return c0_fail(C0_EINVAL, "gaps_s: %d gaps for %d stacks (give one, or one per pair of consecutive stacks: %d)",
			       c->ngaps, c->nangles, c->nangles - 1);
	for (int k = 0; k < c->ngaps; k++)
		if (!(c->gap_s[k] >= 0))
			return c0_fail(C0_EINVAL, "gaps_s: gap %d is %g s, must be >= 0", k + 1, c->gap_s[k]);
	if (c->pairs && (!(c->pair_sep_nm > 0) || !(c->pair_dz_nm >= 0) || c->pair_dz_nm > c->z_max_nm - c->z_min_nm))
		return c0_fail(C0_EINVAL, "pair_sep_nm %g / pair_dz_nm %g: need sep > 0 and 0 <= dz <= the depth range", c->pair_sep_nm,
			       c->pair_dz_nm);
	if (!(c->tau_on_ms > 0) || !(c->tau_off_ms > 0))
		return c0_fail(C0_EINVAL, "tau_on_ms %g / tau_off_ms %g: lifetimes must be positive (ms)", c->tau_on_ms, c->tau_off_ms);
	if (!(c->fps > 0))
		return c0_fail(C0_EINVAL, "fps %g: must be positive", c->fps);
	if (c->tau_bleach_s < 0)
		return c0_fail(C0_EINVAL, "tau_bleach_s %g: must be >= 0 (0: no bleaching)", c->tau_bleach_s);
	if (!(c->brightness >= 0) || !(c->brightness_cv >= 0) || !(c->background >= 0))
		return c0_fail(C0_EINVAL, "brightness, brightness_cv and background: must be >= 0");
	if (!(c->gain > 0) || !(c->read_noise >= 0) || !(c->offset >= 0))
		return c0_fail(C0_EINVAL, "gain: must be positive; read_noise and offset: >= 0");
	if (!(c->hot_fraction >= 0 && c->hot_fraction <= 1) || !(c->hot_sd >= 0))
		return c0_fail(C0_EINVAL, "hot_pixels %g,%g: need a share of pixels in [0, 1] and a noise sd >= 0 (ADU)", c->hot_fraction,
			       c->hot_sd);
	if ((st = c0_sim_camera_check(c)))
		return st;
	if (c->psf != C0_SIM_PSF_GAUSS && c->psf != C0_SIM_PSF_AIRY)
		return c0_fail(C0_EINVAL, "psf: unknown PSF %d", c->psf);
	if (c->psf == C0_SIM_PSF_AIRY && c->fwhm_nm > 8 * c->pixel_nm)
		return c0_fail(C0_EINVAL, "psf airy: fwhm_nm %g is %.3g pixels; the Airy PSF is simulated up to 8", c->fwhm_nm,
			       c->fwhm_nm / c->pixel_nm);
	if (c->psf == C0_SIM_PSF_AIRY && (c->drift_nm[0] != 0 || c->drift_nm[1] != 0))
		return c0_fail(C0_EINVAL, "psf airy: drift_nm is simulated with the gauss PSF only");
	if (!(c->label_radius_nm >= 0) || c->label_radius_nm > 500)
		return c0_fail(C0_EINVAL, "label_radius_nm %g: must be in [0, 500] nm", c->label_radius_nm);
	if (!(c->z_min_nm >= 0) || !(c->z_max_nm >= c->z_min_nm))
		return c0_fail(C0_EINVAL, "z_min_nm %g / z_max_nm %g: need 0 <= min <= max (nm)", c->z_min_nm, c->z_max_nm);
	/* every real parameter finite: infinity passes the >= 0 tests above */
	const double all[] = { c->tau_on_ms, c->tau_off_ms, c->tau_bleach_s, c->fps, c->brightness, c->brightness_cv,
			       c->background, c->offset, c->gain, c->read_noise, c->snr_db, c->hot_sd, c->z_min_nm, c->z_max_nm,
			       c->persistence_nm, c->density_per_um };
	for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
		if (!isfinite(all[i]))
			return c0_fail(C0_EINVAL, "simulation parameter %g: must be finite", all[i]);
	if ((double)c->width * c->height * c->frames > 1e10)
		return c0_fail(C0_EINVAL, "width %d / height %d with frames %d: more than 1e10 pixels per angle", c->width, c->height, c->frames);
	if (!c->emitters_csv && (c->filaments < 1 || !(c->density_per_um > 0) || !(c->persistence_nm > 0)))
		return c0_fail(C0_EINVAL, "empty structure: filaments %d, density_per_um %g, persistence_nm %g must be positive (or give emitters_csv)",
			       c->filaments, c->density_per_um, c->persistence_nm);
	return C0_OK;
}

struct elist { struct c0_emitter *e; int n, cap; };

static int push(struct elist *l, double x, double y, double z, double b)
{
	if (l->n == l->cap) {
		int cap = l->cap ? 2 * l->cap : 1024;
		void *p = realloc(l->e, sizeof *l->e * (size_t)cap);
		if (!p)
			return c0_fail(C0_ENOMEM, "out of memory for emitters");
		l->e = p, l->cap = cap;
	}
	l->e[l->n++] = (struct c0_emitter){ x, y, z, b };
	return C0_OK;
}

static double draw_brightness(const struct c0_sim_conf *c, struct c0_rng *r)
{
	if (c->brightness_cv <= 0)
		return c->brightness;
	double s2 = log1p(c->brightness_cv * c->brightness_cv);   /* log-normal with the given mean and CV */
	return c->brightness * exp(sqrt(s2) * c0_rng_normal(r) - s2 / 2);
}

/* A label on the tube of radius label_radius_nm around the axis point
 * (x, y, z) running in direction th: a uniform angle around the axis, the
 * tube's cross-section standing in the plane of the normal and z. Nothing is
 * drawn without a tube, so the axis-only structures stay as they were. */
static void label(const struct c0_sim_conf *c, struct c0_rng *r, double th, double *x, double *y, double *z)
{
	if (!(c->label_radius_nm > 0))
		return;
	const double phi = 2 * C0_PI * c0_rng_uniform(r), across = c->label_radius_nm * cos(phi);
	*x -= across * sin(th), *y += across * cos(th);
	*z = fmax(0, *z + c->label_radius_nm * sin(phi));
}

/* One filament: a WLC path through a random point, grown both ways until it
 * leaves the field; emitters as a Poisson process along it. */
static int filament(const struct c0_sim_conf *c, struct c0_rng *r, struct elist *l)
{
	const double W = c->width * c->pixel_nm, H = c->height * c->pixel_nm, ds = 5, margin = 200;
	double x0 = W * (0.1 + 0.8 * c0_rng_uniform(r)), y0 = H * (0.1 + 0.8 * c0_rng_uniform(r));
	double th0 = C0_PI * c0_rng_uniform(r);
	/* with pairs the partner runs pair_dz_nm deeper, inside the range */
	double dz = c->pairs ? c->pair_dz_nm : 0, zr = c->z_max_nm - c->z_min_nm - dz, amp = 0.5 * zr * c0_rng_uniform(r);
	double zc = c->z_min_nm + amp + (zr - 2 * amp) * c0_rng_uniform(r);
	double period = 2000 + 4000 * c0_rng_uniform(r), phase = 2 * C0_PI * c0_rng_uniform(r);
	double sep = c->pairs ? c->pair_sep_nm : 0;
	double step_sd = sqrt(ds / c->persistence_nm);
	for (int dir = 0; dir < 2; dir++) {
		double x = x0, y = y0, th = th0 + dir * C0_PI, s = 0;
		double next = dir ? c0_rng_exp(r, 1000 / c->density_per_um) : 0;
		while (x > -margin && x < W + margin && y > -margin && y < H + margin && s < 50000) {
			while (next <= ds) {
				double t = next / ds, ex = x + t * ds * cos(th), ey = y + t * ds * sin(th);
				double arc = (dir ? -1 : 1) * (s + next);
				double z = zc + amp * sin(2 * C0_PI * arc / period + phase);
				for (int k = 0; k <= (sep > 0); k++) {
					/* the partner runs along the local normal */
					double px = ex - k * sep * sin(th), py = ey + k * sep * cos(th), pz = z + k * dz;
					label(c, r, th, &px, &py, &pz);
					if (px >= 0 && px < W && py >= 0 && py < H) {
						int st = push(l, px, py, pz, draw_brightness(c, r));
						if (st)
							return st;
					}
				}
				next += c0_rng_exp(r, 1000 / c->density_per_um);
			}
			next -= ds;
			x += ds * cos(th), y += ds * sin(th), s += ds;
			th += step_sd * c0_rng_normal(r);
		}
	}
	return C0_OK;
}

int c0_sim_read_csv(const char *path, double default_brightness, struct c0_emitter **out, int *n)
{
	FILE *f = fopen(path, "r");
	if (!f)
		return c0_fail(C0_EIO, "emitters_csv %s: %s", path, strerror(errno));
	struct elist l = { 0 };
	char line[1024];
	int lineno = 0, st = C0_OK;
	while (!st && fgets(line, sizeof line, f)) {
		lineno++;
		char *p = line;
		while (*p == ' ' || *p == '\t')
			p++;
		if (*p == '#' || *p == '\n' || *p == '\r' || !*p)
			continue;
		double v[4] = { 0, 0, 0, default_brightness };
		int k = sscanf(p, "%lf , %lf , %lf , %lf", &v[0], &v[1], &v[2], &v[3]);
		if (k < 3) {
			if (lineno == 1 && !l.n)
				continue;   /* header */
			st = c0_fail(C0_EFORMAT, "emitters_csv %s: line %d: expected x_nm,y_nm,z_nm[,brightness]", path, lineno);
			break;
		}
		if (v[2] < 0 || v[3] < 0 || v[0] != v[0] || v[1] != v[1]) {
			st = c0_fail(C0_EFORMAT, "emitters_csv %s: line %d: negative depth or brightness", path, lineno);
			break;
		}
		st = push(&l, v[0], v[1], v[2], v[3]);
	}
	fclose(f);
	if (!st && !l.n)
		st = c0_fail(C0_EINVAL, "emitters_csv %s: empty structure (no emitters)", path);
	if (st) {
		free(l.e);
		return st;
	}
	*out = l.e, *n = l.n;
	return C0_OK;
}

int c0_sim_structure(const struct c0_sim_conf *c, struct c0_emitter **out, int *n)
{
	*out = NULL, *n = 0;
	if (c->emitters_csv) {
		int st = c0_sim_read_csv(c->emitters_csv, c->brightness, out, n);
		if (st)
			return st;
		/* keep what lies in the field */
		int k = 0;
		for (int i = 0; i < *n; i++) {
			const struct c0_emitter *e = &(*out)[i];
			if (e->x >= 0 && e->x < c->width * c->pixel_nm && e->y >= 0 && e->y < c->height * c->pixel_nm)
				(*out)[k++] = *e;
		}
		if (!k) {
			free(*out);
			*out = NULL;
			return c0_fail(C0_EINVAL, "emitters_csv %s: empty structure (no emitter inside the %gx%g nm field)",
				       c->emitters_csv, c->width * c->pixel_nm, c->height * c->pixel_nm);
		}
		*n = k;
		return C0_OK;
	}
	struct c0_rng r;
	c0_rng_init(&r, c->seed, 0);
	struct elist l = { 0 };
	for (int i = 0; i < c->filaments; i++) {
		int st = filament(c, &r, &l);
		if (st) {
			free(l.e);
			return st;
		}
	}
	if (!l.n) {
		free(l.e);
		return c0_fail(C0_EINVAL, "empty structure: no emitter fell inside the field");
	}
	*out = l.e, *n = l.n;
	return C0_OK;
}
