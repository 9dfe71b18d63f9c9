#include "stages/drift.h"
#include "ops/fshift.h"
#include "io/frames.h"
#include "core/c0math.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/fftw_plan.h"
#include "core/mem.h"
#include "core/progress.h"

#include <complex.h>
#include <fftw3.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAXQ C0_DRIFT_MAX
#define REFINE 8      /* at most this many rounds of refinement against the mean of all blocks */
#define REFINE_TOL 0.01   /* ... until no block moves by more than this (pixels) in a round */
#define SIGNIF 6   /* an axis is corrected when its drift exceeds this many noise sds */

struct hook {
	struct c0_drift *d;
	int q;
};

struct c0_drift {
	int nq, nb, block, H, W, interleaved;
	double sigma;                        /* the PSF's sd (pixels): the correlations' filter */
	int64_t frames[MAXQ];                /* per stack */
	double start[MAXQ];                  /* per stack: its first frame on the acquisition's clock */
	int rec[MAXQ], k0[MAXQ + 1];         /* stacks in recording order; the i-th's blocks k0[i]..k0[i+1]-1 */
	double *bt, *bx, *by;
	float **bm;                          /* block means, while estimating */
	double noise_px[2];                  /* sd of a block's shift estimate, per axis */
	int off[2];                          /* axis not corrected: its drift is within the noise */
	double max_px, seconds;
	struct hook hooks[MAXQ];
	struct c0_fshift *sh;
};

void c0_drift_free(struct c0_drift *d)
{
	if (!d)
		return;
	for (int k = 0; d->bm && k < d->nb; k++)
		free(d->bm[k]);
	free(d->bm);
	free(d->bt), free(d->bx), free(d->by);
	c0_fshift_free(d->sh);
	free(d);
}

/* The correlation set-up: the reference block's spectrum, and the window
 * that keeps the image edges from correlating. The images are zero-padded
 * to PH x PW, enough for the lags up to LY, LX to be those of the linear
 * correlation: a drift beyond a quarter of the field is refused anyway, and
 * padding to twice the image would cost 2.5x the transforms. */
struct xcorr {
	int H, W, PH, PW, LY, LX;
	size_t ns;               /* spectrum length */
	double *win, *re;
	double *lp;              /* the PSF's transfer function on the spectrum (NULL: none) */
	fftw_complex *ref, *sp, *xs;   /* reference, image and cross spectra */
	fftw_plan f, b;
	int borrowed;            /* win, lp and ref are another xcorr's */
};

static void xcorr_free(struct xcorr *x)
{
	c0_fftw_destroy(x->f), c0_fftw_destroy(x->b);
	if (!x->borrowed)
		free(x->win), free(x->lp), fftw_free(x->ref);
	fftw_free(x->re), fftw_free(x->sp), fftw_free(x->xs);
}

/* the transforms' buffers and plans; the window and reference are x's own
 * (share == NULL) or share's */
static int xcorr_buffers(struct xcorr *x, const struct xcorr *share)
{
	x->re = fftw_malloc((size_t)x->PH * x->PW * sizeof(double));
	x->sp = fftw_malloc(x->ns * sizeof(fftw_complex));
	x->xs = fftw_malloc(x->ns * sizeof(fftw_complex));
	if (share)
		x->win = share->win, x->lp = share->lp, x->ref = share->ref, x->borrowed = 1;
	else {
		x->win = c0_alloc((size_t)x->H * x->W, sizeof *x->win);
		x->ref = fftw_malloc(x->ns * sizeof(fftw_complex));
	}
	if (!x->win || !x->re || !x->ref || !x->sp || !x->xs)
		return c0_mem_fail((double)x->PH * x->PW * sizeof(double) + 3.0 * x->ns * sizeof(fftw_complex));
#pragma omp critical(c0_fftw_plan)
	{
		x->f = fftw_plan_dft_r2c_2d(x->PH, x->PW, x->re, x->sp, FFTW_ESTIMATE);
		x->b = fftw_plan_dft_c2r_2d(x->PH, x->PW, x->xs, x->re, FFTW_ESTIMATE);
	}
	if (!x->f || !x->b)
		return c0_fail(C0_ENOMEM, "drift: cannot plan the FFTs of %dx%d", x->W, x->H);
	return C0_OK;
}

/* The PSF's transfer function (a Gaussian of sd sigma pixels) on the
 * r2c spectrum: the image and the reference both filtered, the matched
 * filter for an image of PSF-blurred spots in white noise. The camera's
 * fixed pattern is white too, and does not move with the sample: unfiltered,
 * its own peak at lag 0 pulled the shift towards 0. */
