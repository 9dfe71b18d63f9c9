/* Depth pooling, the depth error metric, the depth colour code and the
 * depth readout of a volume: each against the slow obvious computation on
 * small cases; the MA-TIRF depth map against the truth on noise-free input. */
#include "check.h"
#include "stages/depthpool.h"
#include "stages/depthfit.h"
#include "stages/matirf.h"
#include "app/pipeline_conf.h"
#include "optics/tirf.h"
#include <stdio.h>
#include "app/depthcode.h"
#include "ops/splat.h"
#include "eval/metrics.h"
#include "core/rng.h"
#include "core/err.h"
#include "core/c0math.h"
#include "testkit/reference.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static struct c0_rng rng;

static void test_pool_window(void)
{
	enum { NY = 9, NX = 13 };
	float x[NY * NX], out[NY * NX];
	uint8_t m[NY * NX];
	for (int i = 0; i < NY * NX; i++)
		x[i] = (float)c0_rng_normal(&rng), m[i] = c0_rng_uniform(&rng) < 0.4;
	for (int h = 0; h <= 3; h++) {
		CHECK(c0_pool_window(x, m, NY, NX, h, out) == C0_OK);
		double err = 0;
		for (int y = 0; y < NY; y++)
			for (int xx = 0; xx < NX; xx++) {
				double s = 0;
				for (int dy = -h; dy <= h; dy++)
					for (int dx = -h; dx <= h; dx++) {
						int yy = y + dy, x2 = xx + dx;
						if (yy >= 0 && yy < NY && x2 >= 0 && x2 < NX && m[yy * NX + x2])
							s += x[yy * NX + x2];
					}
				if (!m[y * NX + xx])
					s = 0;
				err = fmax(err, fabs(s - out[y * NX + xx]));
			}
		CHECK_MSG(err < 1e-5, "h %d: max error %g", h, err);
	}
	/* rescaling keeps the depth profile and restores each pixel's own total */
	float f[2 * 4], own0[4] = { 1, 2, 0, 4 }, own1[4] = { 1, 1, 0, 2 }, p0[4] = { 2, 2, 3, 4 }, p1[4] = { 2, 1, 3, 0 };
	for (int i = 0; i < 8; i++)
		f[i] = (float)(1 + i);
	const float *own[2] = { own0, own1 }, *pool[2] = { p0, p1 };
	const int all[4] = { 0, 1, 2, 3 }, two[2] = { 1, 3 };
	c0_pool_rescale(f, 2, all, 4, 2, own, pool);
	CHECK_CLOSE(f[0], 1 * 2.0 / 4, 1e-6);   /* (1 + 1) / (2 + 2) */
	CHECK_CLOSE(f[4], 5 * 2.0 / 4, 1e-6);
	CHECK_CLOSE(f[1], 2 * 3.0 / 3, 1e-6);
	CHECK_CLOSE(f[2], 0, 0);
	CHECK_CLOSE(f[7], 8 * 6.0 / 4, 1e-6);
	/* by columns: pixels 1 and 3 only, bin j of column k at f[2 j + k] */
	float g[4] = { 2, 8, 6, 8 };
	c0_pool_rescale(g, 2, two, 2, 2, own, pool);
	CHECK_CLOSE(g[0], 2 * 3.0 / 3, 1e-6);
	CHECK_CLOSE(g[1], 8 * 6.0 / 4, 1e-6);
	CHECK_CLOSE(g[2], 6 * 3.0 / 3, 1e-6);
	CHECK_CLOSE(g[3], 8 * 6.0 / 4, 1e-6);
}

/* The guided window against the slow obvious sum (a neighbour counts when
 * it is on the mask and its guide within range of the centre's), the plain
 * window when the range spans every guide; the single-depth fit returns the
 * bin whose weights made the intensities. */
