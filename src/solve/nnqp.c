#include "solve/nnqp.h"

#include <math.h>

/* z = A_II^-1 r_I by Cholesky of the nf x nf principal block I of A (idx);
 * returns 0, or -1 if the block is not numerically positive definite */
static int solve_block(int n, const double *H, const double *g, const int *idx, int nf, double *z)
{
	double L[C0_NNQP_MAX * C0_NNQP_MAX];
	for (int a = 0; a < nf; a++)
		for (int b = 0; b <= a; b++) {
			double s = H[idx[a] * n + idx[b]];
			for (int l = 0; l < b; l++)
				s -= L[a * nf + l] * L[b * nf + l];
			if (a == b) {
				if (!(s > 0))
					return -1;
				L[a * nf + a] = sqrt(s);
			} else
				L[a * nf + b] = s / L[b * nf + b];
		}
	for (int a = 0; a < nf; a++) {
		double s = g[a];
		for (int l = 0; l < a; l++)
			s -= L[a * nf + l] * z[l];
		z[a] = s / L[a * nf + a];
	}
	for (int a = nf - 1; a >= 0; a--) {
		double s = z[a];
		for (int l = a + 1; l < nf; l++)
			s -= L[l * nf + a] * z[l];
		z[a] = s / L[a * nf + a];
	}
	return 0;
}

int c0_nnqp(int n, const double *H, const double *Hi, const double *g, double *x)
{
	int idx[C0_NNQP_MAX], bdx[C0_NNQP_MAX], solves = 0, have0 = 0;
	unsigned char fr[C0_NNQP_MAX];
	double z[C0_NNQP_MAX], r[C0_NNQP_MAX], x0[C0_NNQP_MAX], gs = 0;
	for (int i = 0; i < n; i++) {
		if (!(x[i] > 0))
			x[i] = 0;
		fr[i] = x[i] > 0;
		gs = fabs(g[i]) > gs ? fabs(g[i]) : gs;
	}
	const double eps = 1e-12 * (gs > 0 ? gs : 1);
	for (int it = 0; it < 3 * n + 10; it++) {
		int nf = 0, nb = 0;
		for (int i = 0; i < n; i++) {
			if (fr[i])
				idx[nf++] = i;
			else
				bdx[nb++] = i;
		}
		if (nf) {
			solves++;
			if (nf <= nb) {           /* few free: their own block of H */
				for (int a = 0; a < nf; a++)
					r[a] = g[idx[a]];
				if (solve_block(n, H, r, idx, nf, z))
					return -1;
			} else {                  /* x0 = H^-1 g corrected on the bound set */
				if (!have0) {
					for (int i = 0; i < n; i++)   /* by columns of the symmetric Hi: no add chain */
						x0[i] = 0;
					for (int l = 0; l < n; l++)
						for (int i = 0; i < n; i++)
							x0[i] += Hi[l * n + i] * g[l];
					have0 = 1;
				}
				double nu[C0_NNQP_MAX];   /* x = x0 + Hi_:B nu, nu = -Hi_BB^-1 x0_B */
				for (int b = 0; b < nb; b++)
					r[b] = -x0[bdx[b]];
				if (nb && solve_block(n, Hi, r, bdx, nb, nu))
					return -1;
				for (int a = 0; a < nf; a++) {
					double s = x0[idx[a]];
					for (int b = 0; b < nb; b++)
						s += Hi[idx[a] * n + bdx[b]] * nu[b];
					z[a] = s;
				}
			}
			double alpha = 1;
			int out = -1;
			for (int a = 0; a < nf; a++)
				if (z[a] <= 0) {
					double d = x[idx[a]] - z[a], q = d > 0 ? x[idx[a]] / d : 0;
					if (q < alpha)
						alpha = q, out = idx[a];
				}
			for (int a = 0; a < nf; a++)
				x[idx[a]] += alpha * (z[a] - x[idx[a]]);
			if (out >= 0) {           /* blocked: the blocking variables leave F */
				x[out] = 0;
				for (int a = 0; a < nf; a++)
					if (!(x[idx[a]] > 0))
						x[idx[a]] = 0, fr[idx[a]] = 0;
				fr[out] = 0;
				continue;
			}
		}
		int best = -1;                    /* optimal on F: free the steepest bound one */
		double wb = eps;
		for (int b = 0; b < nb; b++) {
			const int i = bdx[b];
			double w = g[i];
			for (int a = 0; a < nf; a++)
				w -= H[i * n + idx[a]] * x[idx[a]];
			if (w > wb)
				wb = w, best = i;
		}
		if (best < 0)
			return solves;
		fr[best] = 1;
	}
	return -1;
}

int c0_spd_inverse(int n, const double *A, double *Ai)
{
	int idx[C0_NNQP_MAX];
	double r[C0_NNQP_MAX], z[C0_NNQP_MAX];
	for (int i = 0; i < n; i++)
		idx[i] = i;
	for (int e = 0; e < n; e++) {
		for (int i = 0; i < n; i++)
			r[i] = i == e;
		if (solve_block(n, A, r, idx, n, z))
			return -1;
		for (int i = 0; i < n; i++)
			Ai[i * n + e] = z[i];
	}
	return 0;
}
