/* Intensity and background of one angle on a known support (COL0RME step 2):
 *   min_{x >= 0 on Omega, b >= 0}  1/2 ||Psi_Omega x + b - ybar||^2
 *                                 + mu/2 ||grad_Omega x||^2 + beta/2 ||L b||^2
 * ybar is the stack's temporal mean (camera units), x the mean intensity per
 * fine pixel (camera units per frame, total over the PSF), b the background
 * including the camera offset. grad_Omega couples the support pixels closer
 * than graph_radius fine pixels, each difference weighted by 1/distance: with
 * only 4-neighbours a diagonal filament falls apart into single pixels that
 * nothing smooths (docs/defaults.md#graph_radius). With graph_orient, a difference
 * across the structure weighs less than one along it (ops/psi_omega.h), so
 * that the smoothness does not pull a filament toward a neighbour at
 * another depth. L is the coarse grid's Laplacian
 * (ops/neumann.h): a curvature penalty, under which a dip in b as narrow as
 * the PSF costs (length / PSF)^2 more than a broad one, so b cannot trade
 * against x along a structure; the gradient's cost is the same at every
 * width in 2-D (docs/defaults.md#beta).
 * mu by the discrepancy principle:
 *   ||Psi x + b - ybar||^2 = nu^2 H W sigma2 / T. */
#pragma once
#include "optics/grid.h"
#include "solve/cg.h"

#include <stdint.h>

#include "col0rme.h"   /* enum c0_background */

struct c0_intensity_conf {
	struct c0_grid grid;       /* pixel_nm, fwhm_nm required; srf 4 */
	enum c0_background background; /* smooth */
	double beta;               /* 100: background curvature weight (coarse grid; smoothing length beta^(1/4) pixels) */
	double nu;                 /* 1; 0 means sqrt(T), the reference's choice (docs/defaults.md#nu) */
	double mu;                 /* 0: discrepancy principle; > 0: fixed */
	double tol;                /* 1e-3: CG relative residual, from x = 0, b = the mean (docs/defaults.md#cg_tol) */
	int maxit;                 /* 500 CG steps per active-set round */
	double graph_radius;       /* 6 fine pixels: smoothness neighbourhood (docs/defaults.md#graph_radius) */
	double graph_orient;       /* 20: an edge's weight times (1 - cos^2 with the pixels' normals)^(graph_orient/2); 0: none */
	int relative;              /* 1: residual^2 = floor^2 + target^2, floor = the residual at the smallest mu */
	int tile;                  /* 0: one solve on the whole image; else tiles of this side (camera
				    * pixels) with a halo of two PSF lags, each with its own mu */
	const float *weight;       /* NULL, or Ny x Nx: the data term is 1/2 sum_i w_i (Psi x + b - ybar)_i^2
				    * (w about 1 where a pixel's noise is the typical one: the principle's
				    * target stays; the camera's noisy pixels weigh less) */
	int common_pattern;        /* 0; 1: the whole method takes the MA-TIRF stacks' common fixed pattern
				    * out of their means when no offset map is given (stages/pattern.h) */
	int noise_block;           /* 0; > 0: the whole method also solves the difference of the means of the
				    * frames' two halves in blocks of this many frames (linear, at the final
				    * mu): a draw of the intensity's noise, which the depth readout weighs the
				    * angles by (stages/depthfit.h, c0_depth_noise) */
	int linear;                /* 0; 1: x and b unbounded, one CG solve and no active set: for the
				    * difference of two means, whose solution is then the difference of
				    * theirs wherever neither one's bounds are active (needs mu > 0) */
};
#define C0_INTENSITY_DEFAULTS { { 0, 0, 4 }, C0_BG_SMOOTH, 100, 1, 0, 1e-3, 500, 6, 20, 1, 0, NULL, 0, 0, 0 }
#define C0_INTENSITY_MU_MIN 1e-3   /* the smallest mu the principle may choose */

struct c0_intensity_result {
	int Ly, Lx, Ny, Nx;
	float *x;                  /* Ly x Lx, zero off the support */
	float *b;                  /* Ny x Nx */
	double mu, residual2, target2, sigma2;
	double floor2;             /* residual^2 at the smallest mu (relative principle), else 0 */
	int dp_status;             /* enum c0_root_status; 0 = discrepancy met */
	int solves, cg_iters, active_rounds;
	int tiles, tiles_met;      /* tiles solved (1: the whole image), and those whose principle was met */
	double seconds;
};

int c0_intensity_check(const struct c0_intensity_conf *c);
/* With tiles (c->tile smaller than the image): the tile grid of
 * core/tiles.h, tiles solved side by side and their interiors kept; mu is
 * then the interior-weighted geometric mean of the tiles' mu, and residual2,
 * target2 and floor2 the tiles' values scaled to their interiors and summed.
 * A window without support pixels solves only the background. */
int c0_intensity_solve(const struct c0_intensity_conf *c, const double *ybar, int Ny, int Nx, int64_t T,
		       const uint8_t *mask, double sigma2, struct c0_intensity_result *res);
/* n images of one size solved as c0_intensity_solve does, each with its own
 * conf (which must cut it into tiles), frames and noise variance, their
 * tiles in one pool side by side: the numbers of each are those of its own
 * c0_intensity_solve, and with n images a thread is idle only at the last
 * tile, not at each image's. skip[i] (NULL: none): image i is left out.
 * sts[i] and msg[i]: image i's status and error text; res[i].seconds is the
 * sum of its tiles' solve times (thread seconds). */
int c0_intensity_solve_many(int n, const struct c0_intensity_conf *c, const double *const *ybar, int Ny, int Nx,
			    const int64_t *T, const uint8_t *mask, const double *sigma2, const int *skip,
			    struct c0_intensity_result *res, int *sts, char (*msg)[256]);
void c0_intensity_result_free(struct c0_intensity_result *r);