static int xcorr_lowpass(struct xcorr *x, double sigma)
{
	if (!(sigma > 0))
		return C0_OK;
	const int nx = x->PW / 2 + 1;
	if (!(x->lp = c0_alloc(x->ns, sizeof *x->lp)))
		return C0_ENOMEM;
	const double c = -2 * C0_PI * C0_PI * sigma * sigma;
	for (int y = 0; y < x->PH; y++) {
		const double fy = (double)(y <= x->PH / 2 ? y : y - x->PH) / x->PH;
		for (int i = 0; i < nx; i++) {
			const double fx = (double)i / x->PW;
			x->lp[(size_t)y * nx + i] = exp(c * (fx * fx + fy * fy));
		}
	}
	return C0_OK;
}

static int xcorr_init(struct xcorr *x, int H, int W, double sigma)
{
	memset(x, 0, sizeof *x);
	/* lags to a quarter of the field, and one more for the sub-pixel fit */
	x->H = H, x->W = W, x->LY = H / 4 + 2, x->LX = W / 4 + 2;
	x->PH = c0_fft_size(H + x->LY, 5, 0), x->PW = c0_fft_size(W + x->LX, 5, 0);
	x->ns = (size_t)x->PH * (x->PW / 2 + 1);
	int st = xcorr_buffers(x, NULL);
	if (st)
		return st;
	for (int y = 0; y < H; y++)
		for (int i = 0; i < W; i++)   /* Hann */
			x->win[(size_t)y * W + i] = (0.5 - 0.5 * cos(2 * C0_PI * (y + 0.5) / H)) *
						    (0.5 - 0.5 * cos(2 * C0_PI * (i + 0.5) / W));
	return xcorr_lowpass(x, sigma);
}

/* another thread's set-up against the same reference */
static int xcorr_clone(struct xcorr *y, const struct xcorr *x)
{
	*y = *x;
	y->re = NULL, y->sp = y->xs = NULL, y->f = y->b = NULL;
	return xcorr_buffers(y, x);
}

/* windowed, mean-removed spectrum of img into x->sp */
static void spectrum(struct xcorr *x, const double *img)
{
	const size_t n = (size_t)x->H * x->W;
	double m = 0, w = 0;
	for (size_t i = 0; i < n; i++)
		m += img[i] * x->win[i], w += x->win[i];
	m /= w;
	memset(x->re, 0, (size_t)x->PH * x->PW * sizeof *x->re);
	for (int y = 0; y < x->H; y++)
		for (int i = 0; i < x->W; i++) {
			size_t k = (size_t)y * x->W + i;
			x->re[(size_t)y * x->PW + i] = (img[k] - m) * x->win[k];
		}
	fftw_execute(x->f);
	for (size_t i = 0; x->lp && i < x->ns; i++)
		x->sp[i] *= x->lp[i];
}

/* sub-pixel peak offset from three samples: Gaussian (log-parabola) when all
 * positive, else parabola */
static double peak3(double a, double b, double c)
{
	if (a > 0 && b > 0 && c > 0) {
		double la = log(a), lb = log(b), lc = log(c), den = la - 2 * lb + lc;
		if (den < 0)
			return 0.5 * (la - lc) / den;
	}
	double den = a - 2 * b + c;
	return den < 0 ? 0.5 * (a - c) / den : 0;
}

/* shift (px) of the content of img relative to the reference; img's
 * spectrum is left in x->sp. in_ref: the reference is a sum that holds img,
 * which is left out of it (spectra are linear), else img's own noise peaks
 * at lag 0 and pulls the shift towards 0 */
static void shift_of(struct xcorr *x, const double *img, int in_ref, double *dx, double *dy)
{
	const int H = x->PH, W = x->PW;
	spectrum(x, img);
	for (size_t i = 0; i < x->ns; i++)
		x->xs[i] = x->sp[i] * conj(in_ref ? x->ref[i] - x->sp[i] : x->ref[i]);
	fftw_execute(x->b);   /* x->re: circular cross-correlation, lag (0, 0) at index 0 */
	int by = 0, bx = 0;
	double best = -INFINITY;
	for (int ly = 1 - x->LY; ly < x->LY; ly++)   /* the lags free of wrap-around, but the last */
		for (int lx = 1 - x->LX; lx < x->LX; lx++) {
			double v = x->re[(size_t)(ly < 0 ? ly + H : ly) * W + (lx < 0 ? lx + W : lx)];
			if (v > best)
				best = v, by = ly, bx = lx;
		}
#define AT(ly, lx) x->re[(size_t)(((ly) % H + H) % H) * W + (((lx) % W + W) % W)]
	*dx = bx + peak3(AT(by, bx - 1), AT(by, bx), AT(by, bx + 1));
	*dy = by + peak3(AT(by - 1, bx), AT(by, bx), AT(by + 1, bx));
#undef AT
}

