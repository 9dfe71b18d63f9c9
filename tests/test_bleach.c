/* Bleaching fit and factors (stages/bleach.h) on synthetic frame sums, the
 * closed-form factors against the explicit mean, the depth offset a rate
 * error leaves against the depth fit, and bad options. */
#include "check.h"
#include "stages/bleach.h"
#include "stages/depthfit.h"
#include "optics/tirf.h"
#include "io/frames.h"
#include "core/err.h"
#include "core/rng.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void test_fit(void)
{
	/* 4 stacks of different lengths, recorded 2, 0, 3, 1 with gaps */
	const int n = 4;
	const int64_t T[4] = { 400, 500, 300, 450 };
	struct c0_bleach_conf c = { .norder = 4, .order = { 2, 0, 3, 1 }, .ngaps = 3, .gap_frames = { 50, 0, 120 } };
	CHECK(c0_bleach_check(&c, n) == C0_OK);
	const double k = 2e-4, A[4] = { 5e4, 2e4, 8e4, 1e4 }, B[4] = { 3e5, 2.5e5, 2e5, 1e5 };
	/* starts from the order and gaps: 2 at 0, 0 at 300+50, 3 at 350+400, 1 at 750+450+120 */
	const double start[4] = { 350, 1320, 0, 750 };
	struct c0_rng r;
	c0_rng_init(&r, 5, 0);
	double *S[4];
	for (int q = 0; q < n; q++) {
		S[q] = malloc(sizeof(double) * (size_t)T[q]);
		for (int t = 0; t < T[q]; t++)
			S[q][t] = B[q] + A[q] * exp(-k * (start[q] + t)) * (1 + 0.01 * c0_rng_normal(&r));
	}
	struct c0_bleach_result res;
	memset(&res, 0, sizeof res);
	CHECK(c0_bleach_fit(n, (const double *const *)S, T, B, -1, &res) == C0_OK);
	CHECK_REL(res.k, k, 0.03);
	CHECK(res.k == res.k_fit);
	CHECK(res.k_sd > 0 && fabs(res.k - k) < 4 * res.k_sd);
	c0_bleach_factors(&c, n, T, &res);
	for (int q = 0; q < n; q++) {
		CHECK_CLOSE(res.start[q], start[q], 1e-9);
		double f = 0;   /* the slow obvious mean */
		for (int t = 0; t < T[q]; t++)
			f += exp(-res.k * (start[q] + t)) / (double)T[q];
		CHECK_REL(res.factor[q], f, 1e-9);
	}
	/* interleaved: every stack spans the same time, factors nearly equal */
	struct c0_bleach_conf ci = { .interleaved = 1 };
	c0_bleach_factors(&ci, n, T, &res);
	CHECK_CLOSE(res.start[3], 0.75, 1e-12);
	for (int q = 0; q < n; q++) {
		double f = 0;
		for (int t = 0; t < T[q]; t++)
			f += exp(-res.k * (t + q / 4.0)) / (double)T[q];
		CHECK_REL(res.factor[q], f, 1e-9);
	}
	/* no signal above the background: refused, not a division by zero */
	double Bbig[4] = { 1e9, 1e9, 1e9, 1e9 };
	CHECK(c0_bleach_fit(n, (const double *const *)S, T, Bbig, -1, &res) == C0_EINVAL);
	for (int q = 0; q < n; q++)
		free(S[q]);
}

/* the window's sum from the profiles against the slow per-pixel weights:
 * (in the column band) + (in the row band) - 1, a pixel's share of each
 * band its overlap with it */
static void test_window_sum(void)
{
	const int H = 9, W = 13;
	float img[9 * 13];
	struct c0_rng r;
	c0_rng_init(&r, 3, 0);
	for (int i = 0; i < H * W; i++)
		img[i] = (float)c0_rng_uniform(&r);
	const struct c0_bleach_window w = { 1.3, 10.6, 0.25, 7.5, NULL, NULL };
	double slow = 0, total = 0;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			double wx = fmax(0, fmin(w.x1, x + 1) - fmax(w.x0, x)), wy = fmax(0, fmin(w.y1, y + 1) - fmax(w.y0, y));
			slow += img[y * W + x] * (wx + wy - 1), total += img[y * W + x];
		}
	double got;
	CHECK(c0_bleach_window_sum(&w, img, H, W, &got) == C0_OK);
	CHECK_REL(got, slow, 1e-12);
	const struct c0_bleach_window all = { 0, W, 0, H, NULL, NULL };
	CHECK(c0_bleach_window_sum(&all, img, H, W, &got) == C0_OK);
	CHECK_REL(got, total, 1e-12);
}

