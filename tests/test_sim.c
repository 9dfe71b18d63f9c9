/* Simulator physics: blinking statistics, TIRF closed forms, and the
 * temporal variance of rendered stacks against the model's prediction. */
#define _XOPEN_SOURCE 700   /* j0, j1 */
#include "check.h"
#include "sim/sim.h"
#include "optics/tirf.h"
#include "core/err.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void test_onfraction(void)
{
	struct c0_sim_conf c;
	c0_sim_defaults(&c);
	c.tau_bleach_s = 0;
	const int T = 200000;
	float *on = malloc(sizeof(float) * T);
	c0_sim_blink(&c, 7, T, on);
	double m = 0, v = 0;
	for (int t = 0; t < T; t++)
		m += on[t];
	m /= T;
	for (int t = 0; t < T; t++)
		v += (on[t] - m) * (on[t] - m);
	v /= T - 1;
	CHECK_CLOSE(m, 20.0 / 60.0, 0.01);
	CHECK_REL(v, c0_sim_onfrac_variance(&c), 0.03);
	/* fractions are fractions */
	int ok = 1;
	for (int t = 0; t < T; t++)
		ok &= on[t] >= 0 && on[t] <= 1;
	CHECK(ok);
	/* bleaching: after 20 mean bleach times nearly everything is dark */
	c.tau_bleach_s = 0.05;
	int lit = 0;
	for (int e = 0; e < 200; e++) {
		c0_sim_blink(&c, 100 + e, 100, on);
		lit += on[99] > 0;
	}
	CHECK(lit <= 2);
	free(on);
}

/* Bleaching by cumulative ON time: the population's mean on-fraction decays
 * at c0_sim_bleach_rate, and a process sampled at some slots is the same
 * process as sampled at every slot. */
static void test_bleach_rate(void)
{
	struct c0_sim_conf c;
	c0_sim_defaults(&c);
	c.tau_bleach_s = 2;
	const int E = 3000, T = 1200;
	double k = c0_sim_bleach_rate(&c), p_on = 1.0 / 3;
	CHECK_REL(k, p_on / c.tau_bleach_s, 0.02);     /* about p_on / tau_bleach */
	float *on = malloc(sizeof(float) * T), *sub = malloc(sizeof(float) * 4);
	double *m = calloc(T, sizeof *m);
	const int64_t slot[4] = { 3, 400, 401, 1100 };
	int same = 1;
	for (int e = 0; e < E; e++) {
		c0_sim_blink(&c, 1000 + e, T, on);
		for (int t = 0; t < T; t++)
			m[t] += on[t] / E;
		c0_sim_blink_slots(&c, 1000 + e, slot, 4, sub);
		for (int i = 0; i < 4; i++)
			same &= sub[i] == on[slot[i]];
	}
	CHECK(same);
	/* the decay rate between the means of the second and the last 100 frames */
	double a = 0, b = 0;
	for (int t = 100; t < 200; t++)
		a += m[t];
	for (int t = T - 100; t < T; t++)
		b += m[t];
	CHECK_REL(log(a / b) / ((T - 200) / c.fps), k, 0.03);
	free(on), free(sub), free(m);
}