/* block k moved back by its shift, into tmp */
static int moved_back(struct c0_drift *d, int k, float *tmp)
{
	memcpy(tmp, d->bm[k], (size_t)d->H * d->W * sizeof *tmp);
	return c0_fshift_apply(d->sh, tmp, d->bx[k], d->by[k]);
}

/* block k moved back, re-measured against x->ref */
static int remeasure(struct c0_drift *d, struct xcorr *x, double *img, float *tmp, int k)
{
	const size_t n = (size_t)d->H * d->W;
	int st = moved_back(d, k, tmp);
	for (size_t i = 0; i < n; i++)
		img[i] = tmp[i];
	double rx, ry;
	shift_of(x, img, 1, &rx, &ry);
	d->bx[k] += rx, d->by[k] += ry;
	return st;
}

/* The first estimates correlate each block with the first, one noisy block
 * mean. Refined: the reference becomes the mean of all blocks moved back by
 * their shifts, and each block is re-measured after its own shift has been
 * undone, so that the sub-pixel fit works near zero where it is unbiased.
 * The trajectory stays relative to the first block.
 * Rounds on blocks k0..k1-1 until they stop moving (each round takes a part
 * of what is left: 2 rounds left a dim stack's drift 30 % short); par: the
 * blocks are re-measured side by side (one stack: the threads are not taken
 * by the stacks), each thread but the first with transforms of its own */
static int refine_range(struct c0_drift *d, struct xcorr *x, double *ref, float *tmp, int k0, int k1, int par)
{
	const size_t n = (size_t)d->H * d->W;
	int st = C0_OK;
	double moved = INFINITY;
	for (int round = 0; round < REFINE && moved > REFINE_TOL && k1 - k0 > 1 && !st; round++) {
		moved = 0;
		memset(ref, 0, n * sizeof *ref);
		for (int k = k0; k < k1 && !st; k++) {
			st = moved_back(d, k, tmp);
			for (size_t i = 0; i < n; i++)
				ref[i] += tmp[i];
		}
		if (st)
			break;
		spectrum(x, ref);
		memcpy(x->ref, x->sp, x->ns * sizeof *x->ref);
		struct c0_first_fail fail = { 0 };
#pragma omp parallel if (par)
		{
			struct xcorr own, *y = x;
			double *img = ref;
			float *t = tmp;
			int ts = C0_OK;
			if (omp_get_thread_num() > 0) {
				y = &own, ts = xcorr_clone(&own, x);
				img = c0_alloc(n, sizeof *img), t = c0_alloc(n, sizeof *t);
				if (!ts && (!img || !t))
					ts = C0_ENOMEM;
			}
#pragma omp for schedule(dynamic, 1) reduction(max : moved)
			for (int k = k0; k < k1; k++) {
				const double x0 = d->bx[k], y0 = d->by[k];
				if (!ts)
					ts = remeasure(d, y, img, t, k);
				moved = fmax(moved, fmax(fabs(d->bx[k] - x0), fabs(d->by[k] - y0)));
			}
			c0_first_fail_note(&fail, ts);
			if (y != x)
				xcorr_free(&own), free(img), free(t);
		}
		if (fail.code)
			st = c0_first_fail_raise(&fail);
	}
	return st;
}

/* mean time and value of blocks k0..k1-1 of v, and their centred sums */
static void block_moments(const double *bt, const double *v, int k0, int k1, double *mt, double *mv, double *stt, double *stv)
{
	const int n = k1 - k0;
	*mt = *mv = 0;
	for (int k = k0; k < k1; k++)
		*mt += bt[k] / n, *mv += v[k] / n;
	for (int k = k0; k < k1; k++)
		*stt += (bt[k] - *mt) * (bt[k] - *mt), *stv += (bt[k] - *mt) * (v[k] - *mv);
}

/* The stacks' levels, by continuity. Refined against its own mean, a
 * stack keeps the mean level of its chained first estimates, and those
 * shrink the small block-to-block shifts (the sub-pixel fit of a noisy
 * peak): each stack sat short by part of its own drift, and the shortfall
 * added up over the angles (5 x 500 frames, 200 nm: 64 nm short at the
 * last). Each stack is moved onto the line through the stack before: one
 * slope fitted to both stacks' blocks, each stack at its own level (a
 * stack alone may have only a few blocks). */