/* a linear drift of dx px per frame */
static void shift_x(const void *ctx, int q, int64_t t, double *dx, double *dy)
{
	*dx = *(const double *)ctx * (q * 200 + t), *dy = 0;
}

/* Spots drifting out of the field (none come in: the sample ends at its
 * edges, as in a simulation) fade the whole frames' sums faster than the
 * bleaching does; the window that follows them reads the rate */
static void test_window_drift(void)
{
	enum { n = 3, T = 200, H = 24, W = 32, K = 40 };
	const double k = 1e-4, v = 4.0 / (n * T), bg = 10;   /* 4 px over the acquisition */
	float *data[n];
	double sx[K], sy[K];
	struct c0_rng r;
	c0_rng_init(&r, 11, 0);
	for (int j = 0; j < K; j++)
		sx[j] = W * c0_rng_uniform(&r), sy[j] = H * c0_rng_uniform(&r);
	struct c0_frames f[n];
	double B[n], Bw[n];
	const struct c0_bleach_window win = { 0, W - 4, 0, H, shift_x, &v };
	for (int q = 0; q < n; q++) {
		data[q] = malloc(sizeof(float) * T * H * W);
		float *bgi = malloc(sizeof(float) * H * W);
		for (int t = 0; t < T; t++)
			for (int y = 0; y < H; y++)
				for (int x = 0; x < W; x++) {
					double a = 0, u = q * T + t;
					for (int j = 0; j < K; j++)
						a += 100 * exp(-(pow(x + 0.5 - sx[j] - v * u, 2) + pow(y + 0.5 - sy[j], 2)) / 2);
					data[q][((size_t)t * H + y) * W + x] = (float)(bg + a * exp(-k * u));
					bgi[y * W + x] = (float)bg;
				}
		CHECK(c0_frames_wrap(&f[q], data[q], T, H, W, 100, "drift") == C0_OK);
		B[q] = bg * H * W;
		CHECK(c0_bleach_window_sum(&win, bgi, H, W, &Bw[q]) == C0_OK);
		CHECK(c0_frames_read(&f[q], 0, bgi) == C0_OK);   /* read before: its profiles are read again */
		CHECK(c0_frames_keep_profiles(&f[q]) == C0_OK);
		free(bgi);
	}
	const double *sums, *rows, *cols;
	CHECK(c0_frames_profiles(&f[0], &sums, &rows, &cols) == C0_OK);
	double r0 = 0, c5 = 0;   /* frame 0's first row, frame 1's sixth column */
	for (int x = 0; x < W; x++)
		r0 += data[0][x];
	for (int y = 0; y < H; y++)
		c5 += data[0][((size_t)H + y) * W + 5];
	CHECK_REL(rows[0], r0, 1e-12);
	CHECK_REL(cols[W + 5], c5, 1e-12);
	struct c0_bleach_conf c = { 0 };
	struct c0_bleach_result whole, moved;
	CHECK(c0_bleach_run(&c, n, f, B, NULL, &whole) == C0_OK);
	CHECK(c0_bleach_run(&c, n, f, Bw, &win, &moved) == C0_OK);
	fprintf(stderr, "bleaching under drift: rate %.3g (whole frames %.3g) for %.3g\n", moved.k, whole.k, k);
	CHECK_REL(moved.k, k, 0.05);
	CHECK(whole.k > 1.5 * k);   /* the case does need the window */
	for (int q = 0; q < n; q++)
		c0_frames_close(&f[q]), free(data[q]);
}