static void test_pool_guided(void)
{
	enum { NY = 9, NX = 13, NQ = 3, NP = NY * NX };
	float x[NQ][NP], out[NQ][NP], plain[NP], guide[NP];
	uint8_t m[NP];
	for (int i = 0; i < NP; i++) {
		for (int q = 0; q < NQ; q++)
			x[q][i] = (float)c0_rng_normal(&rng);
		m[i] = c0_rng_uniform(&rng) < 0.5, guide[i] = (float)(20 * (int)(10 * c0_rng_uniform(&rng)));
	}
	const float *xs[NQ] = { x[0], x[1], x[2] };
	float *os[NQ] = { out[0], out[1], out[2] };
	for (int h = 1; h <= 3; h++)
		for (int k = 0; k < 3; k++) {
			const double range = (double[]){ 10, 50, 1e9 }[k];
			CHECK(c0_pool_guided(xs, NQ, m, guide, range, NY, NX, h, os) == C0_OK);
			double err = 0;
			for (int q = 0; q < NQ; q++)
				for (int y = 0; y < NY; y++)
					for (int xx = 0; xx < NX; xx++) {
						const int p = y * NX + xx;
						double s = 0;
						for (int dy = -h; dy <= h; dy++)
							for (int dx = -h; dx <= h; dx++) {
								int yy = y + dy, x2 = xx + dx, o = yy * NX + x2;
								if (yy >= 0 && yy < NY && x2 >= 0 && x2 < NX && m[o] &&
								    fabs(guide[o] - guide[p]) <= range)
									s += x[q][o];
							}
						err = fmax(err, fabs((m[p] ? s : 0) - out[q][p]));
					}
			CHECK_MSG(err < 1e-5, "h %d, range %g: max error %g", h, range, err);
			if (range > 1e3) {
				CHECK(c0_pool_window(x[1], m, NY, NX, h, plain) == C0_OK);
				for (int i = 0; i < NP; i++)
					err = fmax(err, fabs(plain[i] - out[1][i]));
				CHECK_MSG(err < 1e-5, "h %d: guided with every guide in range vs plain %g", h, err);
			}
		}
	/* single depth: x = a W[.][j] (one pixel per bin, a > 0), and a pixel off the mask */
	enum { NZ = 6 };
	double W[NQ * NZ];
	for (int q = 0; q < NQ; q++)
		for (int j = 0; j < NZ; j++)
			W[q * NZ + j] = (1 + q) * exp(-(0.2 + 0.3 * q) * j);
	float y[NQ][NZ + 1], z[NZ + 1];
	uint8_t on[NZ + 1];
	for (int j = 0; j <= NZ; j++)
		for (int q = 0; q < NQ; q++)
			y[q][j] = j < NZ ? (float)((2 + j) * W[q * NZ + j]) : 1, on[j] = j < NZ;
	const float *ys[NQ] = { y[0], y[1], y[2] };
	c0_depth_single(W, NQ, NZ, 100, 20, ys, on, NZ + 1, z);
	for (int j = 0; j < NZ; j++)
		CHECK_MSG(z[j] == (float)(100 + (j + 0.5) * 20), "bin %d: depth %g", j, z[j]);
	CHECK(z[NZ] == 0);
}

/* The run's pooling on the support's pixel list against the dense oracles
 * above, bit for bit (a band of the summed-area table is the same table),
 * and the render's bands against the whole splat. */
