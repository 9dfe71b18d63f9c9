#include "ops/neumann.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/fftw_plan.h"
#include "core/mem.h"

#include <complex.h>
#include <fftw3.h>
#include <stddef.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* one row: its horizontal differences, then the vertical ones to the rows
 * above and below where they exist (NULL at the edges), added in that order
 * (the sums of three passes, bit for bit) in one pass over the row */
static void lap_row(int Nx, const double *restrict c, const double *restrict up, const double *restrict dn,
		    double *restrict o)
{
	if (Nx == 1) {
		o[0] = 0;
		if (up)
			o[0] += c[0] - up[0];
		if (dn)
			o[0] += c[0] - dn[0];
		return;
	}
	if (up && dn) {
		o[0] = c[0] - c[1] + (c[0] - up[0]) + (c[0] - dn[0]);
		for (int x = 1; x < Nx - 1; x++)
			o[x] = 2 * c[x] - c[x - 1] - c[x + 1] + (c[x] - up[x]) + (c[x] - dn[x]);
		o[Nx - 1] = c[Nx - 1] - c[Nx - 2] + (c[Nx - 1] - up[Nx - 1]) + (c[Nx - 1] - dn[Nx - 1]);
	} else if (up || dn) {
		const double *e = up ? up : dn;
		o[0] = c[0] - c[1] + (c[0] - e[0]);
		for (int x = 1; x < Nx - 1; x++)
			o[x] = 2 * c[x] - c[x - 1] - c[x + 1] + (c[x] - e[x]);
		o[Nx - 1] = c[Nx - 1] - c[Nx - 2] + (c[Nx - 1] - e[Nx - 1]);
	} else {
		o[0] = c[0] - c[1];
		for (int x = 1; x < Nx - 1; x++)
			o[x] = 2 * c[x] - c[x - 1] - c[x + 1];
		o[Nx - 1] = c[Nx - 1] - c[Nx - 2];
	}
}

void c0_neumann_laplacian(int Ny, int Nx, const double *in, double *out)
{
	for (int y = 0; y < Ny; y++) {
		const double *c = in + (size_t)y * Nx;
		lap_row(Nx, c, y > 0 ? c - Nx : NULL, y < Ny - 1 ? c + Nx : NULL, out + (size_t)y * Nx);
	}
}

struct c0_neumann {
	int Ny, Nx, Py, Px;      /* the grid, and the one transformed (padded: Py x Px) */
	int periodic;            /* the padded preconditioner: real FFTs on a periodic grid */
	fftw_plan fwd, inv;      /* DCT-II and DCT-III in place, or r2c and c2r */
	double *work;            /* Py x Px */
	fftw_complex *spec;      /* periodic: Py x (Px/2 + 1) */
	double *ly, *lx;         /* eigenvalues of the 1-D second differences */
	double *scale, a, beta;  /* 1 / ((a + beta l^k) norm) for the last a, beta, k */
	int k;
};

void c0_neumann_free(struct c0_neumann *s)
{
	if (!s)
		return;
	c0_fftw_destroy(s->fwd), c0_fftw_destroy(s->inv);
	fftw_free(s->work), fftw_free(s->spec), free(s->ly), free(s->lx), free(s->scale), free(s);
}

/* mirrored edges: 4 sin^2(pi k / 2n); periodic: 4 sin^2(pi k / n) */
static void eig(int n, int periodic, double *l)
{
	for (int k = 0; k < n; k++) {
		double s = sin(C0_PI * k / (periodic ? n : 2.0 * n));
		l[k] = 4 * s * s;
	}
}

