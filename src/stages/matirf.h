/* MA-TIRF axial reconstruction (Soubies et al.): from per-angle images x_q,
 *   min_{f >= 0}  sum_q 1/2 ||W_q f - x_q||^2 + kappa R(f) + s sum f
 * with W_q f = sum_j W[q][j] f_j per lateral pixel (optics/tirf.h) and
 * R = isotropic TV (lateral weight 1, axial weight wz) or the Schatten-1
 * (nuclear) norm of the Hessian. The l1 term s sum f (f >= 0) favours few
 * depths per pixel: without it TV spreads each emitter over depth and the
 * mean depth drifts towards the middle of the range (docs/defaults.md#sparsity).
 * As in the reference: the images are scaled
 * by one global maximum (never per angle), W's columns are normalised and the
 * solver works on u = c f. */
#pragma once
#include "optics/tirf.h"
#include "solve/pdhg.h"

#include "col0rme.h"   /* enum c0_reg */

/* enum c0_matirf_solver (col0rme.h): exact, PDHG whose primal step solves
 * the data + l1 + positivity prox exactly per pixel (a small NNQP); diag,
 * the data rows in the dual with diagonal steps (the earlier solver); apg,
 * exact's PDHG with that prox by a few accelerated projected gradient steps
 * vectorised across pixels */

struct c0_matirf_conf {
	struct c0_tirf tirf;
	double z0_nm, z1_nm, dz_nm;  /* 0, 400, 20: depth bins [z0, z1) */
	enum c0_reg reg;             /* tv */
	double kappa;                /* 3e-2: weight of R, for data scaled to max 1 */
	double wz;                   /* 0: axial weight of R relative to lateral (0: lateral TV) */
	double sparsity;             /* 3e-2: weight s of the l1 term, same scale */
	struct c0_pdhg_conf pdhg;    /* 3000 iterations; tol 0: the solver's (1e-3 exact, 1e-4 diag, apg 5e-4 TV 1e-3 Hessian); relax 1.8 */
	int fused;                   /* 1: TV's steps in one pass each; 0: the operator sequence (tests) */
	enum c0_matirf_solver solver;/* diag (exact, diag or apg; the run conf's auto is resolved before) */
	double gamma;                /* 3: exact solver's primal step relative to the diagonal one */
	/* 0: the images are background-free; > 0: estimate a smooth background
	 * common to all angles jointly with f, as (I + bg_smooth grad^T grad)^-1
	 * of the mean residual, clipped at 0 (bg_smooth in px^2) */
	double bg_smooth;
	/* 0: no deconvolution; > 0: the forward model blurs each angle's image
	 * by a Gaussian of this sigma (camera pixels), in every solver (exact
	 * and apg: their per-pixel step majorises the blurred data term) */
	double psf_sigma_px;
	/* levels of the warm start from 2x2-binned images and PSF (apg and exact with TV) */
	int coarse;
	/* 1: TV solves on every pixel, like the Hessian (tests: the oracle of
	 * the default, which solves only on the pixels with data) */
	int full_grid;
	/* TV: the pixels with data and those within this many steps (4-neighbour)
	 * of them. 0 (the default): TV has free borders at the data's edge; 1:
	 * the jump to the zeros around counts, as on the whole grid (within 1.6 %
	 * of its volume, depths 1.8 nm, on the phantom: tests/test_matirf.c), in memory that
	 * still follows the support */
	int halo;
	/* 0: the coarse levels of the warm start stop at the solve's own
	 * tolerance; > 0: at this one. The early-stopped answer stays near the
	 * start, so a tighter start brings it nearer the converged one (the
	 * blurred unit-test object: 3.5 -> 1.5 nm median depth at 1e-4, for
	 * coarse levels of 1/4 and 1/16 the pixels; docs/speed.md) */
	double coarse_tol;
};
/* kappa where the run conf deconvolves (psf_fwhm_nm > 0) and gives none:
 * measured with the blur modelled, 1e-3 halves the depth error of 3e-2 and
 * doubles the sum-over-depth image's fine detail, short of the truth's
 * (3e-4 overshoots it: noise) (docs/defaults.md#kappa) */
#define C0_MATIRF_KAPPA_DECONV 1e-3
#define C0_MATIRF_DEFAULTS { C0_TIRF_DEFAULTS, 0, 400, 20, C0_REG_TV, 3e-2, 0, 3e-2, { 3000, 0, 1.8 }, 1, C0_MATIRF_DIAG, 3, 0, 0, 0, 0, 0, 0 }

/* The volume is held by columns: the M lateral pixels solved for (with
 * TV, those with data in some image; 0.1 % of a whole camera frame's fine
 * grid, say), the rest being 0, so that no array is depth bins x the
 * whole grid. */
struct c0_matirf_result {
	int nz, ny, nx;
	int M;                       /* columns */
	int *pixel;                  /* M raster indices (y nx + x), increasing */
	float *f;                    /* nz x M: bin j of column k at f[j M + k], in the images' units per bin */
	double *z_nm;                /* bin centres */
	float *depth;                /* ny x nx intensity-weighted mean depth (nm), 0 where empty */
	float *total;                /* ny x nx sum over depth */
	int iters, converged, exact, apg;   /* exact, apg: which solver ran */
	int coarse_iters;            /* iterations of the coarse levels (their pixels are 1/4, 1/16.. of these) */
	double seconds, scale;
	double rel_change;           /* the last iteration's relative change (max of primal, dual) */
	double objective;            /* at the result, data scaled to max 1 (compares solvers) */
	float *background;           /* ny x nx estimated background (image units), or NULL */
	double background_mean;
};

int c0_matirf_check(const struct c0_matirf_conf *c, int nq, const double *angles);
/* The number of depth bins [z0, z1) of width dz. */
int c0_matirf_nz(const struct c0_matirf_conf *c);
/* x: nq images of ny x nx; gain: nq per-angle gains or NULL. */
int c0_matirf_solve(const struct c0_matirf_conf *c, int nq, const double *angles, const double *gain,
		    const float *const *x, int ny, int nx, struct c0_matirf_result *res);
/* x_q -= v for every image (a camera offset or a constant background),
 * refused when v is not below the mean of some image; what names the option. */
int c0_matirf_subtract(float *const *x, int nq, size_t np, double v, const char *what);
void c0_matirf_result_free(struct c0_matirf_result *r);
/* Plane j of the volume on the whole ny x nx grid (0 off the columns). */
void c0_matirf_plane(const struct c0_matirf_result *r, int j, float *plane);
/* The whole volume, nz x ny x nx (allocated; NULL when that fails):
 * small cases, tests and the library's c0_result_volume. */
float *c0_matirf_dense(const struct c0_matirf_result *r);