static void test_tirf_closed_forms(void)
{
	struct c0_tirf t = C0_TIRF_DEFAULTS;
	CHECK_CLOSE(c0_tirf_critical_deg(&t), 61.18, 0.01);
	double p;
	/* penetration depths 1/p, reference/matirf.md table (488 nm, n 1.33) */
	const double ang[] = { 62, 63, 64, 65, 66, 68, 70, 72, 75 }, d[] = { 234, 158, 128, 110, 99, 84, 75, 69, 63 };
	for (int i = 0; i < 9; i++) {
		CHECK(c0_tirf_p(&t, ang[i], &p) == C0_OK);
		CHECK_CLOSE(1 / p, d[i], 0.6);
	}
	t.n_sample = 1.38;
	CHECK(c0_tirf_p(&t, 66, &p) == C0_OK);
	CHECK_CLOSE(1 / p, 284, 0.6);
	CHECK(c0_tirf_p(&t, 64, &p) != C0_OK);        /* below critical */
	CHECK(strstr(c0_errmsg(), "critical") != NULL);
	t.n_sample = 1.37;
	CHECK_CLOSE(c0_tirf_critical_deg(&t), 64.49, 0.01);
	/* Axelrod I0 at n 1.34 */
	t.n_sample = 1.34;
	double is, ip;
	c0_tirf_i0_sp(&t, 62.6, &is, &ip);
	CHECK_CLOSE(ip, 4.91, 0.01);
	CHECK_CLOSE(is, 3.84, 0.01);
	CHECK_CLOSE(c0_tirf_i0(&t, 70), 2.25, 0.01);
	/* bin-averaged weights approach the point value for thin bins */
	double W[2], a = 65;
	c0_tirf_p(&t, a, &p);
	CHECK(c0_tirf_weights(&t, 1, &a, NULL, 2, 100, 1e-3, W) == C0_OK);
	CHECK_REL(W[0], c0_tirf_i0(&t, a) * exp(-p * 100), 1e-5);
}

static void test_variance_image(void)
{
	struct c0_sim_conf c;
	c0_sim_defaults(&c);
	c.width = c.height = 24;
	c.frames = 6000;
	c.tau_bleach_s = 0;
	c.read_noise = 2;
	c.snr_db = 0;
	c.nangles = 1;
	struct c0_emitter em[] = { { 500, 600, 0, 400 }, { 1700, 900, 100, 300 }, { 1210, 1830, 50, 500 }, { 1300, 1900, 150, 350 } };
	const int ne = 4;
	struct c0_sim_scene *s;
	CHECK(c0_sim_scene_new(&c, em, ne, 0, &s) == C0_OK);
	const int n = c.width * c.height;
	double *ph = malloc(sizeof(double) * n), *s1 = calloc(n, sizeof(double)), *s2 = calloc(n, sizeof(double));
	float *adu = malloc(sizeof(float) * n);
	for (int t = 0; t < c.frames; t++) {
		c0_sim_render(s, t, ph);
		c0_sim_camera(&c, 0, t, c.read_noise, ph, adu);
		for (int i = 0; i < n; i++)
			s1[i] += adu[i], s2[i] += (double)adu[i] * adu[i];
	}
	/* prediction: blinking term per emitter + Poisson (mean photons) + read noise + rounding */
	double vb = c0_sim_onfrac_variance(&c);
	double *pred = calloc(n, sizeof(double)), *mean_ph = calloc(n, sizeof(double));
	struct c0_sim_conf one = c;
	/* each emitter's footprint (amplitude x PSF): a single-emitter scene in a
	 * frame where it is on, minus the (identical) background */
	const float *on = c0_sim_scene_onfrac(s);
	const double *bg = c0_sim_scene_background(s);
	double *fp = calloc((size_t)n * ne, sizeof(double));
	for (int e = 0; e < ne; e++) {
		struct c0_sim_scene *se;
		c0_sim_scene_new(&one, &em[e], 1, 0, &se);
		const float *on1 = c0_sim_scene_onfrac(se);
		int t1 = -1;
		for (int t = 0; t < c.frames && t1 < 0; t++)
			if (on1[t] > 0.5)
				t1 = t;
		c0_sim_render(se, t1, ph);
		for (int i = 0; i < n; i++)
			fp[(size_t)e * n + i] = (ph[i] - bg[i]) / on1[t1];
		c0_sim_scene_free(se);
	}
	for (int i = 0; i < n; i++) {
		double m = bg[i];
		for (int e = 0; e < ne; e++) {
			double f = fp[(size_t)e * n + i];
			pred[i] += f * f * vb;
			double mo = 0;
			for (int t = 0; t < c.frames; t++)
				mo += on[(size_t)t * ne + e];
			m += f * mo / c.frames;
		}
		mean_ph[i] = m;
		pred[i] += m + c.read_noise * c.read_noise + 1.0 / 12;
	}
	double se_sum = 0, sp_sum = 0;
	int bad = 0, strong = 0;
	for (int i = 0; i < n; i++) {
		double mu = s1[i] / c.frames, var = (s2[i] - c.frames * mu * mu) / (c.frames - 1);
		se_sum += var, sp_sum += pred[i];
		CHECK_MSG(fabs(mu - c.offset - mean_ph[i]) < 0.05 * mean_ph[i] + 0.5, "pixel %d mean %g vs %g", i, mu - c.offset, mean_ph[i]);
		if (pred[i] > 2 * (mean_ph[i] + 4)) {     /* blinking dominates here */
			strong++;
			bad += fabs(var - pred[i]) > 0.1 * pred[i];
		}
	}
	CHECK_REL(se_sum, sp_sum, 0.03);
	CHECK(strong > 10);
	CHECK_MSG(bad <= strong / 10, "%d of %d strong pixels off by >10%%", bad, strong);
	free(ph), free(s1), free(s2), free(adu), free(pred), free(mean_ph), free(fp);
	c0_sim_scene_free(s);
}

