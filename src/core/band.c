#include "core/band.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>


int c0_band_alloc(struct c0_band *b, int m, int n, int w)
{
	memset(b, 0, sizeof *b);
	if (m <= 0 || n <= 0 || w <= 0)
		return c0_fail(C0_EINVAL, "band: invalid size %dx%d, width %d", m, n, w);
	if (w > n)
		w = n;
	b->m = m, b->n = n, b->w = w;
	b->start = c0_alloc((size_t)m, sizeof *b->start);
	b->v = c0_alloc((size_t)m * w, sizeof *b->v);
	if (!b->start || !b->v) {
		c0_band_free(b);
		return C0_ENOMEM;
	}
	return C0_OK;
}

void c0_band_free(struct c0_band *b)
{
	free(b->start);
	free(b->v);
	b->start = NULL;
	b->v = NULL;
}

double c0_band_get(const struct c0_band *b, int i, int j)
{
	int k = j - b->start[i];
	return k >= 0 && k < b->w ? b->v[(size_t)i * b->w + k] : 0;
}

int c0_band_transpose(const struct c0_band *b, struct c0_band *t)
{
	/* column j is touched by rows whose band covers it; find the span */
	int *lo = c0_alloc((size_t)b->n, sizeof *lo), *hi = c0_alloc((size_t)b->n, sizeof *hi);
	if (!lo || !hi) {
		free(lo), free(hi);
		return C0_ENOMEM;
	}
	for (int j = 0; j < b->n; j++)
		lo[j] = b->m, hi[j] = -1;
	for (int i = 0; i < b->m; i++)
		for (int k = 0; k < b->w; k++) {
			int j = b->start[i] + k;
			if (b->v[(size_t)i * b->w + k] != 0) {
				lo[j] = i < lo[j] ? i : lo[j];
				hi[j] = i > hi[j] ? i : hi[j];
			}
		}
	int w = 1;
	for (int j = 0; j < b->n; j++)
		if (hi[j] >= lo[j] && hi[j] - lo[j] + 1 > w)
			w = hi[j] - lo[j] + 1;
	int st = c0_band_alloc(t, b->n, b->m, w);
	if (!st) {
		for (int j = 0; j < b->n; j++) {
			int s = hi[j] >= lo[j] ? lo[j] : 0;
			if (s > b->m - t->w)
				s = b->m - t->w;
			t->start[j] = s;
			for (int k = 0; k < t->w; k++)
				t->v[(size_t)j * t->w + k] = c0_band_get(b, s + k, j);
		}
	}
	free(lo), free(hi);
	return st;
}

int c0_band_trim(struct c0_band *b, double tol)
{
	double mx = 0;
	for (size_t i = 0; i < (size_t)b->m * b->w; i++)
		mx = fmax(mx, fabs(b->v[i]));
	int *s0 = c0_alloc((size_t)b->m, sizeof *s0), *s1 = c0_alloc((size_t)b->m, sizeof *s1);
	if (!s0 || !s1) {
		free(s0), free(s1);
		return C0_ENOMEM;
	}
	int w = 1;
	for (int i = 0; i < b->m; i++) {
		const double *r = b->v + (size_t)i * b->w;
		int a = 0, z = b->w - 1;
		while (a < z && fabs(r[a]) <= tol * mx) a++;
		while (z > a && fabs(r[z]) <= tol * mx) z--;
		s0[i] = a, s1[i] = z;
		if (z - a + 1 > w)
			w = z - a + 1;
	}
	struct c0_band t;
	int st = c0_band_alloc(&t, b->m, b->n, w);
	if (!st) {
		for (int i = 0; i < b->m; i++) {
			int s = b->start[i] + s0[i];
			if (s > b->n - w)
				s = b->n - w;
			t.start[i] = s;
			for (int k = 0; k < w; k++) {
				int j = s + k;
				t.v[(size_t)i * w + k] = (j - b->start[i] >= s0[i] && j - b->start[i] <= s1[i]) ? c0_band_get(b, i, j) : 0;
			}
		}
		c0_band_free(b);
		*b = t;
	}
	free(s0), free(s1);
	return st;
}

void c0_band_col_sumsq(const struct c0_band *b, double *out)
{
	for (int j = 0; j < b->n; j++)
		out[j] = 0;
	for (int i = 0; i < b->m; i++)
		for (int k = 0; k < b->w; k++) {
			const double g = b->v[(size_t)i * b->w + k];
			out[b->start[i] + k] += g * g;
		}
}

