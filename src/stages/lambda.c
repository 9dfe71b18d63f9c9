#include "stages/lambda.h"
#include "stages/support_parts.h"
#include "ops/covop.h"
#include "optics/psf.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/order.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* docs/defaults.md#lambda: the first step's threshold is RHO times the QUANT
 * quantile of the correlation image over the pixels above the noise floor
 * (the bright structure's typical level, which one very bright spot does
 * not move as it moves lambda_max), never below KAPPA noise sds. It follows
 * the emitters' density, the best lambda one emitter's variance: on the
 * simulated panel it was within 0.03 of a sweep's best on 16 of 19 members
 * (sparse 0.048 short, depths 0-400 nm at 65 degrees 0.052), the second
 * step (lambda.h) with sigma_C from the lower quartile on 18 (spread 1 dense
 * 0.032 short); the fixed 1e-2 lambda_max lost 0.07-0.2 where the
 * brightness spreads widely. KAPPA = 4 takes the MusiJ stacks'
 * far-from-structure share below 10 %. */
static const double RHO = 2e-2, QUANT = 0.9, KAPPA = 4;
/* CEL0 does not shrink what it keeps, and is best with a lower entry
 * threshold: a fraction of the square of the l1 choice */
static const double CEL0_GAMMA = 0.03;

/* C = A^T vec(R / norm) and tr(R / norm) */
static void correlate(struct c0_covop *op, const struct c0_cov *cov, double norm, double *R, double *C, double *trR)
{
	const size_t n = (size_t)cov->W * cov->H;
	*trR = 0;
	for (int l = 0; l < cov->nlag; l++)
		for (size_t i = 0; i < n; i++) {
			R[(size_t)l * n + i] = cov->r[(size_t)l * n + i] / norm;
			if (l == 0)
				*trR += R[i];
		}
	c0_covop_adjoint(op, cov, R, C);
}

double c0_lambda_width_share(const struct c0_support_conf *c)
{
	const double s = c0_grid_sigma_px(&c->grid) * c->grid.pixel_nm, R = fmax(0, c->label_radius_nm);
	return 0.5 * R * R / (s * s + c->grid.pixel_nm * c->grid.pixel_nm / 12);
}

/* The rule, from sigma_C, the signal quantiles sq (QUANT) and sm (the
 * median), lambda_max on the l1 and the l0 scale and the median column
 * norm. */
static void choose(const struct c0_support_conf *c, double sig, double sq, double sm, double lmax, double lmax0,
		   double nm, struct c0_lambda_result *out)
{
	out->noise_rel = sig / lmax, out->signal_rel = sq / lmax, out->rho = RHO, out->kappa = KAPPA;
	out->median_rel = sm / lmax, out->width_share = c0_lambda_width_share(c);
	out->noise_bound = KAPPA * sig >= RHO * sq;
	const double t = fmax(RHO * sq, KAPPA * sig), w = out->width_share * sm;
	if (c->penalty == C0_PENALTY_L1 && c->lambda_noise && !c->lambda_cv) {
		/* beside a tube's axis the correlation is the width's share plus the
		 * noise: kappa sds above the share keep those pixels out as kappa
		 * sds above 0 keep out the empty ones */
		out->noise = 1, out->noise_bound = KAPPA * sig >= w;
		out->chosen_rel = (KAPPA * sig + w) / lmax;
	} else if (c->penalty == C0_PENALTY_L1)
		out->chosen_rel = t / lmax;
	else
		out->chosen_rel = fmin(CEL0_GAMMA * t * t / (2 * nm * nm) / lmax0, 0.5);
}

/* Histogram bins: HB_PER per decade from 10^HB_LO (normalised units, in
 * which lambda_max is of order 1e-2 to 1); a median read from them is
 * within 0.1 % of the exact one. */
#define HB_LO (-12)
#define HB_PER (C0_LAMBDA_BINS / 14)

/* v's position on the bins' axis (-1 for v <= 0) and the bin that holds it */
static double bin_pos(double v)
{
	return v > 0 ? (log10(v) - HB_LO) * HB_PER : -1;
}

