/* Ridges of a smooth image (ops/ridge.h). */
#include "ops/ridge.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

double c0_ridge_dist(const double *f, int Ly, int Lx, int y, int x)
{
	if (y < 1 || x < 1 || y >= Ly - 1 || x >= Lx - 1)
		return INFINITY;
	const double *p = f + (size_t)y * Lx + x;
	const double gy = 0.5 * (p[Lx] - p[-Lx]), gx = 0.5 * (p[1] - p[-1]);
	const double hyy = p[Lx] - 2 * p[0] + p[-Lx], hxx = p[1] - 2 * p[0] + p[-1];
	const double hxy = 0.25 * (p[Lx + 1] - p[Lx - 1] - p[-Lx + 1] + p[-Lx - 1]);
	/* the smaller eigenvalue of [[hyy, hxy], [hxy, hxx]] and its vector */
	const double m = 0.5 * (hyy + hxx), k = m - sqrt(0.25 * (hyy - hxx) * (hyy - hxx) + hxy * hxy);
	if (!(k < 0))
		return INFINITY;
	/* (hxy, k - hyy) and (k - hxx, hxy) both solve it: the longer is the
	 * better conditioned */
	double ny = hxy, nx = k - hyy;
	if (fabs(k - hxx) > fabs(k - hyy))
		ny = k - hxx, nx = hxy;
	const double nn = hypot(ny, nx);
	if (!(nn > 0))  /* hxy = 0 and hyy = hxx: a round crest, every direction alike */
		return hypot(gy, gx) / -k;
	return fabs(gy * ny + gx * nx) / nn / -k;
}

long c0_ridge_grow(const double *f, int Ly, int Lx, double reach, uint8_t *mask)
{
	const size_t L = (size_t)Ly * Lx;
	uint8_t *in = c0_alloc(L, 1);
	if (!in)
		return -1;
	memcpy(in, mask, L);
	long joined = 0;
	for (int y = 1; y < Ly - 1; y++)
		for (int x = 1; x < Lx - 1; x++) {
			const size_t i = (size_t)y * Lx + x;
			if (in[i] || !(in[i - 1] | in[i + 1] | in[i - Lx] | in[i + Lx]))
				continue;
			if (c0_ridge_dist(f, Ly, Lx, y, x) <= reach)
				mask[i] = 1, joined++;
		}
	free(in);
	return joined;
}