static void test_pool_sparse(void)
{
	enum { NY = 23, NX = 17, NQ = 3, NP = NY * NX };
	float x[NQ][NP], dense[NQ][NP], guide[NP];
	uint8_t m[NP];
	for (int i = 0; i < NP; i++) {
		m[i] = c0_rng_uniform(&rng) < 0.3, guide[i] = m[i] ? (float)(20 * (int)(10 * c0_rng_uniform(&rng))) : 0;
		for (int q = 0; q < NQ; q++)
			x[q][i] = m[i] ? (float)c0_rng_uniform(&rng) : 0;
	}
	m[0] = 1, m[NP - 1] = 1;   /* the corners */
	struct c0_pixlist pl;
	CHECK(c0_pixlist_from_mask(m, NY, NX, &pl) == C0_OK);
	size_t M = 0;
	for (int i = 0; i < NP; i++)
		M += m[i];
	CHECK(pl.M == M && pl.row[NY] == M);
	float xs[NQ][NP], out[NQ][NP], gs[NP];
	for (size_t k = 0; k < M; k++) {
		CHECK(m[pl.pix[k]] && (k == 0 || pl.pix[k] > pl.pix[k - 1]) && c0_pixlist_find(&pl, pl.pix[k]) == (long)k);
		gs[k] = guide[pl.pix[k]];
		for (int q = 0; q < NQ; q++)
			xs[q][k] = x[q][pl.pix[k]];
	}
	CHECK(c0_pixlist_find(&pl, 1) == (m[1] ? 1 : -1));
	int bad = 0;
	for (int h = 0; h <= 4; h++) {
		CHECK(c0_pool_window(x[0], m, NY, NX, h, dense[0]) == C0_OK);
		CHECK(c0_pool_window_at(xs[0], &pl, h, out[0]) == C0_OK);
		for (size_t k = 0; k < M; k++)
			bad += memcmp(&out[0][k], &dense[0][pl.pix[k]], sizeof(float)) != 0;
		const float *xd[NQ] = { x[0], x[1], x[2] }, *xl[NQ] = { xs[0], xs[1], xs[2] };
		float *od[NQ] = { dense[0], dense[1], dense[2] }, *ol[NQ] = { out[0], out[1], out[2] };
		CHECK(c0_pool_guided(xd, NQ, m, guide, 30, NY, NX, h, od) == C0_OK);
		CHECK(c0_pool_guided_at(xl, NQ, &pl, gs, 30, NULL, 0, h, ol) == C0_OK);
		for (int q = 0; q < NQ; q++)
			for (size_t k = 0; k < M; k++)
				bad += memcmp(&out[q][k], &dense[q][pl.pix[k]], sizeof(float)) != 0;
		/* rescaling: columns on every other support pixel, and one off it */
		int col[NP], nc = 0;
		for (size_t k = 0; k < M; k += 2)
			col[nc++] = pl.pix[k];
		for (int p = 0; p < NP && nc < NP; p++)
			if (!m[p]) {
				col[nc] = p;
				for (int i = nc; i > 0 && col[i - 1] > p; i--)
					col[i] = col[i - 1], col[i - 1] = p;
				nc++;
				break;
			}
		float f0[2 * NP], f1[2 * NP];
		for (int i = 0; i < 2 * nc; i++)
			f0[i] = f1[i] = (float)(1 + i);
		c0_pool_rescale(f0, 2, col, (size_t)nc, NQ, xd, (const float *const *)od);
		c0_pool_rescale_at(f1, 2, col, (size_t)nc, NQ, &pl, xl, (const float *const *)ol);
		bad += memcmp(f0, f1, sizeof(float) * 2 * nc) != 0;
	}
	CHECK_MSG(bad == 0, "%d values differ from the dense oracles", bad);
	/* single depth on the list equals the dense map at its pixels */
	double W[NQ * 4];
	for (int i = 0; i < NQ * 4; i++)
		W[i] = 1 + c0_rng_uniform(&rng);
	const float *xd[NQ] = { x[0], x[1], x[2] }, *xl[NQ] = { xs[0], xs[1], xs[2] };
	c0_depth_single(W, NQ, 4, 100, 20, xd, m, NP, dense[0]);
	c0_depth_single(W, NQ, 4, 100, 20, xl, NULL, M, out[0]);
	for (size_t k = 0; k < M; k++)
		bad += out[0][k] != dense[0][pl.pix[k]];
	CHECK(bad == 0);
	c0_pixlist_free(&pl);
	/* the render in bands of 5 rows (radius 3) against the whole */
	float *whole = malloc(sizeof(float) * NP), *band = malloc(sizeof(float) * NP);
	CHECK(c0_splat(x[0], NY, NX, 0.9, whole) == C0_OK);
	for (int y0 = 0; y0 < NY; y0 += 5) {   /* x from the band's first row within the radius */
		const int t0 = y0 - c0_splat_radius(0.9) < 0 ? 0 : y0 - c0_splat_radius(0.9);
		CHECK(c0_splat_rows(x[0] + t0 * NX, t0, NY, NX, 0.9, y0, y0 + 5 < NY ? y0 + 5 : NY, band + y0 * NX) == C0_OK);
	}
	CHECK(memcmp(whole, band, sizeof(float) * NP) == 0);
	free(whole), free(band);
}

/* The strip along the structure: each pixel's normal from its neighbours'
 * second moments, and the strip's sums, against a brute-force pass over
 * every pair of pixels; on two parallel lines 5 pixels apart (a filament
 * pair 125 nm apart at 25 nm pixels) at any direction the normal is the
 * lines' own and the default strip never reaches the other line, whatever
 * the guide. */
