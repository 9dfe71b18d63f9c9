/* The tests' references: the whole-grid forms of functions the library
 * runs on lists or bands, and dense or plain forms to check its fast ones
 * against. Only the tests (and bench/) call them. */
#pragma once
#include "core/band.h"
#include "ops/covop.h"
#include <stddef.h>
#include <stdint.h>

/* b as a dense m x n matrix, row-major. */
void c0_band_to_dense(const struct c0_band *b, double *dense);
/* Psi x (fine -> coarse) and Psi^T y. */
void c0_covop_psi(struct c0_covop *op, const double *x, double *y);
void c0_covop_psit(struct c0_covop *op, const double *y, double *x);
/* out (H x W) = x (H x W) convolved with a sampled, normalised Gaussian of
 * sd sigma_px (separable, radius ceil(3 sigma), zero outside the field). */
int c0_splat(const float *x, int H, int W, double sigma_px, float *out);
/* out = sum of x over the (2h+1)^2 window, on the mask (0 elsewhere). */
int c0_pool_window(const float *x, const uint8_t *mask, int ny, int nx, int h, float *out);
/* out[q] = sum of x[q] over the (2h+1)^2 window on the mask, counting only
 * the pixels whose guide depth lies within range nm of the centre's. */
int c0_pool_guided(const float *const *x, int nq, const uint8_t *mask, const float *guide, double range, int ny,
		   int nx, int h, float *const *out);
/* f (nz x M, the columns at raster indices pixel[0..M)) scaled by
 * sum_q x_q / sum_q pooled_q at each column's pixel (images on the grid). */
void c0_pool_rescale(float *f, int nz, const int *pixel, size_t M, int nq, const float *const *x, const float *const *pooled);
/* s's structure set to the simulator's before issue 52: emitters on each
 * filament's axis, 60 a um (the Python tests' LINES_SIM), for tests whose
 * bars were set on it. */
struct c0_sim_conf;
void c0_sim_lines(struct c0_sim_conf *s);
/* A simulation's truth_support.tif as a 0/1 mask (allocated; NULL when the
 * file cannot be read), its size into *w and *h. */
uint8_t *c0_truth_mask(const char *path, int *w, int *h);
