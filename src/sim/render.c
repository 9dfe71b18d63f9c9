/* Frames of one angle: expected photons, then camera noise. */
#include "sim/sim.h"
#include "optics/psf.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/rng.h"

#include <math.h>
#include <stdlib.h>

/* stream ids: 0 structure, 1<<56 blinking, 2<<56 background, 3<<56 camera, 4<<56 drift */
#define STREAM(kind, q, i) (((uint64_t)(kind) << 56) | ((uint64_t)(q) << 40) | (uint64_t)(i))

struct c0_sim_scene {
	const struct c0_sim_conf *c;
	int nem, K;          /* emitters, PSF window (pixels per axis) */
	int *x0, *y0;        /* window corners */
	double *wx, *wy;     /* nem x K */
	double *amp;         /* photons per frame when on */
	float *on;           /* nem x frames */
	double *bg;          /* H x W photons */
	double *ddx, *ddy;   /* drift per frame (pixels), NULL without */
	double *bank;        /* airy: the kernels (airy.c), NULL for the Gaussian */
	int *kid;            /* airy: each emitter's kernel */
	double sig;
	const struct c0_emitter *em;
};

static void background(const struct c0_sim_conf *c, int q, double scale, double *bg)
{
	struct c0_rng r;
	c0_rng_init(&r, c->seed, STREAM(2, q, 0));
	const int W = c->width, H = c->height;
	double cx[3], cy[3], s[3], mx = 0;
	for (int k = 0; k < 3; k++) {
		cx[k] = W * c0_rng_uniform(&r), cy[k] = H * c0_rng_uniform(&r);
		s[k] = (0.3 + 0.3 * c0_rng_uniform(&r)) * (W > H ? W : H);
	}
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			double v = 0;
			for (int k = 0; k < 3; k++)
				v += exp(-((x + 0.5 - cx[k]) * (x + 0.5 - cx[k]) + (y + 0.5 - cy[k]) * (y + 0.5 - cy[k])) / (2 * s[k] * s[k]));
			bg[y * W + x] = v;
			mx = fmax(mx, v);
		}
	/* smooth, between half and full level */
	for (int i = 0; i < W * H; i++)
		bg[i] = c->background * scale * (0.5 + 0.5 * bg[i] / mx);
}

void c0_sim_scene_free(struct c0_sim_scene *s)
{
	if (!s)
		return;
	free(s->x0), free(s->y0), free(s->wx), free(s->wy), free(s->amp), free(s->on), free(s->bg);
	free(s->ddx), free(s->ddy);
	free(s->bank), free(s->kid);
	free(s);
}

int c0_sim_excitation(const struct c0_sim_conf *c, int q, double *p, double *i0_rel)
{
	const double ac = c0_tirf_critical_deg(&c->tirf);
	double i0_1 = 0;
	for (int k = 0; k < c->nangles && !(i0_1 > 0); k++)
		if (c->angles[k] > ac)
			i0_1 = c0_tirf_i0(&c->tirf, c->angles[k]);
	if (!(c->angles[q] > ac) || c0_tirf_p(&c->tirf, c->angles[q], p)) {
		*p = 0, *i0_rel = 1;   /* epi: a propagating beam, as bright as the first TIRF angle at z = 0 */
		return 1;
	}
	*i0_rel = c0_tirf_i0(&c->tirf, c->angles[q]) / i0_1;
	return 0;
}

/* on (frames x nem): every emitter's on-fraction per frame, frame-major so
 * that a frame's render reads its emitters side by side; each emitter's
 * frames drawn into a row, BLK emitters at a time, then written out a frame
 * at a time (whole cache lines). 1 when out of memory. */
#define BLK 16
static int blink_frame_major(const struct c0_sim_conf *c, int qs, const int64_t *slot, int nem, float *on)
{
	const int T = c->frames;
	int fail = 0;
#pragma omp parallel for schedule(dynamic, 4)
	for (int b = 0; b < nem; b += BLK) {
		const int n = nem - b < BLK ? nem - b : BLK;
		float *row = c0_alloc((size_t)n * T, sizeof *row);
		if (!row) {
#pragma omp atomic write
			fail = 1;
			continue;
		}
		for (int i = 0; i < n; i++)
			c0_sim_blink_slots(c, STREAM(1, qs, b + i), slot, T, row + (size_t)i * T);
		for (int t = 0; t < T; t++)
			for (int i = 0; i < n; i++)
				on[(size_t)t * nem + b + i] = row[(size_t)i * T + t];
		free(row);
	}
	return fail;
}

