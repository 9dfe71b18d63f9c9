#include "ops/psi_omega.h"
#include "optics/psf.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/threads.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define MAXOFF 160   /* offsets within radius 8 number 98 */

/* The weight of the edge a -> b, offset (dx, dy): 1/distance, times the
 * direction's factor with dir (0: dropped). */
static double edge_weight(const float *dir, double power, int a, int b, int dx, int dy)
{
	const double d2 = dx * dx + dy * dy;
	if (!dir)
		return 1 / sqrt(d2);
	const double ca = dir[2 * a] * dx + dir[2 * a + 1] * dy, cb = dir[2 * b] * dx + dir[2 * b + 1] * dy;
	const double f = pow(fmax(0, 1 - 0.5 * (ca * ca + cb * cb) / d2), 0.5 * power);
	return f < C0_ORIENT_DROP ? 0 : f / sqrt(d2);
}

/* The graph's edges to the later pixels (raster order) within the radius:
 * counted (p->e0 NULL) or stored. */
static int graph_edges(struct c0_psi_omega *p, const int *pos, double radius, const float *dir, double power)
{
	int no = 0, ox[MAXOFF], oy[MAXOFF], ne = 0;
	const int R = (int)radius;
	for (int dy = 0; dy <= R; dy++)
		for (int dx = -R; dx <= R; dx++)
			if ((dy > 0 || dx > 0) && dx * dx + dy * dy <= radius * radius && no < MAXOFF)
				ox[no] = dx, oy[no++] = dy;
	for (int y = 0; y < p->Ly; y++)
		for (int x = 0; x < p->Lx; x++) {
			const int k = pos[(size_t)y * p->Lx + x];
			for (int o = 0; k >= 0 && o < no; o++) {
				const int xx = x + ox[o], yy = y + oy[o];
				if (xx < 0 || xx >= p->Lx || yy >= p->Ly || pos[(size_t)yy * p->Lx + xx] < 0)
					continue;
				const int l = pos[(size_t)yy * p->Lx + xx];
				const double w = edge_weight(dir, power, k, l, ox[o], oy[o]);
				if (w > 0 && p->e0)
					p->e0[ne] = k, p->e1[ne] = l, p->ew[ne] = w;
				ne += w > 0;
			}
		}
	return ne;
}

int c0_psi_omega_init(struct c0_psi_omega *p, int Ny, int Nx, int r, double sigma, const uint8_t *mask, double radius)
{
	return c0_psi_omega_init_dir(p, Ny, Nx, r, sigma, mask, radius, NULL, 0);
}

int c0_psi_omega_init_dir(struct c0_psi_omega *p, int Ny, int Nx, int r, double sigma, const uint8_t *mask, double radius,
			  const float *dir, double power)
{
	memset(p, 0, sizeof *p);
	p->Ny = Ny, p->Nx = Nx, p->Ly = Ny * r, p->Lx = Nx * r;
	const size_t L = (size_t)p->Ly * p->Lx;
	int *pos = c0_alloc(L, sizeof *pos);
	if (!pos)
		return C0_ENOMEM;
	for (size_t i = 0; i < L; i++)
		pos[i] = mask[i] ? p->n++ : -1;
	if (!p->n) {
		free(pos);
		return c0_fail(C0_EINVAL, "the support is empty: no fine pixel to estimate");
	}
	const int ne = graph_edges(p, pos, radius, dir, power);
	p->idx = c0_alloc((size_t)p->n, sizeof *p->idx);
	p->e0 = c0_alloc((size_t)ne + 1, sizeof *p->e0);
	p->e1 = c0_alloc((size_t)ne + 1, sizeof *p->e1);
	p->ew = c0_alloc((size_t)ne + 1, sizeof *p->ew);
	struct c0_band Gy, Gx;
	int st = !p->idx || !p->e0 || !p->e1 || !p->ew ? C0_ENOMEM : C0_OK;
	if (!st)
		st = c0_psf_factor(Ny, r, sigma, &Gy);
	if (!st) {
		st = c0_psf_factor(Nx, r, sigma, &Gx);
		if (!st) {
			st = c0_band_transpose(&Gy, &p->GyT);
			if (!st)
				st = c0_band_transpose(&Gx, &p->GxT);
			c0_band_free(&Gx);
		}
		c0_band_free(&Gy);
	}
	if (st) {
		free(pos);
		c0_psi_omega_free(p);
		return st;
	}
	for (size_t i = 0; i < L; i++)
		if (pos[i] >= 0)
			p->idx[pos[i]] = (int)i;
	p->ne = graph_edges(p, pos, radius, dir, power);
	free(pos);
	/* inside another team (tiles side by side) the adjoint runs alone */
	for (p->ring = 1; p->ring < p->GyT.w; p->ring *= 2)
		;
	p->nws = c0_threads_here();
	p->ws_t = c0_alloc((size_t)p->nws * p->Lx * p->ring, sizeof *p->ws_t);
	p->ws_hi = c0_alloc((size_t)p->nws * p->Lx, sizeof *p->ws_hi);
	if (!p->ws_t || !p->ws_hi) {
		c0_psi_omega_free(p);
		return C0_ENOMEM;
	}
	return C0_OK;
}