static void test_pool_strip(void)
{
	enum { NY = 40, NX = 40, NP = NY * NX, NQ = 2, R = 3, H = 8 };
	static uint8_t m[NP];
	static float xs[NQ][NP], out[NQ][NP], nrm[2 * NP], gs[NP];
	int bad = 0, crossed = 0;
	for (int a = 0; a < 12; a++) {
		const double t = a * C0_PI / 12, ux = cos(t), uy = sin(t);
		memset(m, 0, sizeof m);
		for (int line = 0; line < 2; line++)
			for (double s = -30; s <= 30; s += 0.25) {
				const int y = (int)lround(20 + s * uy - 2.5 * (2 * line - 1) * ux);
				const int xx = (int)lround(20 + s * ux + 2.5 * (2 * line - 1) * uy);
				if (y >= 0 && y < NY && xx >= 0 && xx < NX)
					m[y * NX + xx] = 1 + line;
			}
		uint8_t mb[NP];
		for (int i = 0; i < NP; i++)
			mb[i] = m[i] != 0;
		struct c0_pixlist pl;
		CHECK(c0_pixlist_from_mask(mb, NY, NX, &pl) == C0_OK);
		for (size_t k = 0; k < pl.M; k++) {
			gs[k] = 0;   /* one depth everywhere: only the strip keeps the lines apart */
			for (int q = 0; q < NQ; q++)
				xs[q][k] = m[pl.pix[k]] == 1 ? (float)(1 + q) : 100.0f;
		}
		c0_pixlist_normals(&pl, R, nrm);
		const float *xl[NQ] = { xs[0], xs[1] };
		float *ol[NQ] = { out[0], out[1] };
		CHECK(c0_pool_guided_at(xl, NQ, &pl, gs, 50, nrm, C0_DEPTH_POOL_WIDTH_PX, H, ol) == C0_OK);
		for (size_t k = 0; k < pl.M; k++) {
			const int y = pl.pix[k] / NX, xx = pl.pix[k] % NX;
			double sxx = 0, syy = 0, sxy = 0, acc[NQ] = { 0 };
			for (size_t o = 0; o < pl.M; o++) {
				const int dy = pl.pix[o] / NX - y, dx = pl.pix[o] % NX - xx;
				if (dx * dx + dy * dy <= R * R)
					sxx += dx * dx, syy += dy * dy, sxy += dx * dy;
			}
			const double al = 0.5 * atan2(2 * sxy, sxx - syy), nx = -sin(al), ny = cos(al);
			bad += fabs(nrm[2 * k] - nx) > 1e-6 || fabs(nrm[2 * k + 1] - ny) > 1e-6;
			for (size_t o = 0; o < pl.M; o++) {
				const int dy = pl.pix[o] / NX - y, dx = pl.pix[o] % NX - xx;
				if (abs(dx) <= H && abs(dy) <= H && fabs(nrm[2 * k] * dx + nrm[2 * k + 1] * dy) <= C0_DEPTH_POOL_WIDTH_PX)
					for (int q = 0; q < NQ; q++)
						acc[q] += xs[q][o];
			}
			for (int q = 0; q < NQ; q++)
				bad += fabs(out[q][k] - acc[q]) > 1e-4 * (1 + acc[q]);
			/* away from the lines' ends: the normal is the lines' (to 15 deg) and line 1 sums itself alone */
			const double along = (xx - 20) * ux + (y - 20) * uy;
			if (m[pl.pix[k]] == 1 && fabs(along) < 12) {
				bad += fabs(nx * uy - ny * ux) < cos(15 * C0_PI / 180);
				crossed += out[0][k] >= 100;
			}
		}
		c0_pixlist_free(&pl);
	}
	CHECK_MSG(bad == 0, "%d normals or strip sums differ from the brute force or the lines' direction", bad);
	CHECK_MSG(crossed == 0, "%d pixels of one line summed the other's", crossed);
}

static void test_depth_error(void)
{
	/* a 2x2 coarse map against a 4x4 truth: nearest upsampling */
	float est[4] = { 100, 0, 50, 200 };
	float truth[16];
	uint8_t mask[16];
	for (int i = 0; i < 16; i++)
		truth[i] = (float)(40 + 10 * i), mask[i] = i % 3 != 0;
	struct c0_depth_err d;
	CHECK(c0_depth_error(est, 2, 2, truth, mask, 4, 4, 0, &d) == C0_OK);
	double a[16];
	int n = 0, nt = 0;
	for (int y = 0; y < 4; y++)
		for (int x = 0; x < 4; x++) {
			int i = y * 4 + x;
			if (!mask[i])
				continue;
			nt++;
			float e = est[(y / 2) * 2 + x / 2];
			if (e > 0)
				a[n++] = fabs(e - truth[i]);
		}
	CHECK(d.pixels == n && d.truth_pixels == nt);
	double s = 0;
	for (int i = 0; i < n; i++)
		s += a[i];
	CHECK_CLOSE(d.mean, s / n, 1e-9);
	int below = 0, above = 0;   /* the median splits the errors in half */
	for (int i = 0; i < n; i++)
		below += a[i] < d.median, above += a[i] > d.median;
	CHECK(below <= n / 2 && above <= n / 2);
	CHECK(c0_depth_error(est, 3, 3, truth, mask, 4, 4, 0, &d) == C0_EINVAL);
}