int c0_sim_scene_new(const struct c0_sim_conf *c, const struct c0_emitter *em, int nem, int q,
		     struct c0_sim_scene **out)
{
	*out = NULL;
	double p, rel, sig = c0_psf_sigma_px(c->fwhm_nm, c->pixel_nm);
	c0_sim_excitation(c, q, &p, &rel);
	struct c0_sim_scene *s = c0_alloc(1, sizeof *s);
	if (!s)
		return C0_ENOMEM;
	s->c = c, s->nem = nem;
	const int airy = c->psf == C0_SIM_PSF_AIRY;
	const int half = airy ? c0_sim_airy_half(c->fwhm_nm / c->pixel_nm) : (int)ceil(C0_PSF_CUTOFF * sig);
	s->K = 2 * half + 2;
	size_t K = (size_t)s->K;
	s->x0 = c0_alloc((size_t)nem, sizeof(int));
	s->y0 = c0_alloc((size_t)nem, sizeof(int));
	s->wx = c0_alloc(nem * K, sizeof(double));
	s->wy = c0_alloc(nem * K, sizeof(double));
	s->amp = c0_alloc((size_t)nem, sizeof(double));
	s->on = c0_alloc((size_t)nem * c->frames, sizeof(float));
	s->bg = c0_alloc((size_t)c->width * c->height, sizeof(double));
	int64_t *slot = c0_alloc((size_t)c->frames, sizeof *slot);
	for (int t = 0; slot && t < c->frames; t++)
		slot[t] = c0_sim_slot(c, q, t);
	if (!slot || !s->x0 || !s->y0 || !s->wx || !s->wy || !s->amp || !s->on || !s->bg) {
		c0_sim_scene_free(s);
		free(slot);
		return C0_ENOMEM;
	}
	/* one process per emitter over the whole acquisition, unless each angle restarts */
	const int qs = c->order == C0_ORDER_RESTART ? q : 0;
	if (airy && (!(s->kid = c0_alloc((size_t)nem, sizeof(int))) ||
		     c0_sim_airy_bank(c->fwhm_nm / c->pixel_nm, s->K, &s->bank))) {
		c0_sim_scene_free(s);
		free(slot);
		return C0_ENOMEM;
	}
#pragma omp parallel for schedule(dynamic, 64)
	for (int e = 0; e < nem; e++) {
		double ex = em[e].x / c->pixel_nm, ey = em[e].y / c->pixel_nm;
		s->x0[e] = (int)floor(ex) - half;
		s->y0[e] = (int)floor(ey) - half;
		if (airy) {   /* the kernel of the nearest sub-pixel position */
			int ix = (int)((ex - floor(ex)) * C0_AIRY_BANK), iy = (int)((ey - floor(ey)) * C0_AIRY_BANK);
			s->kid[e] = (iy < C0_AIRY_BANK ? iy : C0_AIRY_BANK - 1) * C0_AIRY_BANK + (ix < C0_AIRY_BANK ? ix : C0_AIRY_BANK - 1);
		} else {
			c0_psf_pixel_weights(ex, sig, s->x0[e], s->K, s->wx + e * K);
			c0_psf_pixel_weights(ey, sig, s->y0[e], s->K, s->wy + e * K);
		}
		s->amp[e] = em[e].brightness * rel * exp(-p * em[e].z);
	}
	const int fail = blink_frame_major(c, qs, slot, nem, s->on);
	free(slot);
	if (fail) {
		c0_sim_scene_free(s);
		return C0_ENOMEM;
	}
	background(c, q, rel, s->bg);
	s->sig = sig, s->em = em;
	if ((c->drift_nm[0] != 0 || c->drift_nm[1] != 0) && s->K > 64) {
		c0_sim_scene_free(s);
		return c0_fail(C0_EINVAL, "drift_nm: the PSF spans %d pixels; drift is simulated up to 64", s->K);
	}
	if (c->drift_nm[0] != 0 || c->drift_nm[1] != 0) {
		s->ddx = c0_alloc((size_t)c->frames, sizeof(double));
		s->ddy = c0_alloc((size_t)c->frames, sizeof(double));
		if (!s->ddx || !s->ddy) {
			c0_sim_scene_free(s);
			return C0_ENOMEM;
		}
		c0_sim_drift(c, q, s->ddx, s->ddy);
		for (int t = 0; t < c->frames; t++)
			s->ddx[t] /= c->pixel_nm, s->ddy[t] /= c->pixel_nm;
	}
	*out = s;
	return C0_OK;
}

const float *c0_sim_scene_onfrac(const struct c0_sim_scene *s) { return s->on; }
const double *c0_sim_scene_background(const struct c0_sim_scene *s) { return s->bg; }

/* a K x K kernel at window corner (x0, y0), clipped to the frame */
static void render_2d(const double *w, int K, int x0, int y0, int W, int H, double a, double *ph)
{
	for (int j = 0; j < K; j++) {
		int y = y0 + j;
		if (y < 0 || y >= H)
			continue;
		for (int k = 0; k < K; k++) {
			int x = x0 + k;
			if (x >= 0 && x < W)
				ph[y * W + x] += a * w[j * K + k];
		}
	}
}