static void test_check(void)
{
	struct c0_bleach_conf c = { .norder = 3, .order = { 0, 1, 1 } };
	CHECK(c0_bleach_check(&c, 3) == C0_EINVAL && strstr(c0_errmsg(), "twice"));
	c.order[2] = 3;
	CHECK(c0_bleach_check(&c, 3) == C0_EINVAL && strstr(c0_errmsg(), "not a stack number"));
	c.norder = 2;
	CHECK(c0_bleach_check(&c, 3) == C0_EINVAL && strstr(c0_errmsg(), "2 stack numbers for 3"));
	struct c0_bleach_conf g = { .ngaps = 3, .gap_frames = { 1, 2, 3 } };
	CHECK(c0_bleach_check(&g, 3) == C0_EINVAL && strstr(c0_errmsg(), "gaps_frames"));
	g.ngaps = 2, g.gap_frames[1] = -1;
	CHECK(c0_bleach_check(&g, 3) == C0_EINVAL && strstr(c0_errmsg(), "negative"));
	struct c0_bleach_conf f = { .mode = C0_BLEACH_KNOWN, .nfactors = 2, .factor = { 1, 0 } };
	CHECK(c0_bleach_check(&f, 2) == C0_EINVAL && strstr(c0_errmsg(), "factor 2"));
}

/* mode repeat: the rate from the ratio of the repeat's factor to the first
 * stack's (equal lengths, gaps between), checked against the explicit means */
static void test_repeat(void)
{
	const int n = 4;
	const int64_t T[4] = { 300, 250, 400, 300 };
	const double k = 3e-5, start[4] = { 0, 340, 590, 1030 };   /* gaps 40, 0, 40 */
	double F[4];
	for (int q = 0; q < n; q++) {
		F[q] = 0;
		for (int t = 0; t < T[q]; t++)
			F[q] += exp(-k * (start[q] + t)) / (double)T[q];
	}
	struct c0_bleach_conf c = { .mode = C0_BLEACH_REPEAT, .ngaps = 3, .gap_frames = { 40, 0, 40 }, .repeat_ratio = F[3] / F[0] };
	struct c0_bleach_result res;
	memset(&res, 0, sizeof res);
	CHECK(c0_bleach_check(&c, n) == C0_OK);
	CHECK(c0_bleach_repeat(&c, n, T, &res) == C0_OK);
	CHECK_REL(res.k, k, 1e-9);
	for (int q = 0; q < n; q++)
		CHECK_REL(res.factor[q], F[q], 1e-9);
	c.repeat_ratio = F[0] / F[3];   /* brighter at the end: held at 0 */
	CHECK(c0_bleach_repeat(&c, n, T, &res) == C0_OK);
	CHECK_REL(res.k_fit, -k, 1e-9);
	CHECK(res.k == 0 && res.factor[0] == 1 && res.factor[3] == 1);
	c.repeat_ratio = 0;
	CHECK(c0_bleach_repeat(&c, n, T, &res) == C0_EINVAL && strstr(c0_errmsg(), "repeat"));
	struct c0_bleach_conf o = { .mode = C0_BLEACH_REPEAT, .norder = 3, .order = { 0, 2, 1 } };
	CHECK(c0_bleach_check(&o, 3) == C0_EINVAL && strstr(c0_errmsg(), "recorded last"));
	struct c0_bleach_conf i = { .mode = C0_BLEACH_REPEAT, .interleaved = 1 };
	CHECK(c0_bleach_check(&i, 3) == C0_EINVAL && strstr(c0_errmsg(), "sequential"));
}

/* frame sums that rise: the fit says so (k_fit < 0), the rate is held at 0
 * and every factor is 1; a falling fit is left alone (test_fit) */