static void join_stacks(struct c0_drift *d, const int *k0, double *jv)
{
	for (int k = 0; k < k0[1]; k++)
		jv[k] = 0;
	for (int q = 1; q < d->nq; q++) {
		double v0 = k0[q] > 0 ? jv[k0[q] - 1] : 0, add = 0;
		if (k0[q] > k0[q - 1] && k0[q + 1] > k0[q])
			for (int a = 0; a < 2; a++) {
				double *v = a ? d->by : d->bx, pt, pv, t, m, stt = 0, stv = 0;
				block_moments(d->bt, v, k0[q - 1], k0[q], &pt, &pv, &stt, &stv);
				block_moments(d->bt, v, k0[q], k0[q + 1], &t, &m, &stt, &stv);
				const double slope = stt > 0 ? stv / stt : 0, dv = pv + slope * (t - pt) - m;
				for (int k = k0[q]; k < k0[q + 1]; k++)
					v[k] += dv;
				/* the join's variance in units of a block's: the two
				 * levels' and the slope's over the stacks' distance */
				add = 1.0 / (k0[q] - k0[q - 1]) + 1.0 / (k0[q + 1] - k0[q]) + (stt > 0 ? (t - pt) * (t - pt) / stt : 0);
			}
		for (int k = k0[q]; k < k0[q + 1]; k++)
			jv[k] = v0 + add;
	}
}

/* Interleaved stacks share one clock: their blocks k were recorded
 * together, so the trajectory is the stacks' mean, each stack at its own
 * mean level (its blocks are only known relative to each other; a
 * correlation across angles would read their different images as a
 * shift). The block means are no longer needed (same counts: checked). */
static void average_stacks(struct c0_drift *d)
{
	const int nq = d->nq, nb = d->k0[1];
	for (int k = 0; k < d->nb; k++)
		free(d->bm[k]), d->bm[k] = NULL;
	double lx[MAXQ], ly[MAXQ];
	for (int i = 0; i < nq; i++) {
		lx[i] = ly[i] = 0;
		for (int k = d->k0[i]; k < d->k0[i + 1]; k++)
			lx[i] += d->bx[k] / nb, ly[i] += d->by[k] / nb;
	}
	for (int k = 0; k < nb; k++) {
		double t = 0, x = 0, y = 0;
		for (int i = 0; i < nq; i++) {
			const int j = d->k0[i] + k;
			t += d->bt[j] / nq, x += (d->bx[j] - lx[i]) / nq, y += (d->by[j] - ly[i]) / nq;
		}
		d->bt[k] = t, d->bx[k] = x, d->by[k] = y;   /* k <= j: read before written */
	}
	d->nb = nb;
}

static int refine(struct c0_drift *d)
{
	/* each stack against the mean of its own blocks: an angle changes the
	 * image (depth-dependent excitation), which a correlation across angles
	 * would read as a shift. The stacks' blocks are apart: side by side. */
	const int *k0 = d->k0;
	struct c0_first_fail fail = { 0 };
	const size_t n = (size_t)d->H * d->W;
#pragma omp parallel if (d->nq > 1)
	{
		struct xcorr x;
		double *ref = c0_alloc(n, sizeof *ref);
		float *tmp = c0_alloc(n, sizeof *tmp);
		int st = xcorr_init(&x, d->H, d->W, d->sigma);
		if (!st && (!ref || !tmp))
			st = C0_ENOMEM;
#pragma omp for schedule(dynamic, 1)
		for (int q = 0; q < d->nq; q++)
			if (!st)
				st = refine_range(d, &x, ref, tmp, k0[q], k0[q + 1], d->nq == 1);
		c0_first_fail_note(&fail, st);
		xcorr_free(&x);
		free(ref), free(tmp);
	}
	if (fail.code)
		return c0_first_fail_raise(&fail);
	if (d->interleaved)
		average_stacks(d);
	double *jv = c0_alloc((size_t)d->nb, sizeof *jv);
	if (!jv)
		return C0_ENOMEM;
	if (!d->interleaved)
		join_stacks(d, k0, jv);
	for (int k = d->nb - 1; k >= 0; k--)
		d->bx[k] -= d->bx[0], d->by[k] -= d->by[0];
	/* an axis whose shifts stay within SIGNIF noise sds of zero has no
	 * drift we can tell from the estimates' own noise: undoing it would
	 * only add jitter. The noise sd comes from second differences, which a
	 * smooth drift does not feed (var of a second difference = 6 var); a
	 * block in a later stack also carries the joins' noise (jv). */
	for (int a = 0; a < 2 && d->nb >= 3; a++) {
		double *v = a ? d->by : d->bx, s2 = 0, mx = 0;
		for (int k = 1; k + 1 < d->nb; k++)
			s2 += pow(v[k + 1] - 2 * v[k] + v[k - 1], 2);
		for (int k = 0; k < d->nb; k++)
			mx = fmax(mx, fabs(v[k]) / sqrt(1 + jv[k]));
		d->noise_px[a] = sqrt(s2 / (d->nb - 2) / 6);
		if (mx <= SIGNIF * d->noise_px[a])
			memset(v, 0, (size_t)d->nb * sizeof *v), d->off[a] = 1;
	}
	free(jv);
	d->max_px = 0;
	for (int k = 0; k < d->nb; k++)
		d->max_px = fmax(d->max_px, hypot(d->bx[k], d->by[k]));
	return C0_OK;
}

