/* The public calls besides c0_run, through col0rme.h alone: the simulator
 * in memory (parameters by name, deterministic), the support step alone
 * (the same mask as c0_run's), MA-TIRF alone on c0_run's intensities (the
 * same volume as c0_run's without pooling), and bad input refused with a
 * message naming the parameter. */
#include "check.h"
#include "col0rme.h"

#include <stdio.h>
#include <string.h>

static void expect_einval(int st, const char *name)
{
	CHECK_MSG(st == C0_EINVAL && strstr(c0_last_error(), name), "status %d, message '%s' should name %s", st,
		  c0_last_error(), name);
}

static struct c0_simulation *simulate(void)
{
	struct c0_simulation *s;
	CHECK(c0_simulation_new(&s) == C0_OK);
	const char *p[][2] = { { "width", "16" }, { "height", "16" }, { "frames", "120" }, { "angles", "62,65,68" },
			       { "filaments", "2" }, { "seed", "9" } };
	for (size_t i = 0; i < sizeof p / sizeof *p; i++)
		CHECK(c0_simulation_set(s, p[i][0], p[i][1]) == C0_OK);
	CHECK(c0_simulation_run(s) == C0_OK);
	return s;
}

static void test_simulation(void)
{
	struct c0_simulation *a = simulate(), *b = simulate();
	int t, h, w, t2, h2, w2, n, ne;
	const float *sa = c0_simulation_stack(a, 2, &t, &h, &w), *sb = c0_simulation_stack(b, 2, &t2, &h2, &w2);
	CHECK(sa && sb && t == 120 && h == 16 && w == 16 && t2 == t && h2 == h && w2 == w);
	CHECK(sa && sb && !memcmp(sa, sb, sizeof(float) * 120 * 16 * 16));   /* same seed, same values */
	CHECK(!c0_simulation_stack(a, 3, &t, &h, &w));
	const double *ang = c0_simulation_angles(a, &n), *em = c0_simulation_emitters(a, &ne);
	CHECK(n == 3 && ang[1] == 65 && ne > 10 && em);
	int inside = 1;
	for (int e = 0; em && e < ne; e++)
		inside &= em[4 * e] >= 0 && em[4 * e] < 1600 && em[4 * e + 1] >= 0 && em[4 * e + 1] < 1600 &&
			  em[4 * e + 2] >= 0 && em[4 * e + 2] <= 400 && em[4 * e + 3] > 0;
	CHECK(inside);
	CHECK(c0_simulation_get(a, "width") == 16 && c0_simulation_get(a, "fwhm_nm") == 229);
	CHECK(c0_simulation_get(a, "nonsense") != c0_simulation_get(a, "nonsense"));   /* NAN */
	expect_einval(c0_simulation_set(a, "frames", "10"), "frames");                  /* after the run */
	c0_simulation_free(a), c0_simulation_free(b);

	struct c0_simulation *s;
	CHECK(c0_simulation_new(&s) == C0_OK);
	expect_einval(c0_simulation_set(s, "bogus", "1"), "bogus");
	expect_einval(c0_simulation_set(s, "frames", "1.5"), "frames");
	expect_einval(c0_simulation_set(s, "snr_db", "x"), "snr_db");
	expect_einval(c0_simulation_set(s, "angles", ""), "angles");
	expect_einval(c0_simulation_set(s, "nangles", "0"), "nangles");
	CHECK(c0_simulation_set(s, "nangles", "3") == C0_OK);
	CHECK(c0_simulation_set(s, "width", "4") == C0_OK && c0_simulation_run(s) == C0_EINVAL);
	c0_simulation_free(s);
}

/* The simulation's three stacks in st, and a conf with their angles and optics */
static struct c0_run_conf *stacks3(struct c0_simulation *sim, struct c0_stack st[3])
{
	for (int q = 0; q < 3; q++)
		st[q].data = c0_simulation_stack(sim, q, &st[q].frames, &st[q].height, &st[q].width);
	struct c0_run_conf *c = c0_run_conf_new();
	CHECK(c && c->srf == 4);   /* the defaults */
	CHECK(c0_run_conf_set(c, "angles", "62,65,68") == C0_OK && c0_run_conf_set(c, "pixel_nm", "100") == C0_OK &&
	      c0_run_conf_set(c, "fwhm_nm", "229") == C0_OK);
	return c;
}