static void test_rise(void)
{
	const int n = 3;
	const int64_t T[3] = { 200, 200, 200 };
	struct c0_bleach_conf c = { 0 };
	const double k = -1e-4, A = 4e4, B[3] = { 1e5, 1e5, 1e5 };
	double *S[3];
	for (int q = 0; q < n; q++) {
		S[q] = malloc(sizeof(double) * (size_t)T[q]);
		for (int t = 0; t < T[q]; t++)
			S[q][t] = B[q] + A * exp(-k * (200.0 * q + t));
	}
	struct c0_bleach_result res;
	memset(&res, 0, sizeof res);
	CHECK(c0_bleach_fit(n, (const double *const *)S, T, B, -1, &res) == C0_OK);
	CHECK(res.k_fit < 0 && fabs(res.k_fit / k - 1) < 0.05);
	CHECK(res.k == 0);
	c0_bleach_factors(&c, n, T, &res);
	for (int q = 0; q < n; q++)
		CHECK(res.factor[q] == 1);
	for (int q = 0; q < n; q++)
		free(S[q]);
}

/* frame sums whose noise spans frames (AR(1), rho 0.5, as a blink lasting
 * a frame or two): the reported sd matches the scatter of the fits over
 * many draws, where the independent-frames formula reads sqrt(3)x small */
static void test_sd_correlated(void)
{
	enum { n = 3, T = 300, DRAWS = 400 };
	const int64_t Ts[n] = { T, T, T };
	const double k = 1e-4, A = 3e4, B[n] = { 1e5, 1e5, 1e5 }, rho = 0.5, sd = 600;
	struct c0_rng r;
	c0_rng_init(&r, 11, 0);
	double *S[n], sum = 0, sum2 = 0, sdsum = 0, rhosum = 0;
	for (int q = 0; q < n; q++)
		S[q] = malloc(sizeof(double) * T);
	for (int d = 0; d < DRAWS; d++) {
		for (int q = 0; q < n; q++) {
			double e = sd * c0_rng_normal(&r);
			for (int t = 0; t < T; t++) {
				e = rho * e + sd * sqrt(1 - rho * rho) * c0_rng_normal(&r);
				S[q][t] = B[q] + A * exp(-k * (300.0 * q + t)) + e;
			}
		}
		struct c0_bleach_result res;
		memset(&res, 0, sizeof res);
		CHECK(c0_bleach_fit(n, (const double *const *)S, Ts, B, -1, &res) == C0_OK);
		sum += res.k_fit, sum2 += res.k_fit * res.k_fit, sdsum += res.k_sd, rhosum += res.rho;
	}
	const double mean = sum / DRAWS, scatter = sqrt(sum2 / DRAWS - mean * mean);
	printf("AR(1) rho 0.5: fits' scatter %.3g, reported sd %.3g (mean), rho %.3f\n", scatter, sdsum / DRAWS, rhosum / DRAWS);
	CHECK(fabs(mean - k) < 3 * scatter / sqrt(DRAWS));   /* unbiased */
	CHECK(fabs(sdsum / DRAWS / scatter - 1) < 0.15);
	CHECK(fabs(rhosum / DRAWS - rho) < 0.05);
	for (int q = 0; q < n; q++)
		free(S[q]);
}

/* A start-up transient in the first stack recorded (its signal 3 % above
 * the steady state at the start, relaxing over 40 frames), 5 stacks of 500
 * frames fading at k: with the first stack named, the fit finds k within
 * 4 sds where the plain fit reads the transient as fade; without a
 * transient, seeds 1-200, the rule leaves the first stack in on all but a
 * few (3 sds, one-sided: 0.13 % expected). */
static void transient_sums(int seed, double amp, double k, double *S[5], int64_t T[5])
{
	struct c0_rng r;
	c0_rng_init(&r, (uint64_t)seed, 3);
	for (int q = 0; q < 5; q++) {
		T[q] = 500;
		for (int t = 0; t < 500; t++) {
			const double m = 4e4 * exp(-0.5 * q) * exp(-k * (500.0 * q + t));
			S[q][t] = 1e5 + m * (1 + (q ? 0 : amp * exp(-t / 40.0))) + 100 * c0_rng_normal(&r);
		}
	}
}