static void test_depthcode(void)
{
	/* two pixels, one all in the first bin, one all in the last */
	enum { NZ = 5, H = 1, W = 2 };
	float f[NZ * H * W] = { 0 };
	f[0] = 3;                       /* pixel 0, z bin 0 */
	f[(NZ - 1) * W + 1] = 3;        /* pixel 1, last bin */
	uint8_t *rgb;
	int ow, oh;
	CHECK(c0_depthcode(f, NULL, H * W, NZ, H, W, 0, 400, &rgb, &ow, &oh) == C0_OK);
	CHECK(ow > W + 12 && oh >= H);
	CHECK(rgb[0] == 255 && rgb[1] == 0 && rgb[2] == 0);          /* near the glass: red */
	CHECK(rgb[3] == 0 && rgb[4] == 0 && rgb[5] == 255);          /* deep: blue */
	/* the same volume by columns (pixel 1 alone): the same image, pixel 0 black */
	float g[NZ] = { 0 };
	const int one[1] = { 1 };
	g[NZ - 1] = 3;
	uint8_t *rgb2;
	CHECK(c0_depthcode(g, one, 1, NZ, H, W, 0, 400, &rgb2, &ow, &oh) == C0_OK);
	CHECK(rgb2[0] == 0 && rgb2[1] == 0 && rgb2[2] == 0 && memcmp(rgb2 + 3, rgb + 3, (size_t)ow * oh * 3 - 3) == 0);
	free(rgb2);
	/* the bar runs from red at the top to blue at the bottom */
	int bx = W + 8 + 6;
	const uint8_t *top = rgb + ((size_t)2 * ow + bx) * 3, *bot = rgb + ((size_t)(oh - 3 - 10) * ow + bx) * 3;
	CHECK(top[0] == 255 && top[2] == 0 && bot[0] == 0 && bot[2] == 255);
	free(rgb);
}

static const double ANG[5] = { 61.4817, 63.3703, 65.3921, 67.5834, 70 };   /* simulate's default angles */

/* The fit against a brute-force search on a 0.01 nm grid for random
 * non-negative columns, and a single bin read at its centre */
static void test_depth_fit(void)
{
	enum { NQ = 5, NZ = 20, NP = 40 };
	const struct c0_tirf t = C0_TIRF_DEFAULTS;
	const double z0 = 0, dz = 20;
	double W[NQ * NZ], p[NQ], g[NQ];
	CHECK(c0_tirf_weights(&t, NQ, ANG, NULL, NZ, z0, dz, W) == C0_OK);
	for (int q = 0; q < NQ; q++) {
		CHECK(c0_tirf_p(&t, ANG[q], &p[q]) == C0_OK);
		g[q] = c0_tirf_i0(&t, ANG[q]);
	}
	float f[NZ * NP] = { 0 }, depth[NP];
	for (int k = 0; k < NP; k++)
		for (int j = 0; j < NZ; j++)
			f[j * NP + k] = k < NZ ? (j == k) : c0_rng_uniform(&rng) < 0.3 ? (float)c0_rng_uniform(&rng) : 0;
	CHECK(c0_depth_fit(&t, NQ, ANG, NULL, NZ, z0, dz, f, NP, depth) == C0_OK);
	double worst = 0, worst_bin = 0;
	for (int k = 0; k < NP; k++) {
		double y[NQ] = { 0 }, tot = 0, best = -1, zb = 0;
		for (int j = 0; j < NZ; j++) {
			tot += f[j * NP + k];
			for (int q = 0; q < NQ; q++)
				y[q] += W[q * NZ + j] * f[j * NP + k];
		}
		for (double z = z0; z <= z0 + NZ * dz + 1e-9; z += 0.01) {
			double s = 0, n = 0;
			for (int q = 0; q < NQ; q++)
				s += g[q] * exp(-p[q] * z) * y[q], n += g[q] * exp(-p[q] * z) * g[q] * exp(-p[q] * z);
			if (s > 0 && s * s / n > best)
				best = s * s / n, zb = z;
		}
		if (!(tot > 0))
			zb = 0;
		worst = fmax(worst, fabs(depth[k] - zb));
		if (k < NZ)
			worst_bin = fmax(worst_bin, fabs(depth[k] - (z0 + (k + 0.5) * dz)));
	}
	CHECK_MSG(worst < 0.05, "fit vs brute force: %g nm", worst);
	CHECK_MSG(worst_bin < 0.3, "one bin: %g nm from its centre", worst_bin);
}

