/* The whole method as one call: the same stacks given as files and as
 * arrays in memory give identical results; the run conf's defaults are the
 * stages' defaults; bad parameters are refused naming the parameter. */
#define _XOPEN_SOURCE 700
#include "check.h"
#include "core/err.h"
#include "col0rme.h"
#include "app/result.h"
#include "app/pipeline_conf.h"
#include "app/stacks.h"
#include "io/outdir.h"
#include "app/params.h"
#include "report/html.h"
#include "cli/confopts.h"
#include "stages/depthpool.h"
#include "sim/sim.h"
#include "io/tiff.h"
#include "core/mem.h"
#include "core/order.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static int same_f(const float *a, const float *b, size_t n)
{
	return a && b && !memcmp(a, b, n * sizeof *a);
}

static void expect_einval(int st, const char *name)
{
	CHECK_MSG(st == C0_EINVAL && strstr(c0_last_error(), name), "status %d, message '%s' should name %s", st,
		  c0_last_error(), name);
}

static void test_conf(void)
{
	struct c0_run_conf c = C0_RUN_CONF_DEFAULTS, d;
	c0_run_conf_init(&d);
	CHECK(!memcmp(&c, &d, sizeof c));
	/* the defaults are the stages' own */
	struct c0_stage_confs s;
	c.fwhm_nm = 229;
	CHECK(c0_run_conf_stages(&c, 100, &s) == C0_OK);
	struct c0_support_conf sd = C0_SUPPORT_DEFAULTS;
	struct c0_intensity_conf id = C0_INTENSITY_DEFAULTS;
	struct c0_matirf_conf md = C0_MATIRF_DEFAULTS;
	CHECK(s.support.grid.srf == sd.grid.srf && s.support.penalty == sd.penalty && s.support.lambda_rel == sd.lambda_rel &&
	      s.support.lag == sd.lag && s.support.fista.maxit == sd.fista.maxit && s.support.fista.tol == sd.fista.tol &&
	      s.support.cel0_outer == sd.cel0_outer);
	CHECK(s.support.grid.pixel_nm == 100 && s.support.grid.fwhm_nm == 229 && s.intensity.grid.pixel_nm == 100 &&
	      s.intensity.grid.fwhm_nm == 229);   /* one grid for both stages */
	CHECK(s.intensity.grid.srf == id.grid.srf && s.intensity.background == id.background && s.intensity.beta == id.beta &&
	      s.intensity.nu == id.nu && s.intensity.mu == id.mu && s.intensity.tol == id.tol &&
	      s.intensity.maxit == id.maxit && s.intensity.graph_radius == id.graph_radius &&
	      s.intensity.graph_orient == id.graph_orient);
	CHECK(!memcmp(&s.matirf.tirf, &md.tirf, sizeof md.tirf) && s.matirf.z0_nm == md.z0_nm && s.matirf.z1_nm == md.z1_nm &&
	      s.matirf.dz_nm == md.dz_nm && s.matirf.reg == md.reg && s.matirf.kappa == md.kappa && s.matirf.wz == md.wz &&
	      s.matirf.sparsity == md.sparsity && s.matirf.pdhg.maxit == md.pdhg.maxit && s.matirf.pdhg.tol == md.pdhg.tol &&
	      s.matirf.pdhg.relax == md.pdhg.relax && s.matirf.fused == md.fused);
	CHECK(s.pool_nm == C0_DEPTH_POOL_FWHM * 229 && s.pool_range_nm == C0_DEPTH_POOL_RANGE_NM);
	/* the frame halves serve the guided pool's depth fit: 2D, or no guide, none */
	CHECK(s.intensity.noise_block == 0 && id.noise_block == 0);
	struct c0_run_conf c3 = c;
	c3.nangles = 2, c3.angles[0] = 62, c3.angles[1] = 66;
	CHECK(c0_run_conf_stages(&c3, 100, &s) == C0_OK && s.intensity.noise_block == 20 && c3.depth_noise_block == 20);
	c3.depth_pool_range_nm = 0;
	CHECK(c0_run_conf_stages(&c3, 100, &s) == C0_OK && s.intensity.noise_block == 0);
	CHECK(c0_run_conf_stages(&c, 100, &s) == C0_OK);
	/* kappa -1: the plain default, or the deconvolution's with psf_fwhm_nm
	 * (matirf only: run does not deconvolve); a given kappa is kept */
	struct c0_matirf_conf m;
	c.psf_fwhm_nm = 240;
	c0_run_conf_matirf(&c, &m);
	CHECK(c.kappa == -1 && m.kappa == C0_MATIRF_KAPPA_DECONV && C0_MATIRF_KAPPA_DECONV != md.kappa);
	CHECK(c0_run_conf_stages(&c, 100, &s) == C0_OK && s.matirf.kappa == md.kappa);
	c.kappa = 0.02;
	c0_run_conf_matirf(&c, &m);
	CHECK(m.kappa == 0.02);
	c.kappa = -2;
	c0_run_conf_matirf(&c, &m);
	CHECK(c0_run_conf_matirf_check(&c, &m, c.nangles) == C0_EINVAL && strstr(c0_errmsg(), "kappa -2"));
	c.kappa = -1, c.psf_fwhm_nm = 0;
	c0_run_conf_matirf(&c, &m);
	CHECK(c0_run_conf_matirf_check(&c, &m, c.nangles) == C0_OK || !strstr(c0_errmsg(), "kappa"));
	c.depth_pool_range_nm = -2;
	CHECK(c0_run_conf_stages(&c, 100, &s) == C0_EINVAL && strstr(c0_errmsg(), "depth_pool_range_nm"));
	c.depth_pool_range_nm = -1;
	/* set by name */
	CHECK(c0_run_conf_set(&c, "lambda", "1e-3") == C0_OK && c.lambda == 1e-3);
	CHECK(c0_run_conf_set(&c, "angles", "62,64,66") == C0_OK && c.nangles == 3 && c.angles[2] == 66);
	CHECK(c0_run_conf_set(&c, "support_stacks", "1,3") == C0_OK && c.nsupport_stacks == 2 && c.support_stacks[1] == 3);
	CHECK(c0_run_conf_set(&c, "penalty", "cel0") == C0_OK && c.penalty == C0_PENALTY_CEL0);
	CHECK(c0_run_conf_set(&c, "reg", "hessian") == C0_OK && c.reg == C0_REG_HESSIAN);
	CHECK(c0_run_conf_set(&c, "z_range_nm", "0,300,10") == C0_OK && c.z_range_nm[1] == 300);
	CHECK(c0_run_conf_set(&c, "baseline", "1") == C0_OK && c.baseline == 1);
	CHECK(c0_run_conf_set(&c, "srf", "2") == C0_OK && c.srf == 2);
	/* every parameter in the table is settable */
	const char *doc;
	int np = 0;
	for (const char *name; (name = c0_run_conf_param(np, &doc)); np++)
		CHECK_MSG(doc && doc[0] && c0_run_conf_set(&d, name, "foo") == C0_EINVAL && strstr(c0_last_error(), name),
			  "%s", name);
	CHECK(np > 30);
	expect_einval(c0_run_conf_set(&c, "lambda", "abc"), "lambda");
	expect_einval(c0_run_conf_set(&c, "lamda", "1e-3"), "lamda");
	expect_einval(c0_run_conf_set(&c, "penalty", "l2"), "penalty");
	expect_einval(c0_run_conf_set(&c, "srf", "2.5"), "srf");
	expect_einval(c0_run_conf_set(&c, "angles", "62,x"), "angles");
	expect_einval(c0_run_conf_set(&c, "z_range_nm", "0,400"), "z_range_nm");
	expect_einval(c0_run_conf_set(&c, "baseline", "2"), "baseline");
	CHECK(c.srf == 2 && c.nangles == 3 && c.z_range_nm[1] == 300);   /* a refused value changes nothing */
}

