#include "ops/fshift.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/mem.h"

#include <complex.h>
#include <fftw3.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* fftw_plan_* are not thread-safe; fftw_execute_* on new arrays are. Lines
 * are shifted LB at a time, so the work buffers stay small (1 MB for 2048-
 * pixel lines) whatever the frame, and are kept for the next call: a fresh
 * frame-sized buffer per frame cost a page fault per page, as long as the
 * transforms themselves. */
enum { LB = 32, POOL = 16 };
struct work { double *re; fftw_complex *sp, *w; };
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
	fftw_free(w->re), fftw_free(w->sp), fftw_free(w->w);
}

void c0_fshift_free(struct c0_fshift *s)
{
	if (!s)
		return;
	for (int i = 0; i < s->npool; i++)
		work_free(&s->pool[i]);
	if (s->rf) fftw_destroy_plan(s->rf);
	if (s->rb) fftw_destroy_plan(s->rb);
	if (s->cf) fftw_destroy_plan(s->cf);
	if (s->cb) fftw_destroy_plan(s->cb);
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

/* howmany lines of n samples (line k at v + k * lstride, sample stride
 * sstride) shifted by d samples, nb lines per transform (the last block's
 * spare lines are zeros) */
static void shift_lines(fftw_plan f, fftw_plan b, int nb, const struct work *wk, float *v, int n, int howmany,
			long lstride, long sstride, double d)
{
	const int N = 2 * n;
	double *re = wk->re;
	fftw_complex *sp = wk->sp, *w = wk->w;
	/* sample at i + d: multiply bin j by exp(+2 pi i j d / N); the Nyquist
	 * bin of a real signal keeps only its real part */
	for (int j = 0; j <= n; j++)
		w[j] = (j == n ? cos(C0_PI * d) : cexp(2 * C0_PI * I * j * d / N)) / N;
	for (int k0 = 0; k0 < howmany; k0 += nb) {
		const int m = howmany - k0 < nb ? howmany - k0 : nb;
		if (m < nb)
			memset(re + (long)m * N, 0, sizeof *re * (size_t)(nb - m) * N);
		/* line by line within a block: for columns, each row's cache line
		 * serves the block's lines */
		for (int i = 0; i < n; i++)
			for (int k = 0; k < m; k++) {
				double x = v[(k0 + k) * lstride + i * sstride];
				re[(long)k * N + i] = x, re[(long)k * N + N - 1 - i] = x;
			}
		fftw_execute_dft_r2c(f, re, sp);
		for (int k = 0; k < m; k++) {
			fftw_complex *line = sp + (long)k * (n + 1);
			for (int j = 0; j <= n; j++)
				line[j] *= w[j];
		}
		fftw_execute_dft_c2r(b, sp, re);
		for (int i = 0; i < n; i++)
			for (int k = 0; k < m; k++)
				v[(k0 + k) * lstride + i * sstride] = (float)re[(long)k * N + i];
	}
}

int c0_fshift_apply(struct c0_fshift *s, float *img, double dx, double dy)
{
	const int H = s->H, W = s->W, m = H > W ? H : W;
	if (dx == 0 && dy == 0)
		return C0_OK;
	struct work wk = { 0 };
#pragma omp critical(c0_fshift_pool)
	if (s->npool > 0)
		wk = s->pool[--s->npool];
	if (!wk.re) {
		wk.re = fftw_malloc(sizeof(double) * 2 * (size_t)m * LB);
		wk.sp = fftw_malloc(sizeof(fftw_complex) * (size_t)(m + 1) * LB);
		wk.w = fftw_malloc(sizeof(fftw_complex) * (size_t)(m + 1));
		if (!wk.re || !wk.sp || !wk.w) {
			work_free(&wk);
			return c0_fail(C0_ENOMEM, "drift: out of memory for a %dx%d frame", W, H);
		}
	}
	if (dx != 0)
		shift_lines(s->rf, s->rb, s->br, &wk, img, W, H, W, 1, dx);
	if (dy != 0)
		shift_lines(s->cf, s->cb, s->bc, &wk, img, H, W, 1, W, dy);
	int kept = 0;
#pragma omp critical(c0_fshift_pool)
	if (s->npool < POOL)
		s->pool[s->npool++] = wk, kept = 1;
	if (!kept)
		work_free(&wk);
	return C0_OK;
}
