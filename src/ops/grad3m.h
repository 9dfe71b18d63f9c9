/* Gradient of a volume that lives on a subset of the lateral pixels: M
 * columns (the pixels of a mask, in raster order) times nz depths, stored
 * v[j * M + k]. Lateral differences join 4-neighbour pixels that are both
 * in the mask; axial differences join neighbouring depths of one column.
 * Forward differences scaled by (wl, wl, wz), zero where the neighbour is
 * missing (Neumann), nc components of M*nz values: 3, or 2 when wz = 0 (the
 * axial one would be zero). With a full mask this is the usual 3D gradient
 * with Neumann borders. */
#pragma once
#include <stddef.h>
#include <stdint.h>

struct c0_grad3m {
	int M, nz, nc;
	double wl, wz;
	/* Per column: 1 or 0 for whether the right, lower and upper neighbours
	 * exist (the right one is always column k + 1, the left one k - 1 when
	 * column k - 1 has a right neighbour), and the lower and upper neighbour
	 * columns, k itself where missing: the loops then have no branches. */
	float *hr, *hd, *hu;
	int *down, *up;
	int *pixel;                      /* M: raster index of each column */
};

/* mask: ny x nx (nonzero = in); M = 0 is allowed. */
int c0_grad3m_init(struct c0_grad3m *g, const uint8_t *mask, int ny, int nx, int nz, double wl, double wz);
void c0_grad3m_free(struct c0_grad3m *g);
void c0_grad3m_forward(const struct c0_grad3m *g, const float *v, float *d);   /* M nz -> nc M nz */
void c0_grad3m_adjoint(const struct c0_grad3m *g, const float *d, float *v);   /* nc M nz -> M nz */
/* Per voxel, the sum of |entries| of its column of the operator (for
 * diagonal preconditioning): wl (lateral neighbours) + wz (axial neighbours). */
double c0_grad3m_colsum(const struct c0_grad3m *g, int k, int j);

/* The lateral differences, unweighted, of columns k0 .. k0+n-1 at one depth
 * (t: that depth's M values): ex to the right neighbour, ey to the lower
 * one, 0 where missing. Inline, for solvers that fuse the operator with
 * their updates a chunk of columns at a time. */
static inline void c0_grad3m_lateral(const struct c0_grad3m *g, const float *t, size_t k0, size_t n, float *ex, float *ey)
{
	const size_t nr = k0 + n < (size_t)g->M ? n : n - 1;   /* the last column has no right neighbour */
	for (size_t i = 0; i < nr; i++)
		ex[i] = g->hr[k0 + i] * (t[k0 + i + 1] - t[k0 + i]);
	if (nr < n)
		ex[nr] = 0;
	for (size_t i = 0; i < n; i++)       /* gather: from the lower neighbour */
		ey[i] = t[g->down[k0 + i]] - t[k0 + i];
}

/* Its adjoint on the same chunk: a = the chunk's entries of D^T (dx, dy),
 * dx and dy one depth's M values of each component. */
static inline void c0_grad3m_lateral_adjoint(const struct c0_grad3m *g, const float *dx, const float *dy, size_t k0, size_t n,
					     float *a)
{
	const float *dxk = dx + k0, *hr = g->hr + k0, *hd = g->hd + k0;
	for (size_t i = 0; i < n; i++)
		a[i] = -hr[i] * dxk[i] - hd[i] * dy[k0 + i];
	if (k0 > 0)
		a[0] += hr[-1] * dxk[-1];
	for (size_t i = 1; i < n; i++)
		a[i] += hr[i - 1] * dxk[i - 1];
	for (size_t i = 0; i < n; i++)       /* gather: from the upper neighbour */
		a[i] += g->hu[k0 + i] * dy[g->up[k0 + i]];
}