/* One stack's block means, and each block's shift against the block before
 * (chained, so that a large total drift is followed in small steps). */
struct stack_blocks {
	int64_t B, nb;         /* block length, blocks */
	float **bm;            /* nb block means */
	double *sx, *sy;       /* shift of block k against block k - 1 (k >= 1) */
	char msg[256];
};

/* frames read ahead while the ones before are summed: up to this many bytes a batch */
#define READ_AHEAD (32 << 20)

/* Frames t0..t1-1 (in f) added to the block means; a block's mean, once
 * complete, is kept and measured against the block before. */
static int add_frames(struct stack_blocks *o, struct xcorr *x, double *sum, const float *f, int64_t t0, int64_t t1,
		      int64_t T, size_t n, struct c0_progress *pr)
{
	for (int64_t t = t0; t < t1; t++, f += n) {
		const int64_t k = t / o->B < o->nb ? t / o->B : o->nb - 1;
		const int64_t b1 = k * o->B, b2 = k == o->nb - 1 ? T : b1 + o->B;   /* the last block takes the remainder */
		if (t == b1)
			memset(sum, 0, n * sizeof *sum);
		for (size_t i = 0; i < n; i++)
			sum[i] += f[i];
		c0_progress_update(pr, (double)t + 1);
		if (t + 1 < b2)
			continue;
		for (size_t i = 0; i < n; i++)
			sum[i] /= (double)(b2 - b1);
		if (!(o->bm[k] = c0_alloc(n, sizeof(float))))
			return C0_ENOMEM;
		for (size_t i = 0; i < n; i++)
			o->bm[k][i] = (float)sum[i];
		if (k > 0)
			shift_of(x, sum, 0, &o->sx[k], &o->sy[k]);
		else
			spectrum(x, sum);
		memcpy(x->ref, x->sp, x->ns * sizeof *x->ref);
	}
	return C0_OK;
}

static int stack_pass(struct c0_frames *r, int64_t B, double sigma, struct stack_blocks *o)
{
	const int H = r->height, W = r->width;
	const size_t n = (size_t)H * W;
	const int64_t T = r->count, nb = T / B;
	int64_t nf = READ_AHEAD / (int64_t)(n * sizeof(float));
	nf = nf < 1 ? 1 : nf > T ? T : nf;
	const int64_t nbatch = (T + nf - 1) / nf;
	struct xcorr x;
	int st = xcorr_init(&x, H, W, sigma), rst = C0_OK;
	double *sum = c0_alloc(n, sizeof *sum);
	float *buf = c0_alloc(2 * (size_t)nf * n, sizeof *buf);
	o->B = B, o->nb = nb;
	o->bm = c0_alloc((size_t)nb, sizeof *o->bm);
	o->sx = c0_alloc((size_t)nb, sizeof *o->sx);
	o->sy = c0_alloc((size_t)nb, sizeof *o->sy);
	if (!st && (!sum || !buf || !o->bm || !o->sx || !o->sy))
		st = C0_ENOMEM;   /* c0_alloc said which */
	struct c0_progress pr;
	c0_progress_begin(&pr, "drift", (double)T);
	/* One thread reads batch i while another adds batch i - 1 (reading and
	 * adding took about as long each): when this stack is the only one,
	 * else its thread is one of the stacks'. Each status is written by one
	 * thread and read by the other between the barriers. */
	struct c0_first_fail fail = { 0 };
#pragma omp parallel num_threads(2) if (!omp_in_parallel() && omp_get_max_threads() > 1 && nbatch > 1 && !st)
	{
		const int id = omp_get_thread_num(), nt = omp_get_num_threads();
		for (int64_t i = 0; i <= nbatch; i++) {
			const int halt = st || rst;
#pragma omp barrier
			if (halt)
				continue;
			if (id == 0 && i < nbatch) {
				float *f = buf + (size_t)(i % 2) * nf * n;
				for (int64_t t = i * nf; t < (i + 1) * nf && t < T && !rst; t++, f += n)
					rst = c0_frames_read(r, t, f);
				c0_first_fail_note(&fail, rst);
			}
			if (id == nt - 1 && i > 0) {
				const int64_t t0 = (i - 1) * nf, t1 = i * nf < T ? i * nf : T;
				st = add_frames(o, &x, sum, buf + (size_t)((i - 1) % 2) * nf * n, t0, t1, T, n, &pr);
				c0_first_fail_note(&fail, st);
			}
#pragma omp barrier
		}
	}
	if (fail.code)    /* the message, from the thread that failed */
		st = c0_first_fail_raise(&fail);
	c0_progress_end(&pr);
	xcorr_free(&x);
	free(sum), free(buf);
	if (st)
		snprintf(o->msg, sizeof o->msg, "%s", c0_errmsg());
	return st;
}