void c0_sim_render(const struct c0_sim_scene *s, int t, double *ph)
{
	const struct c0_sim_conf *c = s->c;
	const int W = c->width, H = c->height, K = s->K;
	for (int i = 0; i < W * H; i++)
		ph[i] = s->bg[i];
	double dwx[64], dwy[64];   /* K <= 2 ceil(cutoff sigma) + 2 (checked by c0_grid_check) */
	for (int e = 0; e < s->nem; e++) {
		double a = s->amp[e] * s->on[(size_t)t * s->nem + e];
		if (a == 0)
			continue;
		const double *wx = s->wx + (size_t)e * K, *wy = s->wy + (size_t)e * K;
		int x0 = s->x0[e], y0 = s->y0[e];
		if (s->bank) {
			render_2d(s->bank + (size_t)s->kid[e] * K * K, K, x0, y0, W, H, a, ph);
			continue;
		}
		if (s->ddx) {   /* drifted: this frame's own pixel weights */
			double ex = s->em[e].x / c->pixel_nm + s->ddx[t], ey = s->em[e].y / c->pixel_nm + s->ddy[t];
			x0 = (int)floor(ex) - (K - 2) / 2, y0 = (int)floor(ey) - (K - 2) / 2;
			c0_psf_pixel_weights(ex, s->sig, x0, K, dwx);
			c0_psf_pixel_weights(ey, s->sig, y0, K, dwy);
			wx = dwx, wy = dwy;
		}
		/* the window clipped to the frame first: a branch-free row the
		 * compiler vectorises (the same sums, in the same order) */
		const int j0 = y0 < 0 ? -y0 : 0, j1 = y0 + K > H ? H - y0 : K;
		const int k0 = x0 < 0 ? -x0 : 0, k1 = x0 + K > W ? W - x0 : K;
		for (int j = j0; j < j1; j++) {
			const double ay = a * wy[j];
			double *row = ph + (size_t)(y0 + j) * W;
			for (int k = k0; k < k1; k++)
				row[x0 + k] += ay * wx[k];
		}
	}
}

void c0_sim_camera(const struct c0_sim_conf *c, int q, int t, double read_noise, const double *ph, float *adu)
{
	struct c0_rng r;
	c0_rng_init(&r, c->seed, STREAM(3, q, t));
	/* the noisy pixels: the same in every frame and stack (one draw per pixel
	 * from a stream of their own), their noise from another: the rest of the
	 * frame is the same as without them */
	struct c0_rng hot, hn;
	c0_rng_init(&hot, c->seed, STREAM(5, 0, 0));
	c0_rng_init(&hn, c->seed, STREAM(6, q, t));
	for (int i = 0; i < c->width * c->height; i++) {
		double v = c->gain * (double)c0_rng_poisson(&r, ph[i]) + c->offset;
		if (read_noise > 0)
			v += read_noise * c0_rng_normal(&r);
		if (c->hot_fraction > 0 && c0_rng_uniform(&hot) < c->hot_fraction)
			v += c->hot_sd * c0_rng_normal(&hn);
		v = nearbyint(v);
		adu[i] = (float)(v < 0 ? 0 : v > 65535 ? 65535 : v);
	}
}

/* frame t of angle q on the drift's time line: the acquisition's slots
 * (interleaved: in turn; sequential: with the gaps), except that stacks on
 * fresh populations (restart) still follow one another in time */
static int64_t drift_slot(const struct c0_sim_conf *c, int q, int t)
{
	return c->order == C0_ORDER_RESTART ? (int64_t)q * c->frames + t : c0_sim_slot(c, q, t);
}

void c0_sim_drift(const struct c0_sim_conf *c, int q, double *dx, double *dy)
{
	const int64_t last = drift_slot(c, c->nangles - 1, c->frames - 1);   /* the acquisition's last frame */
	const double G = (double)last + 1;
	if (!c->drift_walk) {
		for (int t = 0; t < c->frames; t++) {
			double u = G > 1 ? (double)drift_slot(c, q, t) / (G - 1) : 0;
			dx[t] = c->drift_nm[0] * u, dy[t] = c->drift_nm[1] * u;
		}
		return;
	}
	/* the walk from the first frame of the acquisition, one stream, a step a slot */
	struct c0_rng r;
	c0_rng_init(&r, c->seed, STREAM(4, 0, 0));
	const double sx = fabs(c->drift_nm[0]) / sqrt(G), sy = fabs(c->drift_nm[1]) / sqrt(G);
	double x = 0, y = 0;
	for (int64_t g = 0, t = 0; t < c->frames; g++) {
		if (g > 0)
			x += sx * c0_rng_normal(&r), y += sy * c0_rng_normal(&r);
		if (g == drift_slot(c, q, (int)t))
			dx[t] = x, dy[t] = y, t++;
	}
}
