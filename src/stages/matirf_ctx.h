/* The MA-TIRF solve's insides, shared by its files (not installed): the
 * problem as the PDHG callbacks see it (struct matirf_ctx), the per-entry
 * proximal maps and the callbacks themselves.
 *   matirf.c         the entry point, its checks, one level's setup and unpacking
 *   matirf_steps.c   K, K^T, the diag solver's steps, their fused forms, the background
 *   matirf_exact.c   the exact and apg solvers' per-pixel data steps and their setup
 *   matirf_coarse.c  the warm start from 2x2-binned images */
#pragma once
#include "stages/matirf.h"
#include "ops/blur2.h"
#include "ops/diff3.h"
#include "ops/grad3m.h"
#include "solve/nnqp.h"

#include <math.h>
#include <stddef.h>

#define MAXQ 64

struct matirf_ctx {
	int nq, nz, M;            /* columns: the lateral pixels solved for */
	int ncomp;                /* components of the regulariser's operator */
	size_t N;                 /* M * nz voxels */
	const double *W;          /* nq x nz, column-normalised */
	const float *b;           /* nq x M, scaled data */
	const float *tau;         /* N primal steps */
	double sig_d[MAXQ], sig_r[6];  /* dual steps: per angle, per regulariser component */
	enum c0_reg reg;
	struct c0_grad3m g;       /* TV: gradient over the columns */
	struct c0_diff3 d;        /* Hessian: full grid (M = all pixels) */
	double kappa, l1;
	/* the exact solver (C0_MATIRF_EXACT): K = R's operator, one primal step
	 * tau1, H = W^T W + I / tau1 and c = W^T b - l1 per voxel */
	int exact;
	/* joint deconvolution: the data rows are B W u, B a Gaussian blur of
	 * each angle's image (full grid); work: nq M floats */
	struct c0_blur2 blur;
	float *dwork;
	/* the exact and apg solvers with a blur: W^T W majorises W^T B^2 W
	 * (||B|| <= 1), so their per-pixel step stays, its gradient corrected by
	 * corr = W^T (I - B^2) W x (N floats, the exact solver only: apg applies W^T
	 * to (I - B^2) W x, left in dwork, chunk by chunk; work: dwork2, nq M floats) */
	float *corr, *dwork2;
	/* background estimation: b = b0 - bg, bg updated from the residual every
	 * BG_EVERY iterations; u is the solver's primal iterate */
	const float *b0, *u;
	float *bg, *b_mut;
	double *bgd, *bgr;
	double bg_smooth;
	int ny, nx;
	double tau1, hcol, H[C0_NNQP_MAX * C0_NNQP_MAX], Hi[C0_NNQP_MAX * C0_NNQP_MAX];
	float *c;
	/* the apg solver: the same prox by APG_ITS accelerated projected
	 * gradient steps (step 1/L, momentum beta from L and mu = 1/tau1) */
	int apg;
	float Hf[C0_NNQP_MAX * C0_NNQP_MAX], apg_step, apg_beta;
	struct c0_progress *pr;
};

/* The proximal maps per entry, shared by the plain and the fused steps.
 * Primal, G = l1 sum u + indicator(u >= 0): from x and (K^T y)_i = a. */
static inline void prox_g_entry(float *x, float *t, float tau, float a, float l1, float rho, float *d2, float *n2)
{
	float v = *x - tau * (a + l1);
	c0_pdhg_primal_entry(x, t, 0.5f * (v + fabsf(v)), rho, d2, n2);   /* max(v, 0) without a branch */
}

/* Dual of a data row, F = 1/2 (. - b)^2: from y and (K xbar)_i = s. */
static inline void prox_data_entry(float *y, float s, float b, float sg, float rho, float *d2, float *n2)
{
	c0_pdhg_dual_entry(y, (*y + sg * (s - b)) / (1 + sg), rho, d2, n2);
}

/* Dual of lateral TV (k > 0): (a, b) = y + sigma K xbar, projected on the
 * radius-k disc. */
static inline void prox_tv2_entry(float *yx, float *yy, float a, float b, float k, float rho, float *d2, float *n2)
{
	float r = sqrtf(a * a + b * b), f = k / (r > k ? r : k);
	c0_pdhg_dual_entry(yx, f * a, rho, d2, n2);
	c0_pdhg_dual_entry(yy, f * b, rho, d2, n2);
}

/* PDHG's callbacks (struct c0_pdhg_problem), vc a struct matirf_ctx */
void matirf_K(void *vc, const float *u, float *y);
void matirf_KT(void *vc, const float *y, float *u);
void matirf_iter(void *vc, int it);
void matirf_primal_step(void *vc, float *x, float *t, float rho, double sums[2]);
void matirf_dual_step(void *vc, float *y, const float *s, float rho, double sums[2]);
void matirf_dual_step_exact(void *vc, float *y, const float *s, float rho, double sums[2]);
void matirf_primal_fused(void *vc, const float *y, float *x, float *t, float rho, double sums[2]);
void matirf_dual_fused(void *vc, const float *t, float *y, float rho, double sums[2]);
void matirf_primal_step_exact(void *vc, float *x, float *t, float rho, double sums[2]);
void matirf_primal_step_apg(void *vc, float *x, float *t, float rho, double sums[2]);
void matirf_primal_fused_apg(void *vc, const float *y, float *x, float *t, float rho, double sums[2]);

/* the background of the iterate c->u given the weights W (then the data the
 * solver sees, b = b0 - bg) */
void matirf_background_update(struct matirf_ctx *c, const double *W);
/* the exact and apg solvers' steps, H, its inverse and c (matirf_exact.c) */
void matirf_exact_setup(struct matirf_ctx *x, const struct c0_matirf_conf *c, const double *W);
/* their per-voxel c = W^T B b - l1 from the current data b */
void matirf_exact_rhs(struct matirf_ctx *x);

/* columns: M raster indices, increasing */
struct matirf_cols { const int *pixel; size_t M; };
/* The warm start from 2x2-binned images (matirf_coarse.c): x binned into
 * a buffer of nq ((ny + 1) / 2) ((nx + 1) / 2) floats (returned, NULL when
 * out of memory; xc[q]: its images) and c for that grid (cc); then the
 * coarse level's result r and TV dual yc (or NULL) brought back at the
 * columns (nothing on the whole grid times the depth bins): u0 (nz M, u
 * units) and y0 (the TV dual, 2 nz M). */
float *matirf_coarse_bin(const struct c0_matirf_conf *c, int nq, const float *const *x, int ny, int nx,
			 const float *xc[], struct c0_matirf_conf *cc);
void matirf_coarse_lift(const struct c0_matirf_result *r, const float *yc, int ny, int nx, int nz, double mx,
			const double *col, const struct matirf_cols *cols, float *u0, float *y0);