static void compare(const struct c0_result *a, const struct c0_result *b, int nq)
{
	int h, w, h2, w2, nz, nz2;
	const uint8_t *sa = c0_result_support(a, &h, &w), *sb = c0_result_support(b, &h2, &w2);
	CHECK(sa && sb && h == h2 && w == w2 && !memcmp(sa, sb, (size_t)h * w));
	int on = 0;
	for (int i = 0; sa && i < h * w; i++)
		on += sa[i];
	CHECK_MSG(on > 20, "%d support pixels", on);
	for (int q = 0; q < nq; q++) {
		const float *x = c0_result_intensity(a, q, &h, &w);
		CHECK(same_f(x, c0_result_intensity(b, q, &h2, &w2), (size_t)h * w) && h == h2 && w == w2);
		x = c0_result_background(a, q, &h, &w);
		CHECK(same_f(x, c0_result_background(b, q, &h2, &w2), (size_t)h * w) && h == h2 && w == w2);
	}
	CHECK(!c0_result_intensity(a, nq, NULL, NULL) && !c0_result_background(a, -1, NULL, NULL));
	const float *v = c0_result_volume(a, &nz, &h, &w);
	CHECK(v && same_f(v, c0_result_volume(b, &nz2, &h2, &w2), (size_t)nz * h * w) && nz == nz2 && h == h2);
	CHECK(nz == 20 && h == 4 * 20 && w == 4 * 24);
	double tot = 0;
	for (size_t i = 0; v && i < (size_t)nz * h * w; i++)
		tot += v[i];
	CHECK(tot > 0);
	CHECK(same_f(c0_result_depth(a, &h, &w), c0_result_depth(b, &h2, &w2), (size_t)h * w));
	const double *z = c0_result_z_nm(a, &nz), *z2 = c0_result_z_nm(b, &nz2);
	CHECK(z && z2 && nz == nz2 && !memcmp(z, z2, (size_t)nz * sizeof *z) && z[0] == 10);
	v = c0_result_baseline_volume(a, &nz, &h, &w);
	CHECK(v && same_f(v, c0_result_baseline_volume(b, &nz2, &h2, &w2), (size_t)nz * h * w) && h == 20 && w == 24);
	const char *ja = c0_result_report_json(a);
	CHECK(ja && strstr(ja, "\"lambda_max\"") && strstr(ja, "\"timings_s\"") && strstr(ja, "\"3D\""));
}

