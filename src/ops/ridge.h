/* Ridges of a smooth image: how far a pixel lies from the crest of the
 * ridge it sits on, and a mask grown across its ridges by that distance.
 * For structures wider than one pixel whose crest a sparse mask marks. */
#pragma once
#include <stdint.h>

/* The distance (pixels) from pixel (y, x) of f (Ly x Lx, row-major) to the
 * crest of its ridge, by one Newton step across it: |g.n| / |k|, g the
 * gradient, k < 0 the Hessian's smaller eigenvalue and n its eigenvector
 * (central differences). Infinite where f does not curve down (k >= 0) and
 * on the outermost rows and columns. */
double c0_ridge_dist(const double *f, int Ly, int Lx, int y, int x);

/* mask (Ly x Lx, 0/1) grown by each 4-neighbour of its set pixels whose
 * distance to its ridge's crest is at most reach pixels (one step: the
 * pixels that join do not grow it further). Returns how many joined, or -1
 * when out of memory (mask unchanged). */
long c0_ridge_grow(const double *f, int Ly, int Lx, double reach, uint8_t *mask);