/* The fit on intensities against a brute-force search on a 0.01 nm grid,
 * with weights; an angle with a large variance and a wrong value is left
 * out by the weighted fit and not by the plain one */
static void test_depth_fit_y(void)
{
	enum { NQ = 5, NP = 30 };
	const struct c0_tirf t = C0_TIRF_DEFAULTS;
	double p[NQ], g[NQ];
	for (int q = 0; q < NQ; q++) {
		CHECK(c0_tirf_p(&t, ANG[q], &p[q]) == C0_OK);
		g[q] = c0_tirf_i0(&t, ANG[q]);
	}
	float yv[NQ][NP], var[NQ * NP], dw[NP], dp[NP];
	const float *y[NQ];
	for (int q = 0; q < NQ; q++)
		y[q] = yv[q];
	for (int k = 0; k < NP; k++)
		for (int q = 0; q < NQ; q++) {
			const double z = 400.0 * k / NP;
			yv[q][k] = (float)(1000 * g[q] * exp(-p[q] * z) * (1 + 0.1 * c0_rng_normal(&rng)));
			var[q * NP + k] = (float)(0.5 + c0_rng_uniform(&rng));
		}
	CHECK(c0_depth_fit_y(&t, NQ, ANG, NULL, 0, 400, y, NP, var, dw) == C0_OK);
	double worst = 0;
	for (int k = 0; k < NP; k++) {
		double best = -1, zb = 0;
		for (double z = 0; z <= 400 + 1e-9; z += 0.01) {
			double s = 0, n = 0;
			for (int q = 0; q < NQ; q++) {
				const double w = g[q] * exp(-p[q] * z);
				s += w * yv[q][k] / var[q * NP + k], n += w * w / var[q * NP + k];
			}
			if (s > 0 && s * s / n > best)
				best = s * s / n, zb = z;
		}
		worst = fmax(worst, fabs(dw[k] - zb));
	}
	CHECK_MSG(worst < 0.05, "weighted fit vs brute force: %g nm", worst);
	/* the first angle (the brightest, at depth 25 times the last) 30 % high, its variance 1e6 times the others' */
	for (int k = 0; k < NP; k++)
		for (int q = 0; q < NQ; q++) {
			const double z = 100 + 200.0 * k / NP;
			yv[q][k] = (float)(1000 * g[q] * exp(-p[q] * z) * (q == 0 ? 1.3 : 1));
			var[q * NP + k] = q == 0 ? 1e6f : 1;
		}
	CHECK(c0_depth_fit_y(&t, NQ, ANG, NULL, 0, 400, y, NP, var, dw) == C0_OK);
	CHECK(c0_depth_fit_y(&t, NQ, ANG, NULL, 0, 400, y, NP, NULL, dp) == C0_OK);
	double ew = 0, ep = 0;
	for (int k = 0; k < NP; k++)
		ew = fmax(ew, fabs(dw[k] - (100 + 200.0 * k / NP))), ep = fmax(ep, fabs(dp[k] - (100 + 200.0 * k / NP)));
	CHECK_MSG(ew < 1 && ep > 10, "one wrong angle: weighted %g nm off, plain %g nm", ew, ep);
}

/* The noise model on pooled intensities with known noise: relative noise of
 * a different share per angle, the draw d independent of y's with the same
 * law. Its sd per angle is found, no systematic part (the residuals are the
 * noise), and the weighted fit reads closer than the plain one. With an
 * absolute misfit in y that d does not hold, the systematic variance finds
 * its size, and the weighted fit stays within a little of the plain one. */
