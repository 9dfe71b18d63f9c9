/* The dense formulation of the COL0RME support solver, as the reference
 * MATLAB code runs it: the full N^2 x N^2 covariance, the model covariance
 * Psi diag(x) Psi^T as a dense product, and the adjoint through the
 * Khatri-Rao factors. Only for timing against the banded solver.
 *   dense_baseline STACK.tif PIXEL_NM FWHM_NM SRF ITERATIONS   -> prints ms per iteration */
#include "optics/psf.h"
#include "io/tiff.h"
#include "core/clock.h"
#include "core/err.h"
#include "testkit/reference.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char **argv)
{
	if (argc != 6) {
		fprintf(stderr, "usage: dense_baseline STACK PIXEL_NM FWHM_NM SRF ITERATIONS\n");
		return 2;
	}
	struct c0_tiff_info in;
	float *st;
	if (c0_tiff_load_f32(argv[1], &in, &st)) {
		fprintf(stderr, "%s\n", c0_errmsg());
		return 1;
	}
	const int N = (int)in.width, r = atoi(argv[4]), L = N * r, N2 = N * N, L2 = L * L, T = (int)in.pages, its = atoi(argv[5]);
	double t0 = c0_now();
	/* dense covariance */
	double *mean = calloc(N2, sizeof(double)), *R = calloc((size_t)N2 * N2, sizeof(double));
	for (int t = 0; t < T; t++)
		for (int p = 0; p < N2; p++)
			mean[p] += st[(size_t)t * N2 + p] / T;
	for (int t = 0; t < T; t++)
		for (int p = 0; p < N2; p++) {
			double a = st[(size_t)t * N2 + p] - mean[p];
			for (int q = 0; q < N2; q++)
				R[(size_t)p * N2 + q] += a * (st[(size_t)t * N2 + q] - mean[q]) / (T - 1);
		}
	double tcov = c0_now() - t0;
	struct c0_band Gb;
	c0_psf_factor(N, r, c0_psf_sigma_px(atof(argv[3]), atof(argv[2])), &Gb);
	double *G = malloc(sizeof(double) * N * L);
	c0_band_to_dense(&Gb, G);
	/* Psi (N2 x L2) and the Khatri-Rao factor GG (N^2 x L): GG[(i1,i2), a] = G[i1][a] G[i2][a] */
	double *P = malloc(sizeof(double) * (size_t)N2 * L2), *GG = malloc(sizeof(double) * (size_t)N2 * L);
	for (int i = 0; i < N; i++)
		for (int j = 0; j < N; j++)
			for (int a = 0; a < L; a++)
				for (int b = 0; b < L; b++)
					P[(size_t)(i * N + j) * L2 + a * L + b] = G[i * L + a] * G[j * L + b];
	for (int i1 = 0; i1 < N; i1++)
		for (int i2 = 0; i2 < N; i2++)
			for (int a = 0; a < L; a++)
				GG[(size_t)(i1 * N + i2) * L + a] = G[i1 * L + a] * G[i2 * L + a];
	double *x = malloc(sizeof(double) * L2), *Px = malloc(sizeof(double) * (size_t)N2 * L2);
	double *M = malloc(sizeof(double) * (size_t)N2 * N2), *Wm = malloc(sizeof(double) * (size_t)N2 * N2);
	double *tmp = malloc(sizeof(double) * (size_t)N2 * L), *g = malloc(sizeof(double) * L2);
	for (int k = 0; k < L2; k++)
		x[k] = 1e-3 * (k % 7);
	t0 = c0_now();
	for (int it = 0; it < its; it++) {
		/* forward: (Psi scaled by x) Psi^T, N^4 L^2 multiply-adds */
		for (int p = 0; p < N2; p++)
			for (int k = 0; k < L2; k++)
				Px[(size_t)p * L2 + k] = P[(size_t)p * L2 + k] * x[k];
#pragma omp parallel for
		for (int p = 0; p < N2; p++)
			for (int q = 0; q < N2; q++) {
				double s = 0;
				for (int k = 0; k < L2; k++)
					s += Px[(size_t)p * L2 + k] * P[(size_t)q * L2 + k];
				M[(size_t)p * N2 + q] = s - R[(size_t)p * N2 + q];
			}
		/* adjoint: regroup rows (i1,i2), columns (j1,j2); g = GG^T W GG */
		for (int i1 = 0; i1 < N; i1++)
			for (int j1 = 0; j1 < N; j1++)
				for (int i2 = 0; i2 < N; i2++)
					for (int j2 = 0; j2 < N; j2++)
						Wm[(size_t)(i1 * N + i2) * N2 + j1 * N + j2] = M[(size_t)(i1 * N + j1) * N2 + i2 * N + j2];
#pragma omp parallel for
		for (int p = 0; p < N2; p++)
			for (int b = 0; b < L; b++) {
				double s = 0;
				for (int q = 0; q < N2; q++)
					s += Wm[(size_t)p * N2 + q] * GG[(size_t)q * L + b];
				tmp[(size_t)p * L + b] = s;
			}
		for (int a = 0; a < L; a++)
			for (int b = 0; b < L; b++) {
				double s = 0;
				for (int p = 0; p < N2; p++)
					s += GG[(size_t)p * L + a] * tmp[(size_t)p * L + b];
				g[a * L + b] = s;
			}
		for (int k = 0; k < L2; k++)
			x[k] = x[k] - 1e-3 * g[k] > 0 ? x[k] - 1e-3 * g[k] : 0;
	}
	double tit = (c0_now() - t0) / its;
	printf("%.6f %.6f\n", tit, tcov);
	return 0;
}