void c0_psi_omega_free(struct c0_psi_omega *p)
{
	free(p->idx), free(p->e0), free(p->e1), free(p->ew), free(p->ws_t), free(p->ws_hi);
	c0_band_free(&p->GyT), c0_band_free(&p->GxT);
	memset(p, 0, sizeof *p);
}

/* first support pixel whose PSF footprint starts at coarse row >= row
 * (footprints start at nondecreasing rows: idx is in raster order) */
static int first_from_row(const struct c0_psi_omega *p, int row)
{
	int lo = 0, hi = p->n;
	while (lo < hi) {
		int mid = lo + (hi - lo) / 2;
		if (p->GyT.start[p->idx[mid] / p->Lx] < row)
			lo = mid + 1;
		else
			hi = mid;
	}
	return lo;
}

/* support pixels k0..k1 scattered into y */
C0_HOT static void scatter(const struct c0_psi_omega *p, int k0, int k1, const double *x, double *y)
{
	const int wy = p->GyT.w, wx = p->GxT.w;
	for (int k = k0; k < k1; k++) {
		if (x[k] == 0)
			continue;
		const int a = p->idx[k] / p->Lx, b = p->idx[k] % p->Lx;
		const double *gy = p->GyT.v + (size_t)a * wy, *gx = p->GxT.v + (size_t)b * wx;
		const int i0 = p->GyT.start[a], j0 = p->GxT.start[b];
		for (int i = 0; i < wy; i++) {
			double c = x[k] * gy[i];
			double *row = y + (size_t)(i0 + i) * p->Nx + j0;
			for (int j = 0; j < wx; j++)
				row[j] += c * gx[j];
		}
	}
}

/* A scatter: support pixels are cut into bands by the first coarse row they
 * touch. Bands at least as tall as a footprint, taken every other one, never
 * write the same row, so the even bands run in parallel, then the odd ones. */
void c0_psi_omega_forward(const struct c0_psi_omega *p, const double *x, double *y)
{
	const int wy = p->GyT.w;
	const int B = wy > 8 ? wy : 8, nband = (p->Ny + B - 1) / B;
	memset(y, 0, sizeof *y * (size_t)p->Ny * p->Nx);
	for (int parity = 0; parity < 2; parity++) {
#pragma omp parallel for schedule(dynamic, 1) if (p->n > 4096)
		for (int band = parity; band < nband; band += 2)
			scatter(p, first_from_row(p, band * B), first_from_row(p, (band + 1) * B), x, y);
	}
}

/* y gathered at support pixels k0..k1. Support pixels of one fine column
 * share their row sums t_i = sum_j y(i, j0 + j) gx(j) (they differ only in
 * gy): each is made once and kept in the column's ring of rows. Footprints
 * start at nondecreasing rows (raster order), so a column's rows still
 * needed are the last ones made, [i0, hi). The sums are the ones a pixel's
 * own double loop would make, in the same order: the same bits. */