static int bin_of(double v)
{
	const double u = bin_pos(v);
	return u < 0 ? 0 : u >= C0_LAMBDA_BINS ? C0_LAMBDA_BINS - 1 : (int)u;
}

static void bin(double *h, double v)
{
	h[bin_of(v)]++;
}

static double hmedian(const double *h)
{
	double all = 0, cum = 0;
	for (int k = 0; k < C0_LAMBDA_BINS; k++)
		all += h[k];
	for (int k = 0; k < C0_LAMBDA_BINS; k++) {
		if (h[k] > 0 && cum + h[k] >= 0.5 * all)
			return pow(10, HB_LO + (k + (0.5 * all - cum) / h[k]) / HB_PER);
		cum += h[k];
	}
	return 0;
}

double c0_lambda_curve_rel(int k)
{
	return pow(10, -4 + k / 8.0);
}

/* The share of the all counts of h that lie above v (the bin that holds v
 * split linearly in log v, as the quantiles read it) */
static double share_above(const double *h, double all, double v)
{
	const int kv = bin_of(v);
	double above = h[kv] * fmin(1, fmax(0, kv + 1 - bin_pos(v)));
	for (int k = kv + 1; k < C0_LAMBDA_BINS; k++)
		above += h[k];
	return all > 0 ? above / all : 0;
}

static void curve(const double *signal, const double *noise, double lmax, struct c0_lambda_result *out)
{
	double ns = 0, nn = 0;
	for (int k = 0; k < C0_LAMBDA_BINS; k++)
		ns += signal[k], nn += noise[k];
	for (int k = 0; k < C0_LAMBDA_CURVE; k++) {
		const double lam = lmax * c0_lambda_curve_rel(k);
		out->curve_signal[k] = share_above(signal, ns, lam);
		out->curve_noise[k] = share_above(noise, nn, lam);
	}
}

/* The value below which a fraction q of the counts of h above tau lie
 * (0 when none is above tau) */
static double hquantile_above(const double *h, double tau, double q)
{
	const int kt = bin_of(tau);
	double all = 0, cum = 0;
	for (int k = kt; k < C0_LAMBDA_BINS; k++)
		all += h[k];
	const double need = (1 - q) * all;
	for (int k = C0_LAMBDA_BINS - 1; all > 0 && k >= kt; k--) {
		if (h[k] > 0 && cum + h[k] >= need)
			return pow(10, HB_LO + (k + 1 - (need - cum) / h[k]) / HB_PER);
		cum += h[k];
	}
	return 0;
}

/* sigma_C from the noise image's histogram: |C_A - C_B| / 2 is half-normal
 * with sd sigma where the halves differ by noise alone, and its lower
 * quartile (0.3186 sigma) reads sigma from the background while the
 * structure, whose own sampling noise is larger, covers under 3/4 of the
 * field; the median (0.6745 sigma), read before, took the structure's on
 * dense fields (docs/defaults.md#lambda) */
static double noise_sd(const double *noise)
{
	return hquantile_above(noise, 0, 0.25) / 0.3186;
}