/* The Airy kernels (airy.c): each against the Airy disk integrated over
 * the same pixels by brute force (32 x 32 samples a pixel, j1 each time),
 * their light against the encircled energy, the half maximum at FWHM / 2. */
static double airy_pixel(double k, double cx, double cy, int i, int j)
{
	double s = 0;
	for (int a = 0; a < 32; a++)
		for (int b = 0; b < 32; b++) {
			double v = k * hypot(i + (b + 0.5) / 32 - cx, j + (a + 0.5) / 32 - cy);
			s += v < 1e-9 ? 1 : pow(2 * j1(v) / v, 2);
		}
	return s / 1024 * k * k / (4 * M_PI);
}

static void test_airy_psf(void)
{
	const double fwhm = 2.29, k = 2 * 1.616339948 / fwhm;
	const int half = c0_sim_airy_half(fwhm), K = 2 * half + 2, nb = C0_AIRY_BANK;
	double *bank;
	CHECK(c0_sim_airy_bank(fwhm, K, &bank) == C0_OK);
	const int qs[3] = { 0, 17 * nb + 5, nb * nb - 1 };
	double worst = 0;
	for (int m = 0; m < 3; m++) {
		const double *w = bank + (size_t)qs[m] * K * K;
		const double cx = half + (qs[m] % nb + 0.5) / nb, cy = half + (qs[m] / nb + 0.5) / nb;
		double sum = 0, mx = 0, sx = 0;
		for (int i = 0; i < K * K; i++)
			sum += w[i], mx = fmax(mx, w[i]), sx += w[i] * (i % K + 0.5);
		/* the square window holds more than the circle of radius half */
		const double v = k * half, inside = 1 - pow(j0(v), 2) - pow(j1(v), 2);
		CHECK_MSG(sum >= inside - 2e-3 && sum < 1, "kernel %d holds %g of the light (circle: %g)", qs[m], sum, inside);
		CHECK_CLOSE(sx / sum, cx, 0.03);   /* centred (the cut tail's asymmetry aside) */
		for (int j = half - 2; j <= half + 3; j++)
			for (int i = half - 2; i <= half + 3; i++)
				worst = fmax(worst, fabs(w[j * K + i] - airy_pixel(k, cx, cy, i, j)) / mx);
	}
	CHECK_MSG(worst < 2e-3, "kernels off the brute-force integral by %g of the peak", worst);
	free(bank);
	/* the constant that sets k: half the peak at FWHM / 2 */
	const double vh = 1.616339948;
	CHECK_CLOSE(pow(2 * j1(vh) / vh, 2), 0.5, 1e-8);
	struct c0_sim_conf c;
	c0_sim_defaults(&c);
	int psf = -1;
	CHECK(c0_sim_psf_parse("airy", &psf) == C0_OK && psf == C0_SIM_PSF_AIRY);
	CHECK(c0_sim_psf_parse("bessel", &psf) == C0_EINVAL && strstr(c0_errmsg(), "psf bessel"));
	c.psf = C0_SIM_PSF_AIRY, c.drift_nm[0] = 50;
	CHECK(c0_sim_check(&c) == C0_EINVAL && strstr(c0_errmsg(), "psf airy"));
}