static int cmp_double(const void *a, const void *b);
static double median_err(const float *d, const double *z, int n)
{
	double *e = malloc(sizeof *e * (size_t)n), m;
	for (int k = 0; k < n; k++)
		e[k] = fabs(d[k] - z[k]);
	qsort(e, (size_t)n, sizeof *e, cmp_double);
	m = e[n / 2];
	free(e);
	return m;
}

static void test_depth_noise(void)
{
	enum { NQ = 5, NP = 6000 };
	const struct c0_tirf t = C0_TIRF_DEFAULTS;
	const double sd[NQ] = { 0.02, 0.07, 0.04, 0.03, 0.06 };
	double p[NQ], g[NQ], *z = malloc(sizeof *z * NP);
	float *yv[NQ], *dv[NQ], *var = malloc(sizeof *var * NQ * NP), *dw = malloc(sizeof *dw * NP), *dp = malloc(sizeof *dp * NP);
	for (int q = 0; q < NQ; q++) {
		CHECK(c0_tirf_p(&t, ANG[q], &p[q]) == C0_OK);
		g[q] = c0_tirf_i0(&t, ANG[q]);
		yv[q] = malloc(sizeof *yv[q] * NP), dv[q] = malloc(sizeof *dv[q] * NP);
	}
	for (int pass = 0; pass < 2; pass++) {
		const double sys = pass ? 40 : 0;   /* the misfit's sd, against a signal of about 1000 */
		for (int k = 0; k < NP; k++) {
			z[k] = 20 + 360 * c0_rng_uniform(&rng);
			const double a = 1000 * (0.5 + c0_rng_uniform(&rng));
			for (int q = 0; q < NQ; q++) {
				const double m = a * g[q] * exp(-p[q] * z[k]);
				yv[q][k] = (float)(m * (1 + sd[q] * c0_rng_normal(&rng)) + sys * c0_rng_normal(&rng));
				dv[q][k] = (float)(m * sd[q] * c0_rng_normal(&rng));
			}
		}
		struct c0_depth_noise ns;
		CHECK(c0_depth_noise(&t, NQ, ANG, NULL, 0, 400, (const float *const *)yv, (const float *const *)dv, NP, var, &ns) == C0_OK);
		CHECK(ns.nq == NQ && ns.pixels == NP);
		for (int q = 0; q < NQ; q++)
			CHECK_MSG(fabs(ns.rel_sd[q] / sd[q] - 1) < 0.1, "pass %d angle %d: relative sd %g, true %g", pass, q, ns.rel_sd[q], sd[q]);
		CHECK(c0_depth_fit_y(&t, NQ, ANG, NULL, 0, 400, (const float *const *)yv, NP, var, dw) == C0_OK);
		CHECK(c0_depth_fit_y(&t, NQ, ANG, NULL, 0, 400, (const float *const *)yv, NP, NULL, dp) == C0_OK);
		const double ew = median_err(dw, z, NP), ep = median_err(dp, z, NP);
		double rv = 0;   /* the random variance's mean over pixels and angles */
		for (int k = 0; k < NP; k++)
			for (int q = 0; q < NQ; q++)
				rv += (double)dv[q][k] * dv[q][k] / (NP * NQ);
		printf("noise model, %s: systematic variance %.0f (random %.0f), residuals / noise %.2f; median |error| weighted %.2f nm, plain %.2f nm\n",
		       pass ? "with misfit 1600" : "noise only", ns.sys_var, rv, ns.resid_ratio, ew, ep);
		if (!pass) {
			CHECK_MSG(ns.sys_var < 0.25 * rv && fabs(ns.resid_ratio - 1) < 0.15,
				  "noise only: systematic variance %g (random %g), residuals / noise %g", ns.sys_var, rv, ns.resid_ratio);
			CHECK_MSG(ew < 0.9 * ep, "noise only: weighted %g nm, plain %g nm", ew, ep);
		} else {
			CHECK_MSG(fabs(ns.sys_var / (sys * sys) - 1) < 0.3 && ns.resid_ratio > 1.25,
				  "with misfit: systematic variance %g (true %g), residuals / noise %g", ns.sys_var, sys * sys, ns.resid_ratio);
			CHECK_MSG(ew < 1.05 * ep, "with misfit: weighted %g nm, plain %g nm", ew, ep);
		}
	}
	for (int q = 0; q < NQ; q++)
		free(yv[q]), free(dv[q]);
	free(z), free(var), free(dw), free(dp);
}