int c0_lambda_auto(const struct c0_support_conf *c, const struct c0_cov *a, const struct c0_cov *b,
		   struct c0_lambda_result *out)
{
	double t0 = c0_now();
	memset(out, 0, sizeof *out);
	if (a->W != b->W || a->H != b->H || a->nlag != b->nlag)
		return c0_fail(C0_EINVAL, "lambda: the two halves differ in size");
	const int r = c->grid.srf;
	const size_t n = (size_t)a->W * a->H, L = n * r * r;
	struct c0_covop op;
	int st = c0_support_covop(c, a, &op);
	if (st)
		return st;
	double *R = c0_alloc((size_t)a->nlag * n, sizeof *R), *ca = c0_alloc(L, sizeof *ca);
	double *cb = c0_alloc(L, sizeof *cb), *d = c0_alloc(L, sizeof *d);
	if (!R || !ca || !cb || !d) {
		st = C0_ENOMEM;
		goto out;
	}
	double norm = 0, tra, trb;
	for (size_t i = 0; i < n; i++)
		norm = fmax(norm, 0.5 * (a->r[i] + b->r[i]));
	if (!(norm > 0)) {
		st = c0_support_fail_flat();
		goto out;
	}
	correlate(&op, a, norm, R, ca, &tra);
	correlate(&op, b, norm, R, cb, &trb);
	/* lambda_max of the mean of the halves, on both scales (as in support_solve.c) */
	const double s0 = fmax(0, 0.5 * (tra + trb) / (double)n);
	for (size_t i = 0; i < L; i++)
		d[i] = fabs(ca[i] - cb[i]) / 2, ca[i] = 0.5 * (ca[i] + cb[i]);
	double lm[2];
	c0_lambda_max(ca, 1, s0, op.n, L, lm);
	const double lmax = lm[0], lmax0 = lm[1];
	if (!(lmax > 0)) {
		st = c0_fail(C0_EINVAL, "the stack's covariance correlates with no emitter position (lambda_max = 0)");
		goto out;
	}
	/* the signal: ca - s0 n, as lambda_max reads it, and the noise, binned as on tiles */
	double *h = c0_alloc(2 * C0_LAMBDA_BINS, sizeof *h), *hn = h + C0_LAMBDA_BINS;
	if (!h) {
		st = C0_ENOMEM;
		goto out;
	}
	for (size_t i = 0; i < L; i++)
		bin(h, ca[i] - s0 * op.n[i]), bin(hn, d[i]);
	const double sig = noise_sd(hn);
	const double sq = hquantile_above(h, KAPPA * sig, QUANT), sm = hquantile_above(h, KAPPA * sig, 0.5);
	memcpy(d, op.n, L * sizeof *d);
	choose(c, sig, sq, sm, lmax, lmax0, c0_median(d, L), out);
	curve(h, hn, lmax, out);
	free(h);
	/* a check of the stated PSF, not a part of the rule: none when the band is too short */
	double fw;
	out->fwhm_data_nm = c0_lambda_psf_fwhm(a, b, c->grid.pixel_nm, &fw) ? (c0_clear_error(), 0) : fw;
out:
	free(R), free(ca), free(cb), free(d);
	c0_covop_free(&op);
	out->seconds = c0_now() - t0;
	return st;
}

int c0_lambda_peaks(const struct c0_support_conf *c, const float *rx, double norm, int Ny, int Nx, int iy, int ix,
		    int ih, int iw, double *hist)
{
	const int r = c->grid.srf, Ly = Ny * r, Lx = Nx * r;
	const double sigma = c0_grid_sigma_px(&c->grid);
	/* ||psi_a||^2 = ny[ay] nx[ax], the window's PSF factors' column norms as
	 * the solve's (ops/covop.h) */
	struct c0_band Gy = { 0 }, Gx = { 0 };
	double *ny = c0_alloc((size_t)Ly, sizeof *ny), *nx = c0_alloc((size_t)Lx, sizeof *nx);
	int st = ny && nx ? c0_psf_factor(Ny, r, sigma, &Gy) : C0_ENOMEM;
	if (!st)
		st = c0_psf_factor(Nx, r, sigma, &Gx);
	if (!st)
		c0_band_col_sumsq(&Gy, ny), c0_band_col_sumsq(&Gx, nx);
	c0_band_free(&Gy), c0_band_free(&Gx);
	if (st) {
		free(ny), free(nx);
		return st;
	}
	for (int y = iy * r; y < (iy + ih) * r; y++)
		for (int x = ix * r; x < (ix + iw) * r; x++) {
			const float v = rx[(size_t)y * Lx + x];
			int peak = v > 0;
			for (int dy = -1; peak && dy <= 1; dy++)
				for (int dx = -1; peak && dx <= 1; dx++) {
					const int yy = y + dy, xx = x + dx;
					if ((dy || dx) && yy >= 0 && yy < Ly && xx >= 0 && xx < Lx && rx[(size_t)yy * Lx + xx] > v)
						peak = 0;
				}
			if (peak)
				bin(hist, v / norm * (ny[y] * nx[x]) * (ny[y] * nx[x]));
		}
	free(ny), free(nx);
	return C0_OK;
}