static void test_bad_params(void)
{
	struct c0_sim_conf c;
	c0_sim_defaults(&c);
	c.tau_on_ms = -1;
	CHECK(c0_sim_check(&c) == C0_EINVAL && strstr(c0_errmsg(), "tau_on_ms"));
	c0_sim_defaults(&c);
	c.angles[2] = 55;                 /* below critical: an epi stack */
	CHECK(c0_sim_check(&c) == C0_OK);
	c.angles[2] = 95;
	CHECK(c0_sim_check(&c) == C0_EINVAL && strstr(c0_errmsg(), "incidence angle"));
	c0_sim_defaults(&c);
	c.ngaps = 2;
	CHECK(c0_sim_check(&c) == C0_EINVAL && strstr(c0_errmsg(), "gaps_s"));
	c.ngaps = 1, c.order = C0_ORDER_INTERLEAVED;
	CHECK(c0_sim_check(&c) == C0_EINVAL && strstr(c0_errmsg(), "gaps_s"));
	c0_sim_defaults(&c);
	c.filaments = 0;
	CHECK(c0_sim_check(&c) == C0_EINVAL && strstr(c0_errmsg(), "empty structure"));
	c0_sim_defaults(&c);
	c.z_min_nm = 300, c.z_max_nm = 100;
	CHECK(c0_sim_check(&c) == C0_EINVAL && strstr(c0_errmsg(), "z_min_nm"));
}

/* Emitters on a labelled tube: on one straight filament at a fixed depth
 * each lies at the tube's radius from the axis (the in-plane offset across
 * the filament and the depth offset on a circle), their spread across is
 * R / sqrt 2, and without a tube they lie on the axis. */
static void test_label_tube(void)
{
	for (int k = 0; k < 2; k++) {
		struct c0_sim_conf c;
		c0_sim_defaults(&c);
		c.filaments = 1, c.persistence_nm = 1e12, c.density_per_um = 2000;
		c.z_min_nm = c.z_max_nm = 200, c.label_radius_nm = k ? 20 : 0;
		CHECK(c0_sim_check(&c) == C0_OK);
		struct c0_emitter *e;
		int n;
		CHECK(c0_sim_structure(&c, &e, &n) == C0_OK && n > 1000);
		/* the axis: the principal direction of the emitters' positions */
		double mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
		for (int i = 0; i < n; i++)
			mx += e[i].x / n, my += e[i].y / n;
		for (int i = 0; i < n; i++)
			sxx += (e[i].x - mx) * (e[i].x - mx), syy += (e[i].y - my) * (e[i].y - my), sxy += (e[i].x - mx) * (e[i].y - my);
		const double th = 0.5 * atan2(2 * sxy, sxx - syy), nx = -sin(th), ny = cos(th);
		double worst = 0, v = 0;
		for (int i = 0; i < n; i++) {
			const double d = (e[i].x - mx) * nx + (e[i].y - my) * ny, dz = e[i].z - 200;
			worst = fmax(worst, fabs(sqrt(d * d + dz * dz) - c.label_radius_nm));
			v += d * d / n;
		}
		CHECK(worst < 0.5);
		CHECK_CLOSE(sqrt(v), c.label_radius_nm / sqrt(2), 0.6);
		free(e);
	}
	struct c0_sim_conf c;
	c0_sim_defaults(&c);
	c.label_radius_nm = -1;
	CHECK(c0_sim_check(&c) == C0_EINVAL && strstr(c0_errmsg(), "label_radius_nm"));
}

int main(void)
{
	RUN(test_label_tube);
	RUN(test_onfraction);
	RUN(test_bleach_rate);
	RUN(test_tirf_closed_forms);
	RUN(test_variance_image);
	RUN(test_bad_params);
	RUN(test_airy_psf);
	return CHECK_DONE();
}
