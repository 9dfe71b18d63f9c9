/* The one adjoint test for every operator: <A x, y>_w = <x, A^T y> for
 * random x and y (seeded), w the weights of the output's inner product
 * (NULL: Euclidean). Relative to ||A x|| ||y||, so that cancellation in the
 * inner products cannot hide an error nor fail a correct operator. */
#pragma once
#include "check.h"
#include "core/rng.h"
#include "testkit/linop.h"

#include <stdlib.h>

static inline double adjoint_gap(const struct c0_linop *A, const double *w, uint64_t seed)
{
	struct c0_rng r;
	c0_rng_init(&r, seed, 0);
	double *x = malloc(sizeof *x * (A->nin + 1)), *xa = malloc(sizeof *x * (A->nin + 1));
	double *y = malloc(sizeof *y * (A->nout + 1)), *ax = malloc(sizeof *y * (A->nout + 1));
	for (size_t i = 0; i < A->nin; i++)
		x[i] = c0_rng_normal(&r);
	for (size_t i = 0; i < A->nout; i++)
		y[i] = c0_rng_normal(&r);
	A->forward(A->ctx, x, ax);
	A->adjoint(A->ctx, y, xa);
	double l = 0, rr = 0, nax = 0, ny = 0, nx = 0, nxa = 0;
	for (size_t i = 0; i < A->nout; i++) {
		const double wi = w ? w[i] : 1;
		l += wi * ax[i] * y[i], nax += wi * ax[i] * ax[i], ny += wi * y[i] * y[i];
	}
	for (size_t i = 0; i < A->nin; i++)
		rr += x[i] * xa[i], nx += x[i] * x[i], nxa += xa[i] * xa[i];
	const double s = fmax(sqrt(nax * ny), sqrt(nx * nxa));
	free(x), free(xa), free(y), free(ax);
	return s > 0 ? fabs(l - rr) / s : 0;
}

static inline double adjoint_gapf(const struct c0_linopf *A, uint64_t seed)
{
	struct c0_rng r;
	c0_rng_init(&r, seed, 0);
	float *x = malloc(sizeof *x * (A->nin + 1)), *xa = malloc(sizeof *x * (A->nin + 1));
	float *y = malloc(sizeof *y * (A->nout + 1)), *ax = malloc(sizeof *y * (A->nout + 1));
	for (size_t i = 0; i < A->nin; i++)
		x[i] = (float)c0_rng_normal(&r);
	for (size_t i = 0; i < A->nout; i++)
		y[i] = (float)c0_rng_normal(&r);
	A->forward(A->ctx, x, ax);
	A->adjoint(A->ctx, y, xa);
	double l = 0, rr = 0, nax = 0, ny = 0, nx = 0, nxa = 0;
	for (size_t i = 0; i < A->nout; i++)
		l += (double)ax[i] * y[i], nax += (double)ax[i] * ax[i], ny += (double)y[i] * y[i];
	for (size_t i = 0; i < A->nin; i++)
		rr += (double)x[i] * xa[i], nx += (double)x[i] * x[i], nxa += (double)xa[i] * xa[i];
	const double s = fmax(sqrt(nax * ny), sqrt(nx * nxa));
	free(x), free(xa), free(y), free(ax);
	return s > 0 ? fabs(l - rr) / s : 0;
}

/* tol: 1e-12 for double operators, 1e-5 for float ones */
#define CHECK_ADJOINT(A, w, tol) do { double g_ = adjoint_gap((A), (w), __LINE__); \
	CHECK_MSG(g_ <= (tol), "adjoint of %s: relative gap %.3g", #A, g_); } while (0)
#define CHECK_ADJOINTF(A, tol) do { double g_ = adjoint_gapf((A), __LINE__); \
	CHECK_MSG(g_ <= (tol), "adjoint of %s: relative gap %.3g", #A, g_); } while (0)
