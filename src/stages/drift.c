#include "stages/drift_parts.h"
#include "ops/fshift.h"
#include "io/frames.h"
#include "core/c0math.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/fftw_plan.h"
#include "core/mem.h"
#include "core/progress.h"
#include "core/threads.h"

#include <complex.h>
#include <fftw3.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* sum += frames f[0..m) (n pixels each), a cache-sized chunk of pixels at
 * a time: each sum[i] still adds the frames in order, so the same bits as
 * frame by frame, but the sums (8 MB at 1024^2) stay in cache across the
 * frames instead of going through memory once a frame */
C0_HOT_SAME static void add_block(double *sum, const float *f, int64_t m, size_t n)
{
	enum { CHUNK = 2048 };
	for (size_t i0 = 0; i0 < n; i0 += CHUNK) {
		const size_t i1 = n - i0 < CHUNK ? n : i0 + CHUNK;
		for (int64_t t = 0; t < m; t++) {
			const float *ft = f + (size_t)t * n;
			for (size_t i = i0; i < i1; i++)
				sum[i] += ft[i];
		}
	}
}

/* Frames t0..t1-1 (in f) added to the block means; a block's mean, once
 * complete, is kept and measured against the block before. */
static int add_frames(struct stack_blocks *o, struct xcorr *x, double *sum, const float *f, int64_t t0, int64_t t1,
		      int64_t T, size_t n, struct c0_progress *pr)
{
	for (int64_t t = t0; t < t1;) {
		const int64_t k = t / o->B < o->nb ? t / o->B : o->nb - 1;
		const int64_t b1 = k * o->B, b2 = k == o->nb - 1 ? T : b1 + o->B;   /* the last block takes the remainder */
		const int64_t e = t1 < b2 ? t1 : b2;   /* this call's frames of block k */
		if (t == b1)
			memset(sum, 0, n * sizeof *sum);
		add_block(sum, f + (size_t)(t - t0) * n, e - t, n);
		t = e;
		c0_progress_update(pr, (double)t);
		if (t < b2)
			continue;
		for (size_t i = 0; i < n; i++)
			sum[i] /= (double)(b2 - b1);
		if (!(o->bm[k] = c0_alloc(n, sizeof(float))))
			return C0_ENOMEM;
		for (size_t i = 0; i < n; i++)
			o->bm[k][i] = (float)sum[i];
		if (k > 0)
			drift_shift_of(x, sum, 0, &o->sx[k], &o->sy[k]);
		else
			drift_spectrum(x, sum);
		memcpy(x->ref, x->sp, x->ns * sizeof *x->ref);
	}
	return C0_OK;
}

static int stack_pass(struct c0_frames *r, int64_t B, double sigma, int ahead, struct stack_blocks *o)
{
	const int H = r->height, W = r->width;
	const size_t n = (size_t)H * W;
	const int64_t T = r->count, nb = T / B;
	int64_t nf = ahead > 0 ? ahead : READ_AHEAD / (int64_t)(n * sizeof(float));
	nf = nf < 1 ? 1 : nf > T ? T : nf;
	const int64_t nbatch = (T + nf - 1) / nf;
	struct xcorr x;
	int st = drift_xcorr_init(&x, H, W, sigma), rst = C0_OK;
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
	drift_xcorr_free(&x);
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
 * reads its own file; the ones left over (c0_threads_side) each read beside
 * their adding. The first failing stack's message. */
static int read_stacks(const struct c0_drift_conf *c, struct c0_frames *f, int n, struct stack_blocks *sb)
{
	int fail = -1;
	const int side = c0_threads_side(n);
	for (int pass = 0; pass < 2; pass++)
#pragma omp parallel for schedule(dynamic, 1) if (!pass && side > 1)
		for (int q = pass ? side : 0; q < (pass ? n : side); q++)
			if (stack_pass(&f[q], block_len(c, f[q].count), c->psf_sigma_px, c->read_ahead, &sb[q]))
#pragma omp critical(c0_drift_fail)
				if (fail < 0 || q < fail)
					fail = q;
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
		st = drift_refine(d);
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