static void test_files_and_arrays(void)
{
	char dir[] = "/tmp/c0_test_pipeline_XXXXXX";
	CHECK(mkdtemp(dir) != NULL);
	char data[300], outa[300], outb[300];
	snprintf(data, sizeof data, "%s/data", dir);
	struct c0_sim_conf s;
	c0_sim_defaults(&s);
	s.seed = 5, s.width = 24, s.height = 20, s.frames = 120;
	c0_sim_default_angles(&s, 3);
	struct c0_outdir od;
	CHECK(c0_outdir_open(&od, data, 0) == C0_OK);
	struct c0_sim_result sr;
	CHECK(c0_simulate(&s, &od, &sr) == C0_OK);
	CHECK(c0_outdir_commit(&od) == C0_OK);
	c0_sim_result_free(&sr);

	struct c0_run_conf c;
	c0_run_conf_init(&c);
	char ang[128];
	snprintf(ang, sizeof ang, "%.17g,%.17g,%.17g", s.angles[0], s.angles[1], s.angles[2]);
	CHECK(c0_run_conf_set(&c, "fwhm_nm", "229") == C0_OK && c0_run_conf_set(&c, "angles", ang) == C0_OK &&
	      c0_run_conf_set(&c, "baseline", "1") == C0_OK);

	char paths[3][320];
	struct c0_stack fs[3] = { 0 }, ms[3] = { 0 };
	float *arr[3] = { 0 };
	for (int q = 0; q < 3; q++) {
		snprintf(paths[q], sizeof paths[q], "%s/stack_q%02d.tif", data, q + 1);
		fs[q].path = paths[q];
		struct c0_tiff_info in;
		CHECK(c0_tiff_load_f32(paths[q], &in, &arr[q]) == C0_OK);
		ms[q] = (struct c0_stack){ .data = arr[q], .frames = (int)in.pages, .height = (int)in.height,
					   .width = (int)in.width, .pixel_nm = 100 };
	}
	struct c0_result *ra = NULL, *rb = NULL;
	CHECK(c0_run(&c, fs, 3, &ra) == C0_OK);
	CHECK(c0_run(&c, ms, 3, &rb) == C0_OK);
	if (ra && rb) {
		CHECK(c0_result_nstacks(ra) == 3);
		compare(ra, rb, 3);
		/* written: the files of `col0rme run`; never into an input's directory */
		snprintf(outa, sizeof outa, "%s/a", dir), snprintf(outb, sizeof outb, "%s/b", dir);
		CHECK(c0_result_write(ra, outa, 0) == C0_OK && c0_result_write(rb, outb, 0) == C0_OK);
		const char *files[] = { "support.tif", "rx.tif", "intensity_q03.tif", "background_q01.tif", "volume.tif",
					"depth.tif", "depth.png", "baseline_volume.tif", "report.json" };
		for (size_t k = 0; k < sizeof files / sizeof *files; k++) {
			char p[400];
			snprintf(p, sizeof p, "%s/%s", outb, files[k]);
			CHECK_MSG(access(p, F_OK) == 0, "%s", p);
		}
		expect_einval(c0_result_write(ra, data, 1), "outdir");
		CHECK(c0_result_write(rb, outb, 0) != C0_OK && strstr(c0_last_error(), "not empty"));
	}
	c0_result_free(ra), c0_result_free(rb);
	ra = rb = NULL;

	/* bad input: refused with the parameter named, no result */
	struct c0_run_conf b = c;
	b.fwhm_nm = 0;
	expect_einval(c0_run(&b, ms, 3, &ra), "fwhm_nm");
	CHECK(!ra);
	expect_einval(c0_run(&c, ms, 2, &ra), "angles");
	b = c, b.graph_radius = 0.5;
	expect_einval(c0_run(&b, ms, 3, &ra), "graph_radius");
	b = c, b.graph_orient = -1;
	expect_einval(c0_run(&b, ms, 3, &ra), "graph_orient");
	b = c, b.depth_noise_block = -1;
	expect_einval(c0_run(&b, ms, 3, &ra), "depth_noise_block");
	b = c, b.nsupport_stacks = 1, b.support_stacks[0] = 4;
	expect_einval(c0_run(&b, ms, 3, &ra), "support_stacks");
	b = c, b.angles[1] = 50, b.angles[2] = 50;   /* one below critical is support-only; two leave one TIRF angle */
	expect_einval(c0_run(&b, ms, 3, &ra), "angles");
	b = c, b.nacquisition_order = 3, b.acquisition_order[0] = 1, b.acquisition_order[1] = 1, b.acquisition_order[2] = 2;
	expect_einval(c0_run(&b, ms, 3, &ra), "acquisition_order");
	b = c, b.ngaps_frames = 3;
	expect_einval(c0_run(&b, ms, 3, &ra), "gaps_frames");
	struct c0_stack bad[3] = { ms[0], ms[1], ms[2] };
	bad[1].width = 20, bad[1].frames = 100;
	expect_einval(c0_run(&c, bad, 3, &ra), "array 2");
	bad[1] = ms[1], bad[0].pixel_nm = 0;
	expect_einval(c0_run(&c, bad, 3, &ra), "pixel_nm");
	CHECK(!ra);

	for (int q = 0; q < 3; q++)
		free(arr[q]);
	char cmd[400];
	snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
	CHECK(system(cmd) == 0);
}