static void test_transient(void)
{
	const double k = 2e-5, B[5] = { 1e5, 1e5, 1e5, 1e5, 1e5 };
	double *S[5];
	int64_t T[5];
	for (int q = 0; q < 5; q++)
		S[q] = malloc(sizeof(double) * 500);
	struct c0_bleach_result plain, res;
	memset(&plain, 0, sizeof plain), memset(&res, 0, sizeof res);
	transient_sums(1, 0.03, k, S, T);
	CHECK(c0_bleach_fit(5, (const double *const *)S, T, B, -1, &plain) == C0_OK);
	CHECK(c0_bleach_fit(5, (const double *const *)S, T, B, 0, &res) == C0_OK);
	fprintf(stderr, "transient: k %.3g plain, %.3g +- %.2g with the first stack's second half (true %.3g)\n", plain.k,
		res.k, res.k_sd, k);
	CHECK(res.first_left_out && !plain.first_left_out);
	CHECK_MSG(fabs(res.k - k) < 4 * res.k_sd && plain.k > k + 4 * res.k_sd, "k %.3g (plain %.3g), true %.3g", res.k, plain.k, k);
	int left = 0;
	for (int seed = 1; seed <= 200; seed++) {
		transient_sums(seed, 0, k, S, T);
		memset(&res, 0, sizeof res);
		CHECK(c0_bleach_fit(5, (const double *const *)S, T, B, 0, &res) == C0_OK);
		left += res.first_left_out;
	}
	CHECK_MSG(left <= 3, "no transient: the first stack left out on %d of 200 seeds", left);
	for (int q = 0; q < 5; q++)
		free(S[q]);
}

/* The first-order depth offset of a rate error against the depth fit
 * itself: intensities of one depth, divided by factors off by e^{-tau dk},
 * read by c0_depth_fit_y; stacks recorded in turn (tau alike) read none */
static void test_depth_per_rate(void)
{
	const struct c0_tirf t = C0_TIRF_DEFAULTS;
	const double ang[8] = { 62.5, 63.2, 64, 65, 66, 67, 68.5, 70 }, gain[8] = { 1, 1.1, 0.9, 1, 1.2, 1, 0.8, 1 };
	double tau[8], same[8];
	for (int q = 0; q < 8; q++)
		tau[q] = 500 * q + 249.5, same[q] = 2000;
	for (int nq = 3; nq <= 8; nq += 5)
		for (double z = 50; z <= 300; z += 125) {
			double per = 0, none = 1;
			CHECK(!c0_bleach_depth_per_rate(&t, nq, ang, gain, tau, z, &per));
			CHECK(!c0_bleach_depth_per_rate(&t, nq, ang, gain, same, z, &none));
			CHECK(fabs(none) < 1e-9 * fabs(per));
			const double dk = 5 / fabs(per);   /* a 5 nm offset */
			float y0[8], y1[8], d[2];
			const float *yy[2][8];
			for (int q = 0; q < nq; q++) {
				double p;
				c0_tirf_p(&t, ang[q], &p);
				y0[q] = (float)(gain[q] * c0_tirf_i0(&t, ang[q]) * exp(-p * z));
				y1[q] = (float)(y0[q] * exp(tau[q] * dk));
				yy[0][q] = &y0[q], yy[1][q] = &y1[q];
			}
			CHECK(!c0_depth_fit_y(&t, nq, ang, gain, 0, 500, yy[0], 1, NULL, &d[0]));
			CHECK(!c0_depth_fit_y(&t, nq, ang, gain, 0, 500, yy[1], 1, NULL, &d[1]));
			CHECK_CLOSE(d[0], z, 0.05);
			printf("  %d angles, z %g nm: %.0f nm per unit rate; the fit moved %.3f nm, first order %.3f\n", nq, z, per,
			       d[1] - d[0], per * dk);
			CHECK_MSG(fabs(d[1] - d[0] - per * dk) < 0.05, "%d angles, z %g: fit moved %.3f nm, first order %.3f",
				  nq, z, d[1] - d[0], per * dk);
			CHECK(per < 0);   /* a rate too high brightens the later, steeper stacks: shallower */
		}
}

int main(void)
{
	RUN(test_depth_per_rate);
	RUN(test_transient);
	RUN(test_sd_correlated);
	RUN(test_rise);
	RUN(test_repeat);
	RUN(test_fit);
	RUN(test_check);
	RUN(test_window_sum);
	RUN(test_window_drift);
	return CHECK_DONE();
}