C0_HOT static void gather(const struct c0_psi_omega *p, int k0, int k1, const double *y, double *x, double *T, int *hi)
{
	const int wy = p->GyT.w, wx = p->GxT.w, m = p->ring - 1;
	memset(hi, 0, sizeof *hi * (size_t)p->Lx);
	for (int k = k0; k < k1; k++) {
		const int a = p->idx[k] / p->Lx, b = p->idx[k] % p->Lx;
		const double *gy = p->GyT.v + (size_t)a * wy, *gx = p->GxT.v + (size_t)b * wx;
		const int i0 = p->GyT.start[a], j0 = p->GxT.start[b];
		double *tb = T + (size_t)b * p->ring;
		for (int i = i0 > hi[b] ? i0 : hi[b]; i < i0 + wy; i++) {
			const double *row = y + (size_t)i * p->Nx + j0;
			double t = 0;
			for (int j = 0; j < wx; j++)
				t += row[j] * gx[j];
			tb[i & m] = t;
		}
		hi[b] = i0 + wy;
		double s = 0;
		for (int i = 0; i < wy; i++)
			s += gy[i] * tb[(i0 + i) & m];
		x[k] = s;
	}
}

/* each thread a contiguous run of the support (and its own workspace) */
void c0_psi_omega_adjoint(const struct c0_psi_omega *p, const double *y, double *x)
{
#pragma omp parallel num_threads(p->nws) if (p->n > 4096)
	{
		const int nt = omp_get_num_threads(), id = omp_get_thread_num();
		const int k0 = (int)((long long)p->n * id / nt), k1 = (int)((long long)p->n * (id + 1) / nt);
		gather(p, k0, k1, y, x, p->ws_t + (size_t)id * p->Lx * p->ring, p->ws_hi + (size_t)id * p->Lx);
	}
}

void c0_grad_omega(const struct c0_psi_omega *p, const double *x, double *g)
{
	for (int e = 0; e < p->ne; e++)
		g[e] = p->ew[e] * (x[p->e1[e]] - x[p->e0[e]]);
}

void c0_grad_omega_adjoint(const struct c0_psi_omega *p, const double *g, double *x)
{
	memset(x, 0, sizeof *x * (size_t)p->n);
	for (int e = 0; e < p->ne; e++) {
		x[p->e1[e]] += p->ew[e] * g[e];
		x[p->e0[e]] -= p->ew[e] * g[e];
	}
}

double c0_psi_norm2(const struct c0_psi_omega *p)
{
	/* ||Psi||^2 = lambda_max(Gy Gy^T) lambda_max(Gx Gx^T); G^T's rows are G's columns */
	double l[2];
	const struct c0_band *T[2] = { &p->GyT, &p->GxT };
	for (int ax = 0; ax < 2; ax++) {
		struct c0_band G, GG;
		c0_band_transpose(T[ax], &G);      /* N x L */
		int N = G.m;
		c0_band_alloc(&GG, N, N, N);
		for (int i = 0; i < N; i++) {
			GG.start[i] = 0;
			for (int j = 0; j < N; j++) {
				double s = 0;
				for (int k = 0; k < G.w; k++) {
					int a = G.start[i] + k;
					s += G.v[(size_t)i * G.w + k] * c0_band_get(&G, j, a);
				}
				GG.v[(size_t)i * N + j] = s;
			}
		}
		l[ax] = c0_band_lambda_max(&GG, 1000);
		c0_band_free(&G), c0_band_free(&GG);
	}
	return l[0] * l[1];
}

void c0_psi_omega_diag(const struct c0_psi_omega *p, double *psi2)
{
	for (int k = 0; k < p->n; k++) {
		/* ||psi_k||^2 = ||gy_a||^2 ||gx_b||^2 */
		const int a = p->idx[k] / p->Lx, b = p->idx[k] % p->Lx;
		const double *gy = p->GyT.v + (size_t)a * p->GyT.w, *gx = p->GxT.v + (size_t)b * p->GxT.w;
		double sy = 0, sx = 0;
		for (int i = 0; i < p->GyT.w; i++)
			sy += gy[i] * gy[i];
		for (int j = 0; j < p->GxT.w; j++)
			sx += gx[j] * gx[j];
		psi2[k] = sy * sx;
	}
}

void c0_grad_omega_diag(const struct c0_psi_omega *p, double *deg)
{
	for (int k = 0; k < p->n; k++)
		deg[k] = 0;
	for (int e = 0; e < p->ne; e++)
		deg[p->e0[e]] += p->ew[e] * p->ew[e], deg[p->e1[e]] += p->ew[e] * p->ew[e];
}