static void stack_blocks_free(struct stack_blocks *o)
{
	for (int64_t k = 0; o->bm && k < o->nb; k++)
		free(o->bm[k]);
	free(o->bm), free(o->sx), free(o->sy);
}

/* a stack's block length: c->block frames, fewer when the stack has < 2 */
static int64_t block_len(const struct c0_drift_conf *c, int64_t T)
{
	return T >= 2 * c->block ? c->block : T / 2;
}

/* the stacks' sizes: the same field, each long enough for two blocks */
static int check_stacks(const struct c0_drift_conf *c, const struct c0_frames *f, int n)
{
	if (n < 1 || n > MAXQ)
		return c0_fail(C0_EINVAL, "drift: %d stacks (1..%d)", n, MAXQ);
	if (c->block < 1)
		return c0_fail(C0_EINVAL, "drift block %d: must be >= 1 frame", c->block);
	int st = C0_OK;
	for (int q = 0; q < n && !st; q++) {
		const int64_t T = f[q].count;
		if (f[q].height != f[0].height || f[q].width != f[0].width)
			st = c0_fail(C0_EINVAL, "%s: %dx%d pixels differs from %s", f[q].name, f[q].width, f[q].height, f[0].name);
		/* blocks: c->block frames, fewer when the stack has < 2 blocks */
		else if (block_len(c, T) < 5)
			st = c0_fail(C0_EINVAL, "%s: %lld frames is too short to estimate drift (needs >= 10; switch "
				     "drift correction off)", f[q].name, (long long)T);
		else if (c->interleaved && T / block_len(c, T) != f[0].count / block_len(c, f[0].count))
			st = c0_fail(C0_EINVAL, "%s: %lld frames, %s %lld: interleaved stacks (frame t of each recorded in turn) "
				     "need about as many frames each", f[q].name, (long long)T, f[0].name, (long long)f[0].count);
		else if (c->nstart && !isfinite(c->start[q]))
			st = c0_fail(C0_EINVAL, "drift: stack %d's start on the acquisition clock is not a number", q + 1);
	}
	if (!st && c->nstart && c->nstart != n)
		st = c0_fail(C0_EINVAL, "drift: %d start times for %d stacks", c->nstart, n);
	return st;
}

/* The stacks' clock (c->start, else one after another as given) and their
 * recording order (by start; ties in the given order). */
static void clock(const struct c0_drift_conf *c, const struct c0_frames *f, struct c0_drift *d)
{
	double u = 0;
	for (int q = 0; q < d->nq; q++) {
		d->start[q] = c->nstart ? c->start[q] : u, u += (double)f[q].count;
		int i = q;
		for (; i > 0 && d->start[d->rec[i - 1]] > d->start[q]; i--)
			d->rec[i] = d->rec[i - 1];
		d->rec[i] = q;
	}
}

/* the stacks' block means and chained shifts, the stacks side by side: each
 * reads its own file; the first failing stack's message */
static int read_stacks(const struct c0_drift_conf *c, struct c0_frames *f, int n, struct stack_blocks *sb)
{
	int fail = -1;
#pragma omp parallel for schedule(dynamic, 1) if (n > 1)
	for (int q = 0; q < n; q++) {
		if (stack_pass(&f[q], block_len(c, f[q].count), c->psf_sigma_px, &sb[q]))
#pragma omp critical(c0_drift_fail)
			if (fail < 0 || q < fail)
				fail = q;
	}
	return fail >= 0 ? c0_fail(C0_EIO, "%s", sb[fail].msg) : C0_OK;
}

/* The trajectory, stack after stack: the blocks' shifts chained within a
 * stack and continued across stacks; the block means move into d. */