void c0_lambda_second(const double *hist, double lmax, struct c0_lambda_result *out)
{
	double np = 0;
	for (int k = 0; k < C0_LAMBDA_BINS; k++)
		np += hist[k];
	out->first_rel = out->chosen_rel, out->peaks = np;
	if (!(np > 0) || !(lmax > 0))
		return;
	out->second = 1;
	out->peak_rel = hmedian(hist) / lmax;
	out->noise_bound = KAPPA * out->noise_rel >= C0_LAMBDA_PEAK_SHARE * out->peak_rel;
	out->chosen_rel = fmax(C0_LAMBDA_PEAK_SHARE * out->peak_rel, KAPPA * out->noise_rel);
}

int c0_lambda_tile_max(const struct c0_support_conf *c, const struct c0_cov *all, double norm, int iy, int ix, int ih,
		       int iw, double lmax[2], double *hist)
{
	const int r = c->grid.srf, Lx = all->W * r;
	const size_t n = (size_t)all->W * all->H;
	struct c0_covop op;
	int st = c0_support_covop(c, all, &op);
	if (st)
		return st;
	double *C = c0_alloc(n * r * r, sizeof *C), trR;
	if (!C) {
		c0_covop_free(&op);
		return C0_ENOMEM;
	}
	/* as the tile's solve finds it (stages/support_solve.c) */
	c0_support_correlate(&op, all, norm, C, &trR, lmax);
	const double s0 = fmax(0, trR / (double)n);
	for (int y = iy * r; hist && y < (iy + ih) * r; y++)
		for (int x = ix * r; x < (ix + iw) * r; x++)
			bin(hist + 2 * C0_LAMBDA_BINS, C[(size_t)y * Lx + x] / norm - s0 * op.n[(size_t)y * Lx + x]);
	free(C);
	c0_covop_free(&op);
	return C0_OK;
}

int c0_lambda_tile_corr(const struct c0_support_conf *c, const struct c0_cov *half, double **C, double **n)
{
	const size_t L = (size_t)half->W * half->H * c->grid.srf * c->grid.srf;
	struct c0_covop op;
	*C = NULL;
	if (n)
		*n = NULL;
	int st = c0_support_covop(c, half, &op);
	if (st)
		return st;
	if ((*C = c0_alloc(L, sizeof **C)) && (!n || (*n = c0_alloc(L, sizeof **n)))) {
		c0_covop_adjoint(&op, half, half->r, *C);
		if (n)
			memcpy(*n, op.n, L * sizeof **n);
	} else {
		free(*C), *C = NULL;
		st = C0_ENOMEM;
	}
	c0_covop_free(&op);
	return st;
}

void c0_lambda_tile_noise(const struct c0_support_conf *c, const double *ca, const double *cb, const double *n, int W,
			  double norm, int iy, int ix, int ih, int iw, double *hist)
{
	const int r = c->grid.srf, Lx = W * r;
	for (int y = iy * r; y < (iy + ih) * r; y++)
		for (int x = ix * r; x < (ix + iw) * r; x++) {
			const size_t i = (size_t)y * Lx + x;
			bin(hist, fabs(ca[i] - cb[i]) / (2 * norm));
			bin(hist + C0_LAMBDA_BINS, n[i]);
		}
}

void c0_lambda_tiles_choose(const struct c0_support_conf *c, const double *hist, double lmax, double lmax0,
			    struct c0_lambda_result *out)
{
	memset(out, 0, sizeof *out);
	const double sig = noise_sd(hist);
	const double *h = hist + 2 * C0_LAMBDA_BINS;
	choose(c, sig, hquantile_above(h, KAPPA * sig, QUANT), hquantile_above(h, KAPPA * sig, 0.5), lmax, lmax0,
	       hmedian(hist + C0_LAMBDA_BINS), out);
	curve(hist + 2 * C0_LAMBDA_BINS, hist, lmax, out);
}
