#include "ops/fshift.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/fftw_plan.h"
#include "core/mem.h"

#include <complex.h>
#include <fftw3.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* fftw_plan_* are not thread-safe; fftw_execute_* on new arrays are. Lines
 * are shifted LB at a time, so the work buffers stay small (1 MB for 2048-
 * pixel lines) whatever the frame, and are kept for the next call: a fresh
 * frame-sized buffer per frame cost a page fault per page, as long as the
 * transforms themselves. */
enum { LB = 32, POOL = 16 };
struct work { double *re; fftw_complex *sp; };
struct c0_fshift {
	int H, W, br, bc;             /* lines per block: rows, columns */
	fftw_plan rf, rb, cf, cb;     /* br rows of 2W; bc columns of 2H */
	struct work pool[POOL];
	int npool;
};

static int plans(int n, int howmany, fftw_plan *f, fftw_plan *b)
{
	double *re = fftw_malloc(sizeof(double) * 2 * n * howmany);
	fftw_complex *sp = fftw_malloc(sizeof(fftw_complex) * (n + 1) * howmany);
	int N = 2 * n;
	if (re && sp) {
		*f = fftw_plan_many_dft_r2c(1, &N, howmany, re, NULL, 1, N, sp, NULL, 1, n + 1, FFTW_ESTIMATE);
		*b = fftw_plan_many_dft_c2r(1, &N, howmany, sp, NULL, 1, n + 1, re, NULL, 1, N, FFTW_ESTIMATE);
	}
	fftw_free(re), fftw_free(sp);
	return *f && *b ? C0_OK : c0_fail(C0_ENOMEM, "drift: cannot plan the FFTs of %d x %d", howmany, N);
}

static void work_free(struct work *w)
{
	fftw_free(w->re), fftw_free(w->sp);
}

void c0_fshift_free(struct c0_fshift *s)
{
	if (!s)
		return;
	for (int i = 0; i < s->npool; i++)
		work_free(&s->pool[i]);
	c0_fftw_destroy(s->rf), c0_fftw_destroy(s->rb), c0_fftw_destroy(s->cf), c0_fftw_destroy(s->cb);
	free(s);
}

int c0_fshift_new(int H, int W, struct c0_fshift **out)
{
	struct c0_fshift *s = c0_alloc(1, sizeof *s);
	*out = NULL;
	if (!s)
		return C0_ENOMEM;
	s->H = H, s->W = W, s->br = H < LB ? H : LB, s->bc = W < LB ? W : LB;
	int st;
#pragma omp critical(c0_fftw_plan)
	{
		st = plans(W, s->br, &s->rf, &s->rb);
		if (!st)
			st = plans(H, s->bc, &s->cf, &s->cb);
	}
	if (st) {
		c0_fshift_free(s);
		return st;
	}
	*out = s;
	return C0_OK;
}

/* sample at i + d: multiply bin j by exp(+2 pi i j d / N); the Nyquist bin
 * of a real signal keeps only its real part */
static void phases(fftw_complex *w, int n, double d)
{
	const int N = 2 * n;
	for (int j = 0; j <= n; j++)
		w[j] = (j == n ? cos(C0_PI * d) : cexp(2 * C0_PI * I * j * d / N)) / N;
}

/* lines k0..k0+nb of howmany lines of n samples (line k at v + k * lstride,
 * sample stride sstride) multiplied by the phases w in one transform (the
 * last block's spare lines are zeros) */
static void shift_block(fftw_plan f, fftw_plan b, int nb, const struct work *wk, const fftw_complex *w, float *v, int n,
			int howmany, long lstride, long sstride, int k0)
{
	const int N = 2 * n;
	double *re = wk->re;
	fftw_complex *sp = wk->sp;
	const int m = howmany - k0 < nb ? howmany - k0 : nb;
	if (m < nb)
		memset(re + (long)m * N, 0, sizeof *re * (size_t)(nb - m) * N);
	/* rows are read along their samples; columns line by line within the
	 * block, so that each row's cache line serves the block's lines */
	if (sstride == 1)
		for (int k = 0; k < m; k++) {
			const float *src = v + (k0 + k) * lstride;
			double *r = re + (long)k * N;
			for (int i = 0; i < n; i++)
				r[i] = src[i], r[N - 1 - i] = src[i];
		}
	else
		for (int i = 0; i < n; i++)
			for (int k = 0; k < m; k++) {
				double x = v[(k0 + k) * lstride + i * sstride];
				re[(long)k * N + i] = x, re[(long)k * N + N - 1 - i] = x;
			}
	fftw_execute_dft_r2c(f, re, sp);
	/* the product written out: C's complex multiply checks for NaNs */
	for (int k = 0; k < m; k++) {
		double *line = (double *)(sp + (long)k * (n + 1));
		const double *ph = (const double *)w;
		for (int j = 0; j <= n; j++) {
			const double a = line[2 * j], b = line[2 * j + 1], c = ph[2 * j], d = ph[2 * j + 1];
			line[2 * j] = a * c - b * d, line[2 * j + 1] = a * d + b * c;
		}
	}
	fftw_execute_dft_c2r(b, sp, re);
	if (sstride == 1)
		for (int k = 0; k < m; k++) {
			float *dst = v + (k0 + k) * lstride;
			const double *r = re + (long)k * N;
			for (int i = 0; i < n; i++)
				dst[i] = (float)r[i];
		}
	else
		for (int i = 0; i < n; i++)
			for (int k = 0; k < m; k++)
				v[(k0 + k) * lstride + i * sstride] = (float)re[(long)k * N + i];
}