/* The table's documented default is the defaults' value wherever it is a
 * plain value (a number, a list, a choice, on/off): docs/params.md and the
 * help cannot promise what the library does not do. */
static void test_param_defaults(void)
{
	const struct c0_run_conf d = C0_RUN_CONF_DEFAULTS;
	int n, checked = 0;
	const struct c0_param *t = c0_params(&n);
	for (int i = 0; i < n; i++) {
		struct c0_run_conf c = d;
		const char *def = t[i].def;
		if (t[i].type == C0_P_FLAG || (t[i].type == C0_P_ENUM && (!strcmp(def, "on") || !strcmp(def, "off"))))
			def = !strcmp(def, "on") ? (t[i].type == C0_P_FLAG ? "1" : "on") : !strcmp(def, "off") ? (t[i].type == C0_P_FLAG ? "0" : "off") : def;
		const int sentinel = t[i].type == C0_P_DOUBLE ? *(const double *)((const char *)&d + t[i].off) == -1
				     : t[i].type == C0_P_INT && *(const int *)((const char *)&d + t[i].off) == -1;
		if (sentinel) {   /* -1: the default, resolved by the stages, which the help must say */
			CHECK_MSG(strstr(t[i].help, "-1: the default"), "%s", t[i].name);
			continue;
		}
		if (t[i].type == C0_P_STRING || (t[i].count && strcmp(def, "none")))
			continue;
		if (t[i].count) {   /* a list whose default is none: empty */
			CHECK_MSG(*(const int *)((const char *)&d + t[i].count) == 0, "%s", t[i].name);
			checked++;
			continue;
		}
		/* setting the documented default must leave the defaults as they are */
		if (c0_param_set(&t[i], &c, t[i].name, def) == C0_OK) {
			CHECK_MSG(!memcmp(&c, &d, sizeof c), "%s: documented default '%s' differs from C0_RUN_CONF_DEFAULTS", t[i].name, def);
			checked++;
		}
	}
	CHECK_MSG(n <= C0_CLI_MAXPARAMS, "%d parameters, the CLI has room for %d", n, C0_CLI_MAXPARAMS);
	CHECK_MSG(checked >= 30, "%d of %d rows have a plain default", checked, n);
	/* and each row is a parameter c0_run_conf_set knows, once */
	for (int i = 0; i < n; i++)
		for (int j = i + 1; j < n; j++)
			CHECK_MSG(strcmp(t[i].name, t[j].name), "%s twice", t[i].name);
}