/* The product along x runs on 8 rows at once, stored interleaved (t[k*8 +
 * j] is entry k of row j): the inner loop has unit stride over the 8 rows
 * and vectorises, where a dot product per row would not without
 * reassociating floating-point sums. (Along y the rows are already
 * contiguous: strip_product below.) */
#define VB 8
C0_HOT static void kernel8(const struct c0_band *b, const double *t, double *o)
{
	const int w = b->w;
	for (int i = 0; i < b->m; i++) {
		double acc[VB] = { 0 };
		const double *r = b->v + (size_t)i * w, *s = t + (size_t)b->start[i] * VB;
		for (int k = 0; k < w; k++)
			for (int j = 0; j < VB; j++)
				acc[j] += r[k] * s[(size_t)k * VB + j];
		for (int j = 0; j < VB; j++)
			o[(size_t)i * VB + j] = acc[j];
	}
}

void c0_band_apply_x(const struct c0_band *b, int ny, const double *in, double *out)
{
	const int m = b->m, n = b->n, nblk = (ny + VB - 1) / VB;
#pragma omp parallel if ((long)ny * m * b->w > 100000)
	{
		double *t = malloc(sizeof *t * (size_t)n * VB), *o = malloc(sizeof *o * (size_t)m * VB);
#pragma omp for schedule(static)
		for (int blk = 0; blk < nblk; blk++) {
			const int y0 = blk * VB, nr = ny - y0 < VB ? ny - y0 : VB;
			for (int k = 0; k < n; k++)
				for (int j = 0; j < VB; j++)
					t[(size_t)k * VB + j] = j < nr ? in[(size_t)(y0 + j) * n + k] : 0;
			kernel8(b, t, o);
			for (int j = 0; j < nr; j++)
				for (int i = 0; i < m; i++)
					out[(size_t)(y0 + j) * m + i] = o[(size_t)i * VB + j];
		}
		free(t), free(o);
	}
}

C0_HOT static void scatter_row(const struct c0_band *b, const double *in, double *out, unsigned char *occ)
{
	const int w = b->w;
	memset(out, 0, sizeof *out * (size_t)b->m);
	if (occ)
		memset(occ, 0, (size_t)C0_BAND_STRIPS(b->m));
	for (int k = 0; k < b->n; k++) {
		if (in[k] == 0)
			continue;
		const double v = in[k], *r = b->v + (size_t)k * w;
		double *o = out + b->start[k];
		for (int u = 0; u < w; u++)
			o[u] += v * r[u];
		for (int s = b->start[k] / C0_BAND_STRIP; occ && s <= (b->start[k] + w - 1) / C0_BAND_STRIP; s++)
			occ[s] = 1;
	}
}

void c0_band_apply_x_sym_sparse_occ(const struct c0_band *b, int ny, const double *in, double *out, unsigned char *occ)
{
	const size_t ns = (size_t)C0_BAND_STRIPS(b->m);
#pragma omp parallel for schedule(static) if ((long)ny * b->m * b->w > 100000)
	for (int y = 0; y < ny; y++)
		scatter_row(b, in + (size_t)y * b->n, out + (size_t)y * b->m, occ ? occ + y * ns : NULL);
}

void c0_band_apply_x_sym_sparse(const struct c0_band *b, int ny, const double *in, double *out)
{
	c0_band_apply_x_sym_sparse_occ(b, ny, in, out, NULL);
}

/* The product along the slow axis on 16 columns from x: each output row
 * combines input rows, the 16 sums held in registers (four independent
 * chains); each column sums over k in order, as the scalar tail does. The
 * columns' strip of the input (all rows) stays in cache for every output
 * row, as apply_x's interleaved blocks do, without copying it. */