static int chain(struct c0_drift *d, const struct c0_frames *f, int n, struct stack_blocks *sb)
{
	const int H = d->H, W = d->W;
	int64_t nball = 0;
	for (int q = 0; q < n; q++)
		nball += sb[q].nb;
	if (!(d->bt = c0_alloc((size_t)nball, sizeof *d->bt)) || !(d->bx = c0_alloc((size_t)nball, sizeof *d->bx)) ||
	    !(d->by = c0_alloc((size_t)nball, sizeof *d->by)) || !(d->bm = c0_alloc((size_t)nball, sizeof *d->bm)))
		return C0_ENOMEM;
	int prev0 = 0;
	for (int r = 0; r < n; r++) {
		const int q = d->rec[r], this0 = d->nb;   /* this stack's first block */
		const int64_t T = f[q].count, B = sb[q].B;
		const double g = d->start[q];
		d->k0[r] = this0;
		for (int64_t k = 0; k < sb[q].nb; k++) {
			int64_t t1 = k * B, t2 = k == sb[q].nb - 1 ? T : t1 + B;
			double bx = 0, by = 0;
			if (d->nb > this0) {
				bx = sb[q].sx[k], by = sb[q].sy[k];
				bx += d->bx[d->nb - 1], by += d->by[d->nb - 1];
			} else if (d->nb > 0 && !d->interleaved) {
				/* a new stack (another angle): continue the trajectory at
				 * the previous stack's mean rate (first to last block)
				 * rather than correlate across angles */
				const int j = d->nb - 1, i = prev0;
				double u = j > i ? (g + 0.5 * (double)(t2 - 1) - d->bt[j]) / (d->bt[j] - d->bt[i]) : 0;
				bx = d->bx[j] + u * (d->bx[j] - d->bx[i]);
				by = d->by[j] + u * (d->by[j] - d->by[i]);
			}
			if (fabs(bx) > W / 4.0 || fabs(by) > H / 4.0)
				return c0_fail(C0_EINVAL, "%s: the drift at frames %lld-%lld (%.1f, %.1f pixels) exceeds a quarter "
					       "of the field; correct it beforehand or switch drift correction off",
					       f[q].name, (long long)t1 + 1, (long long)t2, bx, by);
			d->bm[d->nb] = sb[q].bm[k], sb[q].bm[k] = NULL;
			d->bt[d->nb] = g + 0.5 * (double)(t1 + t2 - 1);
			d->bx[d->nb] = bx, d->by[d->nb] = by;
			d->max_px = fmax(d->max_px, hypot(bx, by));
			d->nb++;
		}
		prev0 = this0;
		d->frames[q] = T;
		d->hooks[q].d = d, d->hooks[q].q = q;
	}
	d->k0[n] = d->nb;
	return C0_OK;
}

int c0_drift_estimate(const struct c0_drift_conf *c, struct c0_frames *f, int n, struct c0_drift **out)
{
	double t0 = c0_now();
	*out = NULL;
	int st = check_stacks(c, f, n);
	if (st)
		return st;
	struct c0_drift *d = c0_alloc(1, sizeof *d);
	struct stack_blocks *sb = c0_alloc((size_t)n, sizeof *sb);
	if (!d || !sb) {
		free(d), free(sb);
		return C0_ENOMEM;
	}
	d->nq = n, d->H = f[0].height, d->W = f[0].width, d->interleaved = c->interleaved, d->sigma = c->psf_sigma_px;
	clock(c, f, d);
	st = read_stacks(c, f, n, sb);
	d->block = (int)sb[0].B;
	if (!st)
		st = chain(d, f, n, sb);
	for (int q = 0; q < n; q++)
		stack_blocks_free(&sb[q]);
	free(sb);
	if (!st)
		st = c0_fshift_new(d->H, d->W, &d->sh);
	if (!st)
		st = refine(d);
	for (int k = 0; d->bm && k < d->nb; k++)
		free(d->bm[k]);
	free(d->bm), d->bm = NULL;
	c0_mem_release();     /* the block means: 16 MB each at 2048x2048 */
	d->seconds = c0_now() - t0;
	if (st) {
		c0_drift_free(d);
		return st;
	}
	*out = d;
	return C0_OK;
}

void c0_drift_at(const struct c0_drift *d, int q, int64_t t, double *dx, double *dy)
{
	const double tg = d->start[q] + (double)t;
	if (d->nb < 2) {
		*dx = d->nb ? d->bx[0] : 0, *dy = d->nb ? d->by[0] : 0;
		return;
	}
	int k = 0;   /* segment [k, k + 1], the end ones extended */
	while (k < d->nb - 2 && tg > d->bt[k + 1])
		k++;
	double u = (tg - d->bt[k]) / (d->bt[k + 1] - d->bt[k]);
	*dx = d->bx[k] + u * (d->bx[k + 1] - d->bx[k]);
	*dy = d->by[k] + u * (d->by[k + 1] - d->by[k]);
}

