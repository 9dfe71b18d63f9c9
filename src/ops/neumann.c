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
	fftw_plan fwd, inv;      /* exact: DCT-II and DCT-III in place */
	double *work;            /* exact: Py x Px */
	fftwf_plan pfwd, pinv;   /* periodic: r2c and c2r, in single precision */
	float *pwork;            /* periodic: Py x Px */
	fftwf_complex *spec;     /* periodic: Py x (Px/2 + 1) */
	double *ly, *lx;         /* eigenvalues of the 1-D second differences */
	double *scale;           /* exact: 1 / ((a + beta l^k) norm) for the last a, beta, k */
	float *fscale;           /* periodic: the same in single precision */
	double a, beta;
	int k;
};

void c0_neumann_free(struct c0_neumann *s)
{
	if (!s)
		return;
	c0_fftw_destroy(s->fwd), c0_fftw_destroy(s->inv);
	c0_fftwf_destroy(s->pfwd), c0_fftwf_destroy(s->pinv);
	fftw_free(s->work), fftwf_free(s->pwork), fftwf_free(s->spec), free(s->ly), free(s->lx), free(s->scale);
	free(s->fscale), free(s);
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
	s->Py = pad ? c0_fft_size(Ny + 2 * pad, 5, 1) : Ny, s->Px = pad ? c0_fft_size(Nx + 2 * pad, 5, 1) : Nx;
	const int Py = s->Py, Px = s->Px, Pc = s->periodic ? Px / 2 + 1 : Px;
	const size_t n = (size_t)Py * Px, nc = (size_t)Py * Pc;
	s->ly = c0_alloc((size_t)Py, sizeof *s->ly), s->lx = c0_alloc((size_t)Px, sizeof *s->lx);
	int ok = s->ly && s->lx;
	if (s->periodic) {
		s->pwork = fftwf_malloc(sizeof *s->pwork * n), s->spec = fftwf_malloc(sizeof *s->spec * nc);
		s->fscale = c0_alloc(nc, sizeof *s->fscale);
		ok = ok && s->pwork && s->spec && s->fscale;
	} else {
		s->work = fftw_malloc(sizeof *s->work * n), s->scale = c0_alloc(n, sizeof *s->scale);
		ok = ok && s->work && s->scale;
	}
	if (ok) {
#pragma omp critical(c0_fftw_plan)   /* fftw's planner is not thread-safe */
		if (s->periodic) {
			s->pfwd = fftwf_plan_dft_r2c_2d(Py, Px, s->pwork, s->spec, FFTW_ESTIMATE);
			s->pinv = fftwf_plan_dft_c2r_2d(Py, Px, s->spec, s->pwork, FFTW_ESTIMATE);
		} else {
			s->fwd = fftw_plan_r2r_2d(Py, Px, s->work, s->work, FFTW_REDFT10, FFTW_REDFT10, FFTW_ESTIMATE);
			s->inv = fftw_plan_r2r_2d(Py, Px, s->work, s->work, FFTW_REDFT01, FFTW_REDFT01, FFTW_ESTIMATE);
		}
	}
	if (s->periodic ? !s->pfwd || !s->pinv : !s->fwd || !s->inv) {
		c0_neumann_free(s);
		return c0_fail(C0_ENOMEM, "cannot plan the transforms of a %d x %d grid", Ny, Nx);
	}
	eig(Py, s->periodic, s->ly), eig(Px, s->periodic, s->lx);
	*out = s;
	return C0_OK;
}

/* the padded preconditioner: in set into the zero-padded grid, transformed,
 * scaled and back, all in single precision */
static void solve_periodic(struct c0_neumann *s, const double *in, double *out)
{
	const int Py = s->Py, Px = s->Px, Ny = s->Ny, Nx = s->Nx;
	const size_t nc = (size_t)Py * (Px / 2 + 1);
	float *w = s->pwork;
	for (int y = 0; y < Ny; y++) {   /* the inverse transform wrote all of work: its padding zeroed again */
		float *wr = w + (size_t)y * Px;
		const double *ir = in + (size_t)y * Nx;
		for (int x = 0; x < Nx; x++)
			wr[x] = (float)ir[x];
		memset(wr + Nx, 0, sizeof *w * (size_t)(Px - Nx));
	}
	memset(w + (size_t)Ny * Px, 0, sizeof *w * (size_t)(Py - Ny) * Px);
	fftwf_execute(s->pfwd);
	for (size_t i = 0; i < nc; i++)
		s->spec[i] *= s->fscale[i];
	fftwf_execute(s->pinv);
	for (int y = 0; y < Ny; y++) {
		const float *wr = w + (size_t)y * Px;
		double *or = out + (size_t)y * Nx;
		for (int x = 0; x < Nx; x++)
			or[x] = wr[x];
	}
}

void c0_neumann_solve(struct c0_neumann *s, double a, double beta, int k, const double *in, double *out)
{
	const int Py = s->Py, Px = s->Px, Pc = s->periodic ? Px / 2 + 1 : Px;
	const size_t n = (size_t)Py * Px;
	if (!(s->a == a && s->beta == beta && s->k == k)) {   /* the eigenvalues' scaling, once per operator */
		/* c2r of r2c: n; DCT-III of DCT-II: 2N a dimension */
		const double norm = s->periodic ? (double)n : 4.0 * (double)n;
		for (int y = 0; y < Py; y++)
			for (int x = 0; x < Pc; x++) {
				const double l = s->ly[y] + s->lx[x], d = a + beta * (k == 1 ? l : pow(l, k));
				const double v = d > 0 ? 1 / (d * norm) : 0;   /* the constant mode when a = 0 */
				if (s->periodic)
					s->fscale[(size_t)y * Pc + x] = (float)v;
				else
					s->scale[(size_t)y * Pc + x] = v;
			}
		s->a = a, s->beta = beta, s->k = k;
	}
	if (s->periodic) {
		solve_periodic(s, in, out);
		return;
	}
	memcpy(s->work, in, sizeof *in * n);
	fftw_execute(s->fwd);
	for (size_t i = 0; i < n; i++)
		s->work[i] *= s->scale[i];
	fftw_execute(s->inv);
	memcpy(out, s->work, sizeof *out * n);
}