_Static_assert(C0_BAND_STRIP == 16, "strip_product sums a strip in four vectors of 4");
C0_HOT static void strip_product(const struct c0_band *b, int nx, int x, const double *in, const int *cnt, const int *rows,
				  double *out)
{
	for (int i = 0; i < b->m; i++) {
		const double *r = b->v + (size_t)i * b->w, *s = in + (size_t)b->start[i] * nx + x;
		double *o = out + (size_t)i * nx + x;
		if (cnt && x + C0_BAND_STRIP <= nx) {
			/* only the occupied rows of the band, in order */
			const int j0 = cnt[b->start[i]], j1 = cnt[b->start[i] + b->w];
			c0_v4 a0 = { 0, 0, 0, 0 }, a1 = a0, a2 = a0, a3 = a0, v0, v1, v2, v3;
			for (int j = j0; j < j1; j++) {
				const int k = rows[j];
				const double *sk = in + (size_t)k * nx + x, rk = r[k - b->start[i]];
				memcpy(&v0, sk, sizeof v0), memcpy(&v1, sk + 4, sizeof v1);
				memcpy(&v2, sk + 8, sizeof v2), memcpy(&v3, sk + 12, sizeof v3);
				a0 += rk * v0, a1 += rk * v1, a2 += rk * v2, a3 += rk * v3;
			}
			memcpy(o, &a0, sizeof a0), memcpy(o + 4, &a1, sizeof a1);
			memcpy(o + 8, &a2, sizeof a2), memcpy(o + 12, &a3, sizeof a3);
			continue;
		}
		if (x + C0_BAND_STRIP <= nx) {
			c0_v4 a0 = { 0, 0, 0, 0 }, a1 = a0, a2 = a0, a3 = a0, v0, v1, v2, v3;
			for (int k = 0; k < b->w; k++) {
				const double *sk = s + (size_t)k * nx;
				memcpy(&v0, sk, sizeof v0), memcpy(&v1, sk + 4, sizeof v1);
				memcpy(&v2, sk + 8, sizeof v2), memcpy(&v3, sk + 12, sizeof v3);
				a0 += r[k] * v0, a1 += r[k] * v1, a2 += r[k] * v2, a3 += r[k] * v3;
			}
			memcpy(o, &a0, sizeof a0), memcpy(o + 4, &a1, sizeof a1);
			memcpy(o + 8, &a2, sizeof a2), memcpy(o + 12, &a3, sizeof a3);
			continue;
		}
		for (int j = 0; j < nx - x; j++) {
			double acc = 0;
			for (int k = 0; k < b->w; k++)
				acc += r[k] * s[(size_t)k * nx + j];
			o[j] = acc;
		}
	}
}

void c0_band_apply_y_occ(const struct c0_band *b, int nx, const double *in, const unsigned char *occ, double *out)
{
	const int ns = C0_BAND_STRIPS(nx);
#pragma omp parallel if ((long)nx * b->m * b->w > 100000)
	{
		/* cnt[k]: occupied rows before row k in this strip */
		int *cnt = occ ? malloc(sizeof *cnt * (2 * (size_t)b->n + 1)) : NULL, *rows = cnt ? cnt + b->n + 1 : NULL;
#pragma omp for schedule(static)
		for (int s = 0; s < ns; s++) {
			if (cnt) {
				cnt[0] = 0;
				for (int k = 0; k < b->n; k++) {
					const int on = occ[(size_t)k * ns + s] != 0;
					rows[cnt[k]] = k;
					cnt[k + 1] = cnt[k] + on;
				}
			}
			/* (no memory for the counts: every strip in full) */
			strip_product(b, nx, s * C0_BAND_STRIP, in, cnt, rows, out);
		}
		free(cnt);
	}
}

void c0_band_apply_y(const struct c0_band *b, int nx, const double *in, double *out)
{
	c0_band_apply_y_occ(b, nx, in, NULL, out);
}

double c0_band_lambda_max(const struct c0_band *b, int iters)
{
	int n = b->n;
	double *v = c0_alloc((size_t)n, sizeof *v), *u = c0_alloc((size_t)n, sizeof *u);
	if (!v || !u) {
		free(v), free(u);
		return NAN;
	}
	for (int i = 0; i < n; i++)
		v[i] = 1 / sqrt(n);
	double lam = 0;
	for (int it = 0; it < iters; it++) {
		c0_band_apply_x(b, 1, v, u);
		double dot = 0, nn = 0;
		for (int i = 0; i < n; i++)
			dot += u[i] * v[i], nn += u[i] * u[i];
		double prev = lam;
		lam = dot;                       /* Rayleigh quotient, v normalised */
		nn = sqrt(nn);
		if (nn == 0)
			break;
		for (int i = 0; i < n; i++)
			v[i] = u[i] / nn;
		if (it > 2 && fabs(lam - prev) <= 1e-15 * lam)
			break;
	}
	free(v), free(u);
	return lam;
}
