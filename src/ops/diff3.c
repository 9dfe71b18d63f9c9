#include "ops/diff3.h"
#include "core/mem.h"

#include <math.h>
#include <string.h>

/* strides and lengths of the three axes: 0 = x, 1 = y, 2 = z */
static void axis(const struct c0_diff3 *d, int a, size_t *stride, int *len)
{
	*stride = a == 0 ? 1 : a == 1 ? (size_t)d->nx : (size_t)d->nx * d->ny;
	*len = a == 0 ? d->nx : a == 1 ? d->ny : d->nz;
}

/* out = D_a in (forward difference, zero at the last index) */
static void dfwd(const struct c0_diff3 *d, int a, const float *in, float *out)
{
	size_t s;
	int n;
	axis(d, a, &s, &n);
	const size_t N = (size_t)d->nx * d->ny * d->nz, block = s * n;
	/* the volume is a sequence of blocks of n slabs of s contiguous values */
	for (size_t b0 = 0; b0 < N; b0 += block)
		for (int k = 0; k < n; k++) {
			const float *p = in + b0 + k * s;
			float *o = out + b0 + k * s;
			if (k < n - 1)
				for (size_t i = 0; i < s; i++)
					o[i] = p[i + s] - p[i];
			else
				memset(o, 0, s * sizeof *o);
		}
}

/* out = D_a^T in */
static void dadj(const struct c0_diff3 *d, int a, const float *in, float *out)
{
	size_t s;
	int n;
	axis(d, a, &s, &n);
	const size_t N = (size_t)d->nx * d->ny * d->nz, block = s * n;
	for (size_t b0 = 0; b0 < N; b0 += block)
		for (int k = 0; k < n; k++) {
			const float *p = in + b0 + k * s;
			float *o = out + b0 + k * s;
			/* (p - s)[i], not p[i - s]: i - s would wrap as an unsigned offset */
			for (size_t i = 0; i < s; i++)
				o[i] = (k < n - 1 ? -p[i] : 0) + (k > 0 ? (p - s)[i] : 0);
		}
}

static double w(const struct c0_diff3 *d, int a) { return a == 2 ? d->wz : d->wl; }

void c0_grad3(const struct c0_diff3 *d, const float *v, float *g)
{
	size_t N = (size_t)d->nx * d->ny * d->nz;
	for (int a = 0; a < 3; a++) {
		dfwd(d, a, v, g + a * N);
		for (size_t i = 0; i < N; i++)
			g[a * N + i] *= (float)w(d, a);
	}
}

void c0_grad3_adjoint(const struct c0_diff3 *d, const float *g, float *v)
{
	size_t N = (size_t)d->nx * d->ny * d->nz;
	float *t = d->work;
	memset(v, 0, N * sizeof *v);
	for (int a = 0; a < 3; a++) {
		dadj(d, a, g + a * N, t);
		for (size_t i = 0; i < N; i++)
			v[i] += (float)w(d, a) * t[i];
	}
}

/* components: xx, yy, zz, xy, xz, yz */
static const int HA[6] = { 0, 1, 2, 0, 0, 1 }, HB[6] = { 0, 1, 2, 1, 2, 2 };

void c0_hess3(const struct c0_diff3 *d, const float *v, float *h)
{
	size_t N = (size_t)d->nx * d->ny * d->nz;
	float *t = d->work;
	for (int c = 0; c < 6; c++) {
		double sc = w(d, HA[c]) * w(d, HB[c]);
		if (c < 3) {               /* -D^T D */
			dfwd(d, HA[c], v, t);
			dadj(d, HA[c], t, h + c * N);
			sc = -sc;
		} else {                   /* D_b D_a */
			dfwd(d, HA[c], v, t);
			dfwd(d, HB[c], t, h + c * N);
			sc *= sqrt(2.0);
		}
		for (size_t i = 0; i < N; i++)
			h[c * N + i] *= (float)sc;
	}
}

void c0_hess3_adjoint(const struct c0_diff3 *d, const float *h, float *v)
{
	size_t N = (size_t)d->nx * d->ny * d->nz;
	float *t = d->work, *u = d->work + N;
	memset(v, 0, N * sizeof *v);
	for (int c = 0; c < 6; c++) {
		double sc = w(d, HA[c]) * w(d, HB[c]);
		if (c < 3) {               /* (-D^T D)^T = -D^T D */
			dfwd(d, HA[c], h + c * N, t);
			dadj(d, HA[c], t, u);
			sc = -sc;
		} else {                   /* (D_b D_a)^T = D_a^T D_b^T */
			dadj(d, HB[c], h + c * N, t);
			dadj(d, HA[c], t, u);
			sc *= sqrt(2.0);
		}
		for (size_t i = 0; i < N; i++)
			v[i] += (float)sc * u[i];
	}
}
