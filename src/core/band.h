/* Banded matrices with a fixed number of stored entries per row: row i holds
 * columns start[i] .. start[i]+w-1 (entries past the band are zero). Used for
 * the separable 1-D factors of every operator here, applied along one axis
 * of a row-major image (x fastest). */
#pragma once

struct c0_band {
	int m, n;      /* rows, columns */
	int w;         /* stored entries per row */
	int *start;    /* m first columns, with 0 <= start[i] <= n - w */
	double *v;     /* m*w values */
};

int c0_band_alloc(struct c0_band *b, int m, int n, int w);
void c0_band_free(struct c0_band *b);
double c0_band_get(const struct c0_band *b, int i, int j);
/* Transpose as a new band (exact). */
int c0_band_transpose(const struct c0_band *b, struct c0_band *t);
/* Drops stored entries below tol*max|v| at the ends of rows to shrink w. */
int c0_band_trim(struct c0_band *b, double tol);
/* out[j] = sum_i B[i][j]^2 (n values) */
void c0_band_col_sumsq(const struct c0_band *b, double *out);
/* out[y][i] = sum_k B[i][k] in[y][k]; in is ny x n, out is ny x m */
void c0_band_apply_x(const struct c0_band *b, int ny, const double *in, double *out);
/* The same for a symmetric B (row k of B is its column k) and a sparse in:
 * each non-zero in[y][k] adds its row of B to out's row y. The sums run in
 * the same order as c0_band_apply_x's, so the numbers are the same, at the
 * cost of a row of B per non-zero instead of a dot product per output. */
void c0_band_apply_x_sym_sparse(const struct c0_band *b, int ny, const double *in, double *out);
/* out[i][x] = sum_k B[i][k] in[k][x]; in is n x nx, out is m x nx */
void c0_band_apply_y(const struct c0_band *b, int nx, const double *in, double *out);

/* Occupancy of a row-major image by strips of C0_BAND_STRIP columns:
 * occ[y * C0_BAND_STRIPS(nx) + s] = 0 says that row y is exactly zero in
 * columns [s C0_BAND_STRIP, (s + 1) C0_BAND_STRIP). */
#define C0_BAND_STRIP 16
#define C0_BAND_STRIPS(nx) (((nx) + C0_BAND_STRIP - 1) / C0_BAND_STRIP)
/* apply_x_sym_sparse that also writes out's occupancy (ny x STRIPS(m)) */
void c0_band_apply_x_sym_sparse_occ(const struct c0_band *b, int ny, const double *in, double *out, unsigned char *occ);
/* apply_y given in's occupancy: an output strip whose band rows are all
 * zero there is written as zeros without its sums (the same numbers: a sum
 * of zero products is +0) */
void c0_band_apply_y_occ(const struct c0_band *b, int nx, const double *in, const unsigned char *occ, double *out);
/* Largest eigenvalue of a symmetric nonnegative band (power iteration from
 * the all-ones vector, close to the Perron vector). */
double c0_band_lambda_max(const struct c0_band *b, int iters);
