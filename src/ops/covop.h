/* The covariance-domain forward model of COL0RME in separable form.
 *
 * Coarse image N_y x N_x, fine image L = r N per axis, Psi = G_y (x) G_x
 * (optics/psf.h). A maps a fine image x to the model covariance
 * Psi diag(x) Psi^T; restricted to the lag band of a c0_cov it is
 *   M_l(i, j) = sum_ab x_ab Ky_dy(i, a) Kx_dx(j, b),  K_d(i, a) = G(i, a) G(i + d, a)
 * with the Frobenius product over the full band (weight 2 off the diagonal).
 * Over all pixel pairs, A^T A = H_y (x) H_x with H = (G^T G) o (G^T G). */
#pragma once
#include "core/band.h"
#include "ops/covariance.h"

struct c0_covop {
	int Ny, Nx, r, Ly, Lx, d;
	struct c0_band Gy, Gx, GyT, GxT, Hy, Hx;
	struct c0_band *Ky, *Kx, *KyT, *KxT;   /* index d + lag, lags -d..d */
	double *n;       /* column norms ||psi_ab||^2 = ||a_ab||, Ly x Lx */
	double lip;      /* lambda_max(A^T A) = lambda_max(H_y) lambda_max(H_x) */
	double *tmp, *tmp2;  /* Ly x Lx workspaces */
	unsigned char *occ;  /* Ly x C0_BAND_STRIPS(Lx): tmp's occupancy (core/band.h) */
};

/* H's bands drop the entries below C0_COVOP_TRIM of their largest (91 -> 43
 * entries a row at 229 nm / 25 nm; 49 at 1e-8): A^T A x then differs from
 * the exact product by ~2e-7 of its largest value (tests/test_support.c),
 * far below the noise of the correlation images (sigma_C >= 2e-4 lambda_max
 * measured), and the solve takes 13 % less time than at 1e-8. */
#define C0_COVOP_TRIM 1e-6

int c0_covop_init(struct c0_covop *op, int Ny, int Nx, int r, double sigma_px, int d);
void c0_covop_free(struct c0_covop *op);
/* Banded forward: x (Ly x Lx) -> m (nlag x Ny x Nx) on the lags of cov. */
void c0_covop_forward(struct c0_covop *op, const struct c0_cov *cov, const double *x, double *m);
/* Its adjoint for the band's Frobenius product: R (nlag x Ny x Nx) -> c (Ly x Lx). */
void c0_covop_adjoint(struct c0_covop *op, const struct c0_cov *cov, const double *R, double *c);
/* c0_covop_adjoint's values at the fine pixels where on (Ly x Lx), bit for
 * bit, 0 elsewhere: for a fit on a known support, a few thousand pixels of
 * the grid's millions. */
void c0_covop_adjoint_on(const struct c0_covop *op, const struct c0_cov *cov, const double *R, const uint8_t *on, double *c);
/* A^T A x over all pixel pairs. */
void c0_covop_normal(struct c0_covop *op, const double *x, double *out);