int c0_neumann_new(int Ny, int Nx, int pad, struct c0_neumann **out)
{
	struct c0_neumann *s = c0_alloc(1, sizeof *s);
	*out = NULL;
	if (!s)
		return C0_ENOMEM;
	s->Ny = Ny, s->Nx = Nx, s->periodic = pad > 0;
	s->Py = pad ? c0_fft_size(Ny + 2 * pad, 7, 1) : Ny, s->Px = pad ? c0_fft_size(Nx + 2 * pad, 7, 1) : Nx;
	const int Py = s->Py, Px = s->Px, Pc = s->periodic ? Px / 2 + 1 : Px;
	s->work = fftw_malloc(sizeof *s->work * (size_t)Py * Px);
	s->spec = s->periodic ? fftw_malloc(sizeof *s->spec * (size_t)Py * Pc) : NULL;
	s->ly = c0_alloc((size_t)Py, sizeof *s->ly), s->lx = c0_alloc((size_t)Px, sizeof *s->lx);
	s->scale = c0_alloc((size_t)Py * Pc, sizeof *s->scale);
	if (s->work && s->ly && s->lx && s->scale && (s->spec || !s->periodic)) {
#pragma omp critical(c0_fftw_plan)   /* fftw's planner is not thread-safe */
		if (s->periodic) {
			s->fwd = fftw_plan_dft_r2c_2d(Py, Px, s->work, s->spec, FFTW_ESTIMATE);
			s->inv = fftw_plan_dft_c2r_2d(Py, Px, s->spec, s->work, FFTW_ESTIMATE);
		} else {
			s->fwd = fftw_plan_r2r_2d(Py, Px, s->work, s->work, FFTW_REDFT10, FFTW_REDFT10, FFTW_ESTIMATE);
			s->inv = fftw_plan_r2r_2d(Py, Px, s->work, s->work, FFTW_REDFT01, FFTW_REDFT01, FFTW_ESTIMATE);
		}
	}
	if (!s->fwd || !s->inv) {
		c0_neumann_free(s);
		return c0_fail(C0_ENOMEM, "cannot plan the transforms of a %d x %d grid", Ny, Nx);
	}
	eig(Py, s->periodic, s->ly), eig(Px, s->periodic, s->lx);
	*out = s;
	return C0_OK;
}

void c0_neumann_solve(struct c0_neumann *s, double a, double beta, int k, const double *in, double *out)
{
	const int Py = s->Py, Px = s->Px, Pc = s->periodic ? Px / 2 + 1 : Px;
	const size_t n = (size_t)Py * Px, nc = (size_t)Py * Pc;
	if (!(s->a == a && s->beta == beta && s->k == k)) {   /* the eigenvalues' scaling, once per operator */
		/* c2r of r2c: n; DCT-III of DCT-II: 2N a dimension */
		const double norm = s->periodic ? (double)n : 4.0 * (double)n;
		for (int y = 0; y < Py; y++)
			for (int x = 0; x < Pc; x++) {
				double l = s->ly[y] + s->lx[x], d = a + beta * (k == 1 ? l : pow(l, k));
				s->scale[(size_t)y * Pc + x] = d > 0 ? 1 / (d * norm) : 0;   /* the constant mode when a = 0 */
			}
		s->a = a, s->beta = beta, s->k = k;
	}
	for (int y = 0; y < s->Ny; y++) {   /* the inverse transform wrote all of work: its padding zeroed again */
		memcpy(s->work + (size_t)y * Px, in + (size_t)y * s->Nx, sizeof *in * s->Nx);
		memset(s->work + (size_t)y * Px + s->Nx, 0, sizeof *s->work * (size_t)(Px - s->Nx));
	}
	memset(s->work + (size_t)s->Ny * Px, 0, sizeof *s->work * (size_t)(Py - s->Ny) * Px);
	fftw_execute(s->fwd);
	if (s->periodic)
		for (size_t i = 0; i < nc; i++)
			s->spec[i] *= s->scale[i];
	else
		for (size_t i = 0; i < n; i++)
			s->work[i] *= s->scale[i];
	fftw_execute(s->inv);
	for (int y = 0; y < s->Ny; y++)
		memcpy(out + (size_t)y * s->Nx, s->work + (size_t)y * Px, sizeof *out * s->Nx);
}
