/* The common shape of a linear operator, for the tests' adjoint checks
 * (tests/check_adjoint.h; the library's solvers take their own callbacks):
 * sizes, forward, adjoint and the context they run on. Two element types, as the operators have them:
 * double (support, intensity) and float (the MA-TIRF volumes). The adjoint
 * is the adjoint for the Euclidean product unless the operator says
 * otherwise (the banded covariance operator: weight 2 off the diagonal). */
#pragma once
#include <stddef.h>

struct c0_linop {
	size_t nin, nout;
	void *ctx;
	void (*forward)(void *ctx, const double *x, double *y);   /* nin -> nout */
	void (*adjoint)(void *ctx, const double *y, double *x);   /* nout -> nin */
};

struct c0_linopf {
	size_t nin, nout;
	void *ctx;
	void (*forward)(void *ctx, const float *x, float *y);
	void (*adjoint)(void *ctx, const float *y, float *x);
};

/* Adapters for the operators of ops/ and optics/ (defined in testkit/linop.c). */
struct c0_cov;
struct c0_covop;
struct c0_psi_omega;
struct c0_diff3;
struct c0_grad3m;
struct c0_tirfop;
struct c0_blur2;
struct c0_band;

/* The banded covariance operator on the lags of cov (Ly Lx -> nlag Ny Nx). */
struct c0_covop_band { struct c0_covop *op; const struct c0_cov *cov; };
struct c0_linop c0_covop_linop(struct c0_covop_band *b);
/* Psi = G_y (x) G_x: fine image -> coarse image (Ly Lx -> Ny Nx). */
struct c0_linop c0_covop_psi_linop(struct c0_covop *op);
/* Psi restricted to a support (n -> Ny Nx) and the graph gradient (n -> ne). */
struct c0_linop c0_psi_omega_linop(const struct c0_psi_omega *p);
struct c0_linop c0_grad_omega_linop(const struct c0_psi_omega *p);
/* A band matrix (optics/psf.h's factors) applied along x to ny rows. */
struct c0_band_rows { const struct c0_band *b; int ny; };
struct c0_linop c0_band_linop(struct c0_band_rows *b);
/* Volume differences: N -> 3N, N -> 6N, and on mask columns M nz -> nc M nz. */
struct c0_linopf c0_grad3_linop(const struct c0_diff3 *d);
struct c0_linopf c0_hess3_linop(const struct c0_diff3 *d);
struct c0_linopf c0_grad3m_linop(const struct c0_grad3m *g);
/* MA-TIRF weights per column: nz M -> nq M. */
struct c0_linopf c0_tirfop_linop(const struct c0_tirfop *o);
/* The separable blur of one ny x nx image (its own adjoint). */
struct c0_linopf c0_blur2_linop(const struct c0_blur2 *b);