/* the report's quantile (a quickselect) against the obvious sort, on values
 * with many ties (a fine grid is mostly zeros), NaNs left out */
static int cmp_f(const void *a, const void *b)
{
	const float x = *(const float *)a, y = *(const float *)b;
	return (x > y) - (x < y);
}

static int cmp_d(const void *a, const void *b)
{
	const double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static void test_quantile(void)
{
	enum { N = 5003 };
	static float v[N], s[N];
	unsigned u = 12345;
	for (int t = 0; t < 3; t++) {
		size_t m = 0;
		for (int i = 0; i < N; i++) {
			u = u * 1103515245u + 12345u;
			const unsigned r = (u >> 8) % 1000;
			v[i] = t == 0 ? (float)r : t == 1 ? (r < 900 ? 0.f : (float)r / 7) : (r < 10 ? NAN : (float)(r % 5));
			if (!isnan(v[i]))
				s[m++] = v[i];
		}
		qsort(s, m, sizeof *s, cmp_f);
		const double qs[] = { 0, 0.005, 0.5, 0.9, 0.995, 0.999, 1 };
		for (size_t k = 0; k < sizeof qs / sizeof *qs; k++) {
			const size_t at = (size_t)fmin((double)m - 1, floor(qs[k] * (double)m));
			CHECK_MSG(c0_quantile(v, N, qs[k]) == s[at], "case %d, q %g: %g vs sorted %g", t, qs[k],
				  c0_quantile(v, N, qs[k]), s[at]);
		}
	}
	CHECK(c0_quantile(v, 0, 0.5) == 0);
}

/* c0_median against a sort, on both sides of its insertion sort's 16 values,
 * with ties; c0_median_of the same on floats */
static void test_median(void)
{
	unsigned u = 777;
	for (size_t n = 1; n <= 41; n++) {
		double v[41], s[41];
		float f[41];
		for (size_t i = 0; i < n; i++) {
			u = u * 1103515245u + 12345u;
			f[i] = (float)((u >> 8) % 9) - 4.5f, v[i] = s[i] = f[i];
		}
		qsort(s, n, sizeof *s, cmp_d);
		const double want = n % 2 ? s[n / 2] : (s[n / 2 - 1] + s[n / 2]) / 2;
		CHECK_MSG(c0_median_of(f, n) == want, "n %zu: %g vs %g", n, c0_median_of(f, n), want);
		CHECK_MSG(c0_median(v, n) == want, "n %zu: %g vs %g", n, c0_median(v, n), want);
		CHECK(memcmp(v, s, n * sizeof *v) == 0);   /* sorted in place */
	}
	CHECK(isnan(c0_median(NULL, 0)));
}

/* How many stacks the page cache keeps between the passes: the first ones
 * that fit in three quarters of the memory available, all when they all fit
 * or the memory is unknown */
static void test_keep_cached(void)
{
	const double G = 1e9, five[5] = { 4.2 * G, 4.2 * G, 4.2 * G, 4.2 * G, 4.2 * G };
	CHECK(c0_stacks_keep_cached(five, 5, 21 * G) == 3);   /* 15.75 GB: three of 21 */
	CHECK(c0_stacks_keep_cached(five, 5, 28 * G) == 5);   /* 21 <= 21 */
	CHECK(c0_stacks_keep_cached(five, 5, 27 * G) == 4);
	CHECK(c0_stacks_keep_cached(five, 5, 5 * G) == 0);
	CHECK(c0_stacks_keep_cached(five, 5, 0) == 5);
	const double mixed[3] = { 1 * G, 0, 9 * G };           /* an array counts 0 */
	CHECK(c0_stacks_keep_cached(mixed, 3, 8 * G) == 2);
	CHECK(c0_stacks_keep_cached(mixed, 3, 14 * G) == 3);
}

/* The THPeligible line of /proc/self/smaps for the mapping holding p: 1 or
 * 0, -1 where the kernel does not say */
static int thp_eligible(const void *p)
{
	FILE *f = fopen("/proc/self/smaps", "r");
	char line[512];
	int in = 0, e = -1;
	while (f && fgets(line, sizeof line, f)) {
		unsigned long lo, hi;
		char perms[8];
		if (sscanf(line, "%lx-%lx %7s", &lo, &hi, perms) == 3)   /* a mapping's first line */
			in = (unsigned long)p >= lo && (unsigned long)p < hi;
		else if (in && sscanf(line, "THPeligible: %d", &e) == 1)
			break;
	}
	if (f)
		fclose(f);
	return e;
}

/* A large buffer asks for transparent huge pages (core/mem.c): where the
 * kernel gives them only on request ("madvise"), its aligned inside is
 * eligible */
static void test_alloc_huge(void)
{
	FILE *f = fopen("/sys/kernel/mm/transparent_hugepage/enabled", "r");
	char mode[128] = "";
	if (f && !fgets(mode, sizeof mode, f))
		mode[0] = 0;
	if (f)
		fclose(f);
	mode[strcspn(mode, "\n")] = 0;
	const size_t n = 16u << 20;
	char *big = c0_alloc(n, 1);
	CHECK(big != NULL);
	if (!big || !strstr(mode, "[madvise]") || thp_eligible(big + n / 2) < 0) {
		printf("  (THP mode '%.40s', or smaps without THPeligible: eligibility not checked)\n", mode);
		free(big);
		return;
	}
	big[n / 2] = 1;
	CHECK(thp_eligible(big + n / 2) == 1);
	free(big);
}

int main(void)
{
	RUN(test_conf);
	RUN(test_param_defaults);
	RUN(test_files_and_arrays);
	RUN(test_quantile);
	RUN(test_median);
	RUN(test_keep_cached);
	RUN(test_alloc_huge);
	return CHECK_DONE();
}
