/* Psi restricted to a support: intensities x on the n fine pixels of a mask
 * Omega map to the coarse image sum_a x_a gy_a (x) gx_a, where gy_a, gx_a are
 * the columns of the separable PSF factors (optics/psf.h). Stored as the
 * columns themselves, so it costs n (PSF width)^2, whatever the field size.
 * Also the graph gradient on Omega: one difference per pair of pixels of
 * Omega at most radius fine pixels apart (1: 4-neighbours), divided by
 * their distance. */
#pragma once
#include "core/band.h"

#include <stdint.h>

struct c0_psi_omega {
	int Ny, Nx, Ly, Lx, n;
	int *idx;                   /* n fine indices (row-major) */
	struct c0_band GyT, GxT;    /* L x N: row a is column a of G */
	int ne, *e0, *e1;           /* graph edges as positions in 0..n-1 */
	double *ew;                 /* edge weights: 1 / distance */
	/* the adjoint's row sums kept per fine column (one workspace per
	 * thread that may run it): ring rows of each column, a power of 2 >=
	 * GyT.w; nws x Lx x ring sums and nws x Lx marks */
	int ring, nws;
	double *ws_t;
	int *ws_hi;
};

int c0_psi_omega_init(struct c0_psi_omega *p, int Ny, int Nx, int r, double sigma_px, const uint8_t *mask, double radius);
/* With dir (NULL: as c0_psi_omega_init), a unit vector (x, y) at dir[2k],
 * dir[2k + 1] for each mask pixel k in raster order: each edge's weight is
 * multiplied by (1 - c^2)^(power / 2), c^2 the mean over its two ends of the
 * squared cosine between the edge and the end's dir, and an edge whose factor
 * is below C0_ORIENT_DROP is left out. With each pixel's normal to the
 * structure it lies on, a difference along the structure keeps its weight and
 * one across it fades. */
#define C0_ORIENT_DROP 1e-3   /* most of a long radius's edges: they would only cost time */
int c0_psi_omega_init_dir(struct c0_psi_omega *p, int Ny, int Nx, int r, double sigma_px, const uint8_t *mask, double radius,
			  const float *dir, double power);
void c0_psi_omega_free(struct c0_psi_omega *p);
void c0_psi_omega_forward(const struct c0_psi_omega *p, const double *x, double *y);  /* n -> Ny*Nx */
void c0_psi_omega_adjoint(const struct c0_psi_omega *p, const double *y, double *x);  /* Ny*Nx -> n */
void c0_grad_omega(const struct c0_psi_omega *p, const double *x, double *g);         /* n -> ne */
void c0_grad_omega_adjoint(const struct c0_psi_omega *p, const double *g, double *x); /* ne -> n */
/* Fine raster index of unknown k. */
static inline int c0_psi_omega_pixel(const struct c0_psi_omega *p, int k) { return p->idx[k]; }
/* The diagonals of Psi_Omega^T Psi_Omega (||psi_k||^2) and of D^T D for the
 * graph gradient D (sum of squared edge weights at each node), n each, for
 * diagonal preconditioners. */
void c0_psi_omega_diag(const struct c0_psi_omega *p, double *psi2);
void c0_grad_omega_diag(const struct c0_psi_omega *p, double *deg);
/* lambda_max(Psi^T Psi) of the full operator, an upper bound for Psi_Omega */
double c0_psi_norm2(const struct c0_psi_omega *p);