static void test_steps(void)
{
	struct c0_simulation *sim = simulate();
	struct c0_stack st[3] = { { 0 } };
	struct c0_run_conf *c = stacks3(sim, st);
	CHECK(c0_run_conf_set(c, "depth_pool_nm", "0") == C0_OK &&
	      c0_run_conf_set(c, "bleach", "off") == C0_OK);   /* the volume from the intensities as returned */
	/* the drift of a run comes from all its stacks, that of one stack from it alone */
	CHECK(c0_run_conf_set(c, "drift", "off") == C0_OK);
	struct c0_result *run = NULL, *sup = NULL, *mat = NULL;
	CHECK(c0_run(c, st, 3, &run) == C0_OK);
	if (!run) {
		c0_run_conf_free(c), c0_simulation_free(sim);
		return;
	}
	/* the support of the three stacks pooled: c0_run's support */
	int h, w, h2, w2, nz, nz2;
	CHECK(c0_run_support(c, st, 3, &sup) == C0_OK);
	const uint8_t *ma = c0_result_support(run, &h, &w), *mb = sup ? c0_result_support(sup, &h2, &w2) : NULL;
	CHECK(ma && mb && h == 64 && w == 64 && h2 == h && w2 == w && !memcmp(ma, mb, (size_t)h * w));
	CHECK(sup && !c0_result_volume(sup, &nz, &h2, &w2) && !c0_result_intensity(sup, 0, &h2, &w2));
	/* MA-TIRF on c0_run's intensities: c0_run's volume (no pooling) */
	const float *img[3];
	for (int q = 0; q < 3; q++)
		img[q] = c0_result_intensity(run, q, &h, &w);
	CHECK(c0_run_matirf(c, img, 3, h, w, &mat) == C0_OK);
	const float *va = c0_result_volume(run, &nz, &h, &w), *vb = mat ? c0_result_volume(mat, &nz2, &h2, &w2) : NULL;
	CHECK(va && vb && nz == 20 && nz2 == nz && h2 == h && w2 == w && !memcmp(va, vb, sizeof(float) * nz * h * w));
	const double *za = c0_result_z_nm(run, &nz), *zb = mat ? c0_result_z_nm(mat, &nz2) : NULL;
	CHECK(za && zb && nz == nz2 && za[0] == zb[0] && za[nz - 1] == zb[nz - 1]);
	CHECK(mat && strstr(c0_result_report_json(mat), "\"matirf\""));
	/* bad input */
	struct c0_result *bad = run;
	expect_einval(c0_run_matirf(c, img, 2, h, w, &bad), "angles");
	CHECK(bad == NULL);
	img[1] = NULL;
	expect_einval(c0_run_matirf(c, img, 3, h, w, &bad), "images");
	expect_einval(c0_run_support(c, st, 0, &bad), "stacks");
	c0_result_free(run), c0_result_free(sup), c0_result_free(mat);
	c0_run_conf_free(c);
	c0_simulation_free(sim);
}

/* What the progress callback heard, and where it asks to stop. */
struct heard {
	char stages[16][16];
	int nstages, calls, bad_fraction, backwards;
	double last;
	const char *stop_at;
};

static int listen(const char *stage, double fraction, void *user)
{
	struct heard *h = user;
	h->calls++;
	h->bad_fraction |= !(fraction >= 0 && fraction <= 1);
	if (!h->nstages || strcmp(h->stages[h->nstages - 1], stage)) {
		if (h->nstages < 16)
			snprintf(h->stages[h->nstages++], sizeof h->stages[0], "%s", stage);
		h->last = 0;
	}
	h->backwards |= fraction < h->last;
	h->last = fraction;
	return h->stop_at && !strcmp(stage, h->stop_at);
}

static int heard(const struct heard *h, const char *stage)
{
	for (int i = 0; i < h->nstages; i++)
		if (!strcmp(h->stages[i], stage))
			return 1;
	return 0;
}

/* Every stage of a run is heard, in order, fractions in [0, 1] and never
 * back within a stage; a callback that asks to stop gets C0_ECANCELED and
 * no result, and nothing was written. */
static void test_progress_cancel(void)
{
	struct c0_simulation *sim = simulate();
	struct c0_stack st[3] = { { 0 } };
	struct c0_run_conf *c = stacks3(sim, st);
	struct heard h = { 0 };
	c0_run_conf_set_progress(c, listen, &h);
	struct c0_result *r = NULL;
	CHECK(c0_run(c, st, 3, &r) == C0_OK && r);
	const char *want[] = { "drift", "support", "intensity", "render", "bleaching", "matirf" };
	CHECK_MSG(h.nstages == 6, "%d stages heard", h.nstages);
	for (int i = 0; i < 6 && i < h.nstages; i++)
		CHECK_MSG(!strcmp(h.stages[i], want[i]), "stage %d: %s, expected %s", i, h.stages[i], want[i]);
	CHECK(h.calls >= 12 && !h.bad_fraction && !h.backwards && h.last == 1);
	c0_result_free(r);

	const char *stops[] = { "drift", "support", "matirf" };
	for (int i = 0; i < 3; i++) {
		struct heard s = { .stop_at = stops[i] };
		c0_run_conf_set_progress(c, listen, &s);
		r = (struct c0_result *)&s;   /* overwritten with NULL */
		int rc = c0_run(c, st, 3, &r);
		CHECK_MSG(rc == C0_ECANCELED && !r && strstr(c0_last_error(), stops[i]), "stop at %s: status %d, '%s'",
			  stops[i], rc, c0_last_error());
		CHECK(!heard(&s, "matirf") || !strcmp(stops[i], "matirf"));
	}
	struct heard s = { .stop_at = "support" };
	c0_run_conf_set_progress(c, listen, &s);
	r = NULL;
	CHECK(c0_run_support(c, st, 1, &r) == C0_ECANCELED && !r);
	int h2, w2;
	const float *img[3];
	struct c0_run_conf *m = c0_run_conf_new();
	CHECK(m && c0_run_conf_set(m, "angles", "62,65,68") == C0_OK);
	for (int q = 0; q < 3; q++)
		img[q] = c0_simulation_stack(sim, q, &st[q].frames, &h2, &w2);   /* first frames as images */
	struct heard mh = { .stop_at = "matirf" };
	c0_run_conf_set_progress(m, listen, &mh);
	CHECK(c0_run_matirf(m, img, 3, h2, w2, &r) == C0_ECANCELED && !r && mh.calls == 1);
	c0_run_conf_set_progress(m, NULL, NULL);
	CHECK(c0_run_matirf(m, img, 3, h2, w2, &r) == C0_OK && r);
	c0_result_free(r);
	c0_run_conf_free(m);
	c0_run_conf_free(c);
	c0_simulation_free(sim);
}

int main(void)
{
	RUN(test_simulation);
	RUN(test_steps);
	RUN(test_progress_cancel);
	return CHECK_DONE();
}