static int take(struct c0_fshift *s, struct work *wk)
{
	const int m = s->H > s->W ? s->H : s->W;
	*wk = (struct work){ 0 };
#pragma omp critical(c0_fshift_pool)
	if (s->npool > 0)
		*wk = s->pool[--s->npool];
	if (!wk->re) {
		wk->re = fftw_malloc(sizeof(double) * 2 * (size_t)m * LB);
		wk->sp = fftw_malloc(sizeof(fftw_complex) * (size_t)(m + 1) * LB);
		if (!wk->re || !wk->sp) {
			work_free(wk);
			return C0_ENOMEM;
		}
	}
	return C0_OK;
}

static void give(struct c0_fshift *s, struct work *wk)
{
	int kept = 0;
#pragma omp critical(c0_fshift_pool)
	if (s->npool < POOL)
		s->pool[s->npool++] = *wk, kept = 1;
	if (!kept)
		work_free(wk);
}

/* The blocks of lines are shared among the threads when the caller is not
 * itself one of several (a single stack's drift, frame by frame). */
int c0_fshift_apply(struct c0_fshift *s, float *img, double dx, double dy)
{
	const int H = s->H, W = s->W;
	if (dx == 0 && dy == 0)
		return C0_OK;
	fftw_complex *wr = fftw_malloc(sizeof(fftw_complex) * (size_t)(W + 1));
	fftw_complex *wc = fftw_malloc(sizeof(fftw_complex) * (size_t)(H + 1));
	int fail = wr && wc ? C0_OK : C0_ENOMEM;
	if (!fail)
		phases(wr, W, dx), phases(wc, H, dy);
#pragma omp parallel if (!fail && !omp_in_parallel() && H * W >= 256 * 256)
	{
		struct work wk;
		const int st = take(s, &wk);
		if (st) {
#pragma omp atomic write
			fail = st;
		}
		/* every thread meets both loops; one without buffers leaves its lines */
#pragma omp for schedule(static)
		for (int k0 = 0; k0 < H; k0 += s->br)
			if (!st && dx != 0)
				shift_block(s->rf, s->rb, s->br, &wk, wr, img, W, H, W, 1, k0);
#pragma omp for schedule(static)
		for (int k0 = 0; k0 < W; k0 += s->bc)
			if (!st && dy != 0)
				shift_block(s->cf, s->cb, s->bc, &wk, wc, img, H, W, 1, W, k0);
		if (!st)
			give(s, &wk);
	}
	fftw_free(wr), fftw_free(wc);
	return fail ? c0_mem_fail(0) : C0_OK;
}

/* The line shift's kernel for the fraction f in [0, 1) on lines of n
 * samples (period 2n): out(x) = sum_j in(x + j) k(j) away from the ends,
 * from the phases above (the Nyquist bin's real part included); squared,
 * |j| <= FS_R, and summed to 1 (the truncated tail holds ~1 % at f = 1/2). */
enum { FS_R = 16 };
static void kernel2(int n, double f, double *k2)
{
	const int N = 2 * n;
	double s = 0;
	for (int j = -FS_R; j <= FS_R; j++) {
		double v = 1 + ((j & 1) ? -1 : 1) * cos(C0_PI * f);
		for (int b = 1; b < n; b++)
			v += 2 * cos(2 * C0_PI * b * (f - j) / N);
		v /= N;
		k2[j + FS_R] = v * v, s += v * v;
	}
	for (int j = 0; j <= 2 * FS_R; j++)
		k2[j] /= s;
}

int c0_fshift_variance(int H, int W, const float *var, double dx, double dy, double w, double *out)
{
	const int ix = (int)floor(dx), iy = (int)floor(dy), P = W + 2 * FS_R;
	double kx[2 * FS_R + 1], ky[2 * FS_R + 1];
	kernel2(W, dx - ix, kx), kernel2(H, dy - iy, ky);
	int fail = 0;
#pragma omp parallel if (!omp_in_parallel() && H * W >= 256 * 256)
	{
		double *row = malloc(sizeof *row * (size_t)(P + W)), *t = row + P;   /* a row, and it mirrored beyond its ends */
		if (!row) {
#pragma omp atomic write
			fail = 1;
		}
#pragma omp for schedule(static)
		for (int y = 0; y < H; y++) {
			if (!row)
				continue;
			for (int x = 0; x < W; x++)
				t[x] = 0;
			for (int j = -FS_R; j <= FS_R; j++) {
				const float *v = var + (size_t)c0_mirror(y + iy + j, H) * W;
				for (int x = 0; x < W; x++)
					t[x] += ky[j + FS_R] * v[x];
			}
			for (int i = 0; i < P; i++)
				row[i] = t[c0_mirror(i - FS_R + ix, W)];
			for (int x = 0; x < W; x++) {
				double s = 0;
				for (int j = 0; j <= 2 * FS_R; j++)
					s += kx[j] * row[x + j];
				out[(size_t)y * W + x] += w * s;
			}
		}
		free(row);
	}
	return fail ? c0_mem_fail(0) : C0_OK;
}