static int cmp_double(const void *a, const void *b)
{
	const double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* MA-TIRF with the run's defaults on noise-free intensities of lines whose
 * depth varies along them (continuous depths, not bin centres): the depth
 * map's median signed error is within 1.5 nm of the truth, where the
 * columns' intensity-weighted mean reads about 3 nm deep (the bias of
 * issue 29: the solve stops where spreading mass over depth costs little) */
static void test_depth_noise_free(void)
{
	enum { N = 64, NQ = 5 };
	const struct c0_tirf t = C0_TIRF_DEFAULTS;
	float *img[NQ], *truth = calloc(N * N, sizeof *truth);
	double p[NQ], g[NQ];
	for (int q = 0; q < NQ; q++) {
		img[q] = calloc(N * N, sizeof *img[q]);
		CHECK(c0_tirf_p(&t, ANG[q], &p[q]) == C0_OK);
		g[q] = c0_tirf_i0(&t, ANG[q]);
	}
	for (int l = 0; l < 6; l++)   /* lines across the field, depth 40..330 nm along each */
		for (int i = 4; i < N - 4; i++) {
			const int y = l < 3 ? 8 + 20 * l : i, x = l < 3 ? i : 6 + 20 * (l - 3) + i / 8;
			const double z = 40 + 290 * (double)(i - 4) / (N - 8) * (l % 2 ? 1 : 0.6) + 7.3 * l;
			const double a = 0.3 + 0.7 * c0_rng_uniform(&rng);   /* a few emitters per pixel */
			truth[y * N + x] = (float)z;
			for (int q = 0; q < NQ; q++)
				img[q][y * N + x] = (float)(a * g[q] * exp(-p[q] * z));
		}
	struct c0_run_conf rc;
	c0_run_conf_init(&rc);
	struct c0_matirf_conf c;
	c0_run_conf_matirf(&rc, &c);
	struct c0_matirf_result r;
	CHECK(c0_matirf_solve(&c, NQ, ANG, NULL, (const float *const *)img, N, N, &r) == C0_OK);
	float *f = c0_matirf_dense(&r);   /* the volume on the whole grid (the solve holds its columns) */
	CHECK(f && c0_depth_fit(&t, NQ, ANG, NULL, r.nz, c.z0_nm, c.dz_nm, f, (size_t)N * N, r.depth) == C0_OK);
	double *e = malloc(sizeof *e * N * N), *em = malloc(sizeof *em * N * N), *ea = malloc(sizeof *ea * N * N);
	int n = 0;
	for (int k = 0; k < N * N; k++) {
		if (!(truth[k] > 0))
			continue;
		double s = 0, sz = 0;
		for (int j = 0; j < r.nz; j++)
			s += f[(size_t)j * N * N + k], sz += f[(size_t)j * N * N + k] * r.z_nm[j];
		e[n] = r.depth[k] - truth[k], ea[n] = fabs(e[n]), em[n] = sz / s - truth[k], n++;
	}
	qsort(e, n, sizeof *e, cmp_double), qsort(em, n, sizeof *em, cmp_double), qsort(ea, n, sizeof *ea, cmp_double);
	const double signed_fit = e[n / 2], signed_mean = em[n / 2], abs_fit = ea[n / 2];
	printf("noise-free MA-TIRF, %d pixels: median signed %+.2f nm (columns' mean: %+.2f nm), median |error| %.2f nm\n",
	       n, signed_fit, signed_mean, abs_fit);
	CHECK_MSG(fabs(signed_fit) <= 1.5, "median signed depth error %+.2f nm", signed_fit);
	CHECK_MSG(abs_fit <= 3, "median depth error %.2f nm", abs_fit);
	CHECK_MSG(signed_mean > 2, "the columns' mean no longer reads deep (%+.2f nm): the test lost its point", signed_mean);
	c0_matirf_result_free(&r);
	for (int q = 0; q < NQ; q++)
		free(img[q]);
	free(f), free(truth), free(e), free(em), free(ea);
}

int main(void)
{
	c0_rng_init(&rng, 23, 0);
	RUN(test_pool_window);
	RUN(test_pool_guided);
	RUN(test_pool_sparse);
	RUN(test_pool_strip);
	RUN(test_depth_error);
	RUN(test_depthcode);
	RUN(test_depth_fit);
	RUN(test_depth_fit_y);
	RUN(test_depth_noise);
	RUN(test_depth_noise_free);
	return CHECK_DONE();
}
