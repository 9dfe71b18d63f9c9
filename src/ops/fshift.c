#include "ops/fshift.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/mem.h"

#include <complex.h>
#include <fftw3.h>
#include <math.h>
#include <stdlib.h>

/* fftw_plan_* are not thread-safe; fftw_execute_* on new arrays are */
struct c0_fshift {
	int H, W;
	fftw_plan rf, rb, cf, cb;     /* H rows of 2W; W columns of 2H */
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

void c0_fshift_free(struct c0_fshift *s)
{
	if (!s)
		return;
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
	s->H = H, s->W = W;
	int st;
#pragma omp critical(c0_fftw_plan)
	{
		st = plans(W, H, &s->rf, &s->rb);
		if (!st)
			st = plans(H, W, &s->cf, &s->cb);
	}
	if (st) {
		c0_fshift_free(s);
		return st;
	}
	*out = s;
	return C0_OK;
}

/* howmany lines of n samples (line k at v + k * lstride, sample stride
 * sstride) shifted by d samples */
static void shift_lines(fftw_plan f, fftw_plan b, double *re, fftw_complex *sp, float *v, int n, int howmany,
			long lstride, long sstride, double d)
{
	const int N = 2 * n;
	for (int k = 0; k < howmany; k++)
		for (int i = 0; i < n; i++) {
			double x = v[k * lstride + i * sstride];
			re[(long)k * N + i] = x, re[(long)k * N + N - 1 - i] = x;
		}
	fftw_execute_dft_r2c(f, re, sp);
	for (int j = 0; j <= n; j++) {
		/* sample at i + d: multiply bin j by exp(+2 pi i j d / N); the
		 * Nyquist bin of a real signal keeps only its real part */
		double complex w = j == n ? cos(C0_PI * d) : cexp(2 * C0_PI * I * j * d / N);
		w /= N;
		for (int k = 0; k < howmany; k++)
			sp[(long)k * (n + 1) + j] *= w;
	}
	fftw_execute_dft_c2r(b, sp, re);
	for (int k = 0; k < howmany; k++)
		for (int i = 0; i < n; i++)
			v[k * lstride + i * sstride] = (float)re[(long)k * N + i];
}

int c0_fshift_apply(const struct c0_fshift *s, float *img, double dx, double dy)
{
	const int H = s->H, W = s->W, m = H > W ? H : W;
	double *re = fftw_malloc(sizeof(double) * 2 * (size_t)m * m);
	fftw_complex *sp = fftw_malloc(sizeof(fftw_complex) * (size_t)(m + 1) * m);
	if (!re || !sp) {
		fftw_free(re), fftw_free(sp);
		return c0_fail(C0_ENOMEM, "drift: out of memory for a %dx%d frame", W, H);
	}
	if (dx != 0)
		shift_lines(s->rf, s->rb, re, sp, img, W, H, W, 1, dx);
	if (dy != 0)
		shift_lines(s->cf, s->cb, re, sp, img, H, W, 1, W, dy);
	fftw_free(re), fftw_free(sp);
	return C0_OK;
}
