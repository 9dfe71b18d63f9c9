/* The drift's refinement (drift_parts.h). */
#include "stages/drift_parts.h"
#include "core/err.h"
#include "core/threads.h"
#include "core/mem.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define REFINE 8      /* at most this many rounds of refinement against the mean of all blocks */
#define REFINE_TOL 0.01   /* ... until no block moves by more than this (pixels) in a round */
#define SIGNIF 6   /* an axis is corrected when its drift exceeds this many noise sds */

/* block k moved back by its shift, into out */
static int moved_back(struct c0_drift *d, int k, float *out)
{
	memcpy(out, d->bm[k], (size_t)d->H * d->W * sizeof *out);
	return c0_fshift_apply(d->sh, out, d->bx[k], d->by[k]);
}

/* block k, moved back (in moved), re-measured against x->ref */
static void remeasure(struct c0_drift *d, struct xcorr *x, double *img, const float *moved, int k)
{
	const size_t n = (size_t)d->H * d->W;
	for (size_t i = 0; i < n; i++)
		img[i] = moved[i];
	double rx, ry;
	drift_shift_of(x, img, 1, &rx, &ry);
	d->bx[k] += rx, d->by[k] += ry;
}

/* The first estimates correlate each block with the first, one noisy block
 * mean. Refined: the reference becomes the mean of all blocks moved back by
 * their shifts, and each block is re-measured after its own shift has been
 * undone, so that the sub-pixel fit works near zero where it is unbiased.
 * The trajectory stays relative to the first block.
 * Rounds on blocks k0..k1-1 until they stop moving (each round takes a part
 * of what is left: 2 rounds left a dim stack's drift 30 % short); par: the
 * blocks are moved back and re-measured side by side (one stack: the threads
 * are not taken by the stacks), each thread but the first with transforms of
 * its own */
static int refine_range(struct c0_drift *d, struct xcorr *x, double *ref, int k0, int k1, int par)
{
	const size_t n = (size_t)d->H * d->W;
	if (k1 - k0 < 2)
		return C0_OK;
	/* the round's moved blocks, for the reference and then their re-measure:
	 * one Fourier shift a block a round (as much memory as the stack's block
	 * means) */
	float *mv = c0_alloc((size_t)(k1 - k0) * n, sizeof *mv);
	int st = mv ? C0_OK : C0_ENOMEM;
	double moved = INFINITY;
	for (int round = 0; round < REFINE && moved > REFINE_TOL && !st; round++) {
		moved = 0;
		struct c0_first_fail fail = { 0 };
#pragma omp parallel for schedule(dynamic, 1) if (par)
		for (int k = k0; k < k1; k++)
			c0_first_fail_note(&fail, moved_back(d, k, mv + (size_t)(k - k0) * n));
		if (fail.code) {
			st = c0_first_fail_raise(&fail);
			break;
		}
		memset(ref, 0, n * sizeof *ref);
		for (int k = k0; k < k1; k++) {   /* the blocks added in order: the same sums on any threads */
			const float *m = mv + (size_t)(k - k0) * n;
			for (size_t i = 0; i < n; i++)
				ref[i] += m[i];
		}
		drift_spectrum(x, ref);
		memcpy(x->ref, x->sp, x->ns * sizeof *x->ref);
#pragma omp parallel if (par)
		{
			struct xcorr own, *y = x;
			double *img = ref;
			int ts = C0_OK;
			if (omp_get_thread_num() > 0) {
				y = &own, ts = drift_xcorr_clone(&own, x);
				img = c0_alloc(n, sizeof *img);
				if (!ts && !img)
					ts = C0_ENOMEM;
			}
#pragma omp for schedule(dynamic, 1) reduction(max : moved)
			for (int k = k0; k < k1; k++) {
				const double x0 = d->bx[k], y0 = d->by[k];
				if (!ts)
					remeasure(d, y, img, mv + (size_t)(k - k0) * n, k);
				moved = fmax(moved, fmax(fabs(d->bx[k] - x0), fabs(d->by[k] - y0)));
			}
			c0_first_fail_note(&fail, ts);
			if (y != x)
				drift_xcorr_free(&own), free(img);
		}
		if (fail.code)
			st = c0_first_fail_raise(&fail);
	}
	free(mv);
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

/* Stacks q0..q1-1: side by side (each thread with transforms of its own),
 * or one after another with each stack's blocks re-measured side by side
 * (a stack alone, or those left over by c0_threads_side) */
static int refine_stacks(struct c0_drift *d, int q0, int q1, int side)
{
	struct c0_first_fail fail = { 0 };
	const size_t n = (size_t)d->H * d->W;
	const int par = !side || q1 - q0 == 1;
	if (q1 <= q0)
		return C0_OK;
#pragma omp parallel if (!par)
	{
		struct xcorr x;
		double *ref = c0_alloc(n, sizeof *ref);
		int st = drift_xcorr_init(&x, d->H, d->W, d->sigma);
		if (!st && !ref)
			st = C0_ENOMEM;
#pragma omp for schedule(dynamic, 1)
		for (int q = q0; q < q1; q++)
			if (!st)
				st = refine_range(d, &x, ref, d->k0[q], d->k0[q + 1], par);
		c0_first_fail_note(&fail, st);
		drift_xcorr_free(&x);
		free(ref);
	}
	return fail.code ? c0_first_fail_raise(&fail) : C0_OK;
}

int drift_refine(struct c0_drift *d)
{
	/* each stack against the mean of its own blocks: an angle changes the
	 * image (depth-dependent excitation), which a correlation across angles
	 * would read as a shift. The stacks' blocks are apart: side by side. */
	const int *k0 = d->k0, side = c0_threads_side(d->nq);
	int st = refine_stacks(d, 0, side, 1);
	if (!st)
		st = refine_stacks(d, side, d->nq, 0);
	if (st)
		return st;
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