/* fn(dx, dy, w, ctx) for each run of stack q's frames at one shift (to 1/8
 * pixel), w the run's share of the stack's frames */
typedef int (*run_fn)(const struct c0_drift *d, double dx, double dy, double w, void *ctx);
static int each_run(const struct c0_drift *d, int q, run_fn fn, void *ctx)
{
	const int64_t T = d->frames[q];
	int st = C0_OK;
	for (int64_t t = 0, u; !st && t < T; t = u) {
		double dx, dy, ex, ey;
		c0_drift_at(d, q, t, &dx, &dy);
		dx = round(8 * dx) / 8, dy = round(8 * dy) / 8;
		for (u = t + 1; u < T; u++) {
			c0_drift_at(d, q, u, &ex, &ey);
			if (round(8 * ex) / 8 != dx || round(8 * ey) / 8 != dy)
				break;
		}
		st = fn(d, dx, dy, (double)(u - t) / (double)T, ctx);
	}
	return st;
}

struct moved { const float *in; double *acc; float *tmp; };

static int add_variance(const struct c0_drift *d, double dx, double dy, double w, void *ctx)
{
	const struct moved *m = ctx;
	return c0_fshift_variance(d->H, d->W, m->in, dx, dy, w, m->acc);
}

static int add_image(const struct c0_drift *d, double dx, double dy, double w, void *ctx)
{
	const struct moved *m = ctx;
	const size_t n = (size_t)d->H * d->W;
	memcpy(m->tmp, m->in, n * sizeof *m->tmp);
	int st = c0_fshift_apply(d->sh, m->tmp, dx, dy);
	for (size_t i = 0; !st && i < n; i++)
		m->acc[i] += w * m->tmp[i];
	return st;
}

static int moved(const struct c0_drift *d, int q, const float *in, run_fn fn, float *out)
{
	const size_t n = (size_t)d->H * d->W;
	struct moved m = { in, c0_alloc(n, sizeof *m.acc), c0_alloc(n, sizeof *m.tmp) };   /* tmp: add_image's */
	int st = m.acc && m.tmp ? each_run(d, q, fn, &m) : C0_ENOMEM;
	for (size_t i = 0; !st && i < n; i++)
		out[i] = (float)m.acc[i];
	free(m.acc), free(m.tmp);
	return st;
}

int c0_drift_variance(const struct c0_drift *d, int q, const float *var, float *out)
{
	return moved(d, q, var, add_variance, out);
}

int c0_drift_image(const struct c0_drift *d, int q, const float *img, float *out)
{
	return moved(d, q, img, add_image, out);
}

int c0_drift_unmove(const struct c0_drift *d, int q, float *img)
{
	double mx = 0, my = 0, dx, dy;
	for (int64_t t = 0; t < d->frames[q]; t++)
		c0_drift_at(d, q, t, &dx, &dy), mx += dx, my += dy;
	return c0_fshift_apply(d->sh, img, -mx / (double)d->frames[q], -my / (double)d->frames[q]);
}

void *c0_drift_hook(struct c0_drift *d, int q) { return &d->hooks[q]; }

int c0_drift_frame_fn(void *ctx, int64_t t, float *frame, int H, int W)
{
	const struct hook *h = ctx;
	if (H != h->d->H || W != h->d->W)
		return c0_fail(C0_EINVAL, "drift: a %dx%d frame for a %dx%d trajectory", W, H, h->d->W, h->d->H);
	double dx, dy;
	c0_drift_at(h->d, h->q, t, &dx, &dy);
	return c0_fshift_apply(h->d->sh, frame, dx, dy);
}

void c0_drift_get_info(const struct c0_drift *d, struct c0_drift_info *o)
{
	o->stacks = d->nq, o->blocks = d->nb, o->block = d->block;
	o->frames = 0;
	for (int q = 0; q < d->nq; q++)
		o->frames = fmax(o->frames, d->start[q] + (double)d->frames[q]);
	o->stack_frames = d->frames, o->start = d->start;
	o->bt = d->bt, o->bx = d->bx, o->by = d->by;
	o->max_px = d->max_px, o->seconds = d->seconds;
	o->noise_px[0] = d->noise_px[0], o->noise_px[1] = d->noise_px[1];
	o->corrected[0] = !d->off[0], o->corrected[1] = !d->off[1];
}
