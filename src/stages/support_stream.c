/* The support step's passes over a stack's frames: the covariance (and its
 * two interleaved halves), the temporal mean, the noise variance on a known
 * support, and the tiled stack's band of rows, all through one frame loop. */
#include "stages/support_parts.h"
#include "optics/psf.h"
#include "core/clock.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Every frame of in, after c's frame hook, its rows [y0, y0 + ny) to
 * use(ctx, t, rows); with band and no hook (which needs whole frames) only
 * those rows are read. what: the progress line's stage (NULL: none). */
typedef int (*frame_use)(void *ctx, int64_t t, const float *rows);
static int each_frame(const struct c0_support_conf *c, struct c0_frames *in, int band, int y0, int ny,
		      const char *what, frame_use use, void *ctx)
{
	const int W = in->width, H = in->height, whole = !band || c->frame_fn;
	float *frame = c0_alloc((size_t)W * (whole ? H : ny), sizeof *frame);
	if (!frame)
		return C0_ENOMEM;
	const float *mine = whole ? frame + (size_t)y0 * W : frame;
	struct c0_progress pr;
	if (what)
		c0_progress_begin(&pr, what, (double)in->count);
	int st = C0_OK;
	for (int64_t t = 0; t < in->count && !st; t++) {
		if (whole) {
			st = c0_frames_read(in, t, frame);
			if (!st && c->frame_fn)
				st = c->frame_fn(c->frame_ctx, t, frame, H, W);
		} else {
			st = c0_frames_read_rows(in, t, y0, ny, frame);
		}
		if (!st)
			st = use(ctx, t, mine);
		if (what)
			c0_progress_update(&pr, (double)t + 1);
	}
	if (what)
		c0_progress_end(&pr);
	free(frame);
	return st;
}

/* frames alternate between the accumulators */
struct alternate {
	struct c0_cov_acc **acc;
	int n;
};

static int add_alternate(void *ctx, int64_t t, const float *rows)
{
	struct alternate *a = ctx;
	return c0_cov_acc_add(a->acc[t % a->n], rows);
}

/* One pass; frames alternate between the nacc accumulators (1 or 2). */
static int stream_cov(const struct c0_support_conf *c, struct c0_frames *in, int nacc, struct c0_cov *cov,
		      double *seconds)
{
	int st = c0_support_check(c, in->width, in->height, in->count, in->name);
	if (!st && nacc == 2 && in->count < 6)
		st = c0_support_fail_short(in);
	if (st)
		return st;
	double t0 = c0_now();
	struct c0_cov_acc *acc[2] = { NULL, NULL };
	for (int k = 0; k < nacc && !st; k++)
		st = c0_support_acc_new(c, in->width, in->height, c0_support_lag(c), 0, 0, &acc[k]);
	if (!st)
		st = each_frame(c, in, 0, 0, in->height, "covariance", add_alternate, &(struct alternate){ acc, nacc });
	for (int k = 0; k < nacc; k++) {
		if (st)
			c0_cov_acc_free(acc[k]);
		else if ((st = c0_cov_acc_finish(acc[k], &cov[k])))
			for (int j = k + 1; j < nacc; j++)
				c0_cov_acc_free(acc[j]);
	}
	*seconds = c0_now() - t0;
	return st;
}

int c0_stack_covariance(const struct c0_support_conf *c, struct c0_frames *in, struct c0_cov *cov, double *seconds)
{
	return stream_cov(c, in, 1, cov, seconds);
}

int c0_stack_covariance_halves(const struct c0_support_conf *c, struct c0_frames *in, struct c0_cov half[2],
			       double *seconds)
{
	return stream_cov(c, in, 2, half, seconds);
}

/* sum[i] += frame[i] over n pixels */
struct sum {
	double *sum;
	size_t n;
};

static int add_sum(void *ctx, int64_t t, const float *rows)
{
	(void)t;
	const struct sum *s = ctx;
	for (size_t i = 0; i < s->n; i++)
		s->sum[i] += rows[i];
	return C0_OK;
}

int c0_stack_mean(const struct c0_support_conf *c, struct c0_frames *in, double **mean, int64_t *frames,
		  double *seconds)
{
	int st = c0_support_check(c, in->width, in->height, in->count, in->name);
	if (st)
		return st;
	double t0 = c0_now();
	const size_t n = (size_t)in->width * in->height;
	if (!(*mean = c0_alloc(n, sizeof **mean)))
		return C0_ENOMEM;
	st = each_frame(c, in, 0, 0, in->height, "mean", add_sum, &(struct sum){ *mean, n });
	for (size_t i = 0; !st && i < n; i++)
		(*mean)[i] /= (double)in->count;
	if (st)
		free(*mean), *mean = NULL;
	*frames = in->count;
	*seconds = c0_now() - t0;
	return st;
}

int c0_block_halves_init(struct c0_block_halves *h, int block, size_t n, c0_frame_fn fn, void *ctx)
{
	*h = (struct c0_block_halves){ fn, ctx, block, n, { NULL, NULL }, { 0, 0 } };
	for (int k = 0; k < 2; k++)
		if (!(h->sum[k] = c0_alloc(n, sizeof *h->sum[k])))
			return free(h->sum[0]), h->sum[0] = NULL, C0_ENOMEM;
	return C0_OK;
}

int c0_block_halves_fn(void *ctx, int64_t t, float *frame, int H, int W)
{
	struct c0_block_halves *h = ctx;
	int st = h->fn ? h->fn(h->ctx, t, frame, H, W) : C0_OK;
	const int k = (int)((t / h->block) % 2);
	for (size_t i = 0; !st && i < h->n; i++)
		h->sum[k][i] += frame[i];
	h->count[k] += !st;
	return st;
}

int c0_block_halves_finish(struct c0_block_halves *h, float *half[2], int64_t count[2])
{
	int st = C0_OK;
	half[0] = half[1] = NULL, count[0] = h->count[0], count[1] = h->count[1];
	for (int k = 0; k < 2 && count[0] > 0 && count[1] > 0 && !st; k++) {   /* as floats: what the solve reads */
		if (!(half[k] = c0_alloc(h->n, sizeof *half[k])))
			st = C0_ENOMEM;
		for (size_t i = 0; !st && i < h->n; i++)
			half[k][i] = (float)(h->sum[k][i] / (double)count[k]);
	}
	free(h->sum[0]), free(h->sum[1]), h->sum[0] = h->sum[1] = NULL;
	if (st || !half[1])
		free(half[0]), free(half[1]), half[0] = half[1] = NULL;
	return st;
}

static int use_none(void *ctx, int64_t t, const float *rows)
{
	(void)ctx, (void)t, (void)rows;
	return C0_OK;
}

int c0_stack_block_means(const struct c0_support_conf *c, struct c0_frames *in, int block, float *half[2],
			 int64_t count[2], double *seconds)
{
	half[0] = half[1] = NULL, count[0] = count[1] = 0, *seconds = 0;
	if (block < 1 || in->count < 2 * (int64_t)block)
		return C0_OK;
	const double t0 = c0_now();
	struct c0_block_halves h;
	int st = c0_block_halves_init(&h, block, (size_t)in->width * in->height, c->frame_fn, c->frame_ctx);
	struct c0_support_conf cc = *c;
	cc.frame_fn = c0_block_halves_fn, cc.frame_ctx = &h;
	if (!st)
		st = each_frame(&cc, in, 0, 0, in->height, NULL, use_none, NULL);
	if (!st)
		st = c0_block_halves_finish(&h, half, count);
	free(h.sum[0]), free(h.sum[1]);
	*seconds = c0_now() - t0;
	return st;
}

static int add_one(void *ctx, int64_t t, const float *rows)
{
	(void)t;
	return c0_cov_acc_add(ctx, rows);
}

/* c0_stack_noise on tile t: s2 its noise variance, its interior's mean
 * into the image's (W camera pixels wide) */
static int noise_tile(const struct c0_support_conf *c, struct c0_cov_acc *acc, const struct c0_tile *t,
		      const uint8_t *mask, int W, double *s2, double *mean)
{
	const int r = c->grid.srf;
	struct c0_cov cov = { 0 };
	struct c0_support_result tr;
	memset(&tr, 0, sizeof tr);
	const size_t Lw = (size_t)t->w * r;
	uint8_t *m = malloc(Lw * t->h * r);
	int st = m ? c0_cov_acc_window(acc, t->y0, t->x0, t->h, t->w, &cov) : C0_ENOMEM;
	if (!st) {
		c0_tile_copy(m, Lw, mask + (size_t)(t->y0 * r) * W * r + (size_t)t->x0 * r, (size_t)W * r, t->h * r, Lw);
		st = c0_support_noise_solve(c, &cov, m, &tr);
	}
	if (!st) {
		*s2 = tr.sigma2;
		const int oy = t->iy0 - t->y0, ox = t->ix0 - t->x0;
		c0_tile_copy(mean + (size_t)t->iy0 * W + t->ix0, (size_t)W * sizeof *mean,
			     cov.mean + (size_t)oy * t->w + ox, (size_t)t->w * sizeof *mean, t->ih, (size_t)t->iw * sizeof *mean);
	}
	c0_cov_free(&cov);
	c0_support_result_free(&tr);
	free(m);
	return st;
}

/* 1 where the distance along the line (n values, step apart) to a set
 * value of in is at most rad */
static void dilate_line(const uint8_t *in, uint8_t *out, int n, size_t step, int rad)
{
	for (int i = 0, last = -rad - 1; i < n; i++) {
		last = in[i * step] ? i : last;
		out[i * step] = i - last <= rad;
	}
	for (int i = n - 1, next = n + rad; i >= 0; i--) {
		next = in[i * step] ? i : next;
		out[i * step] |= next - i <= rad;
	}
}

/* The noise fit reads the covariance's lags only where a support pixel's
 * PSF reaches: the correlation A^T R at the mask's pixels sums a lag's
 * products over the camera pixels i (the pair's first) whose PSF weight on
 * the fine pixel is non-zero, |i + 1/2 - its centre| <= C0_PSF_CUTOFF sigma
 * + 1/2; the variances and the guard's lags stay whole. A radius of
 * cutoff sigma + 1 camera pixels around each support pixel's camera pixel
 * holds that with a pixel to spare (at 512 x 512, 20 % of the image). */
static int noise_region(const struct c0_support_conf *c, struct c0_cov_acc *acc, const uint8_t *mask, int W, int H)
{
	const int r = c->grid.srf, rad = (int)ceil(C0_PSF_CUTOFF * c0_grid_sigma_px(&c->grid) + 1);
	uint8_t *cm = c0_alloc((size_t)W * H, 1), *row = c0_alloc((size_t)W * H, 1);
	int st = cm && row ? C0_OK : C0_ENOMEM;
	for (size_t i = 0; !st && i < (size_t)W * H * r * r; i++)
		if (mask[i])
			cm[(i / ((size_t)W * r)) / r * W + (i % ((size_t)W * r)) / r] = 1;
	for (int y = 0; !st && y < H; y++)
		dilate_line(cm + (size_t)y * W, row + (size_t)y * W, W, 1, rad);
	for (int x = 0; !st && x < W; x++)
		dilate_line(row + x, cm + x, H, (size_t)W, rad);
	if (!st)
		st = c0_cov_acc_set_region(acc, cm);
	free(cm), free(row);
	return st;
}

int c0_stack_noise(const struct c0_support_conf *c, struct c0_frames *in, const uint8_t *mask, double **mean,
		   int64_t *frames, double *sigma2, double *seconds)
{
	*mean = NULL, *frames = in->count, *sigma2 = 0, *seconds = 0;
	const int W = in->width, H = in->height;
	struct c0_tiling tl;
	int st = c0_support_grid(c, in, &tl);
	if (st)
		return st;
	double t0 = c0_now();
	struct c0_cov_acc *acc = NULL;
	st = c0_support_acc_new(c, W, H, c0_support_lag(c), 0, 0, &acc);
	if (!st)
		st = noise_region(c, acc, mask, W, H);
	if (!st)
		st = each_frame(c, in, 0, 0, H, NULL, add_one, acc);
	if (!st && in->count < 3)
		st = c0_fail(C0_EINVAL, "%s: the covariance needs at least 3 frames", in->name);
	if (!st)
		c0_cov_acc_seal(acc);   /* the windows below only read */
	*seconds = c0_now() - t0;
	double *s2 = c0_alloc((size_t)tl.n, sizeof *s2);
	*mean = c0_alloc((size_t)W * H, sizeof **mean);
	if (!st && (!s2 || !*mean))
		st = C0_ENOMEM;
	struct c0_support_conf cc = *c;
	cc.fista.maxit = 100;   /* sigma2 within 0.1 % of 1000 iterations (docs/defaults.md#noise_variance) */
	struct c0_first_fail fail = { 0 };
#pragma omp parallel for schedule(dynamic, 1) if (tl.n > 1)
	for (int k = 0; k < (st ? 0 : tl.n); k++)
		c0_first_fail_note(&fail, noise_tile(&cc, acc, &tl.t[k], mask, W, &s2[k], *mean));
	if (!st)
		st = c0_first_fail_raise(&fail);
	double area = 0;
	for (int k = 0; !st && k < tl.n; k++)   /* in tile order: the same sum on any schedule */
		*sigma2 += s2[k] * tl.t[k].ih * tl.t[k].iw, area += (double)tl.t[k].ih * tl.t[k].iw;
	if (!st)
		*sigma2 /= area;
	c0_cov_acc_free(acc);
	free(s2);
	c0_tiling_free(&tl);
	if (st)
		free(*mean), *mean = NULL;
	return st;
}

/* the tiled stack's pass: all frames into s->acc, and the odd ones' (and
 * with even bands the even ones') windows into the subset's accumulators */
struct tiles_pass {
	struct c0_support_share *s;
	int W;
	float *win;
};

static int add_window(const struct tiles_pass *p, struct c0_cov_acc *a, const struct c0_tile *w, const float *mine)
{
	const struct c0_support_share *s = p->s;
	c0_tile_copy(p->win, (size_t)w->w * sizeof *p->win, mine + (size_t)(w->y0 - s->ya) * p->W + w->x0,
		     (size_t)p->W * sizeof *p->win, w->h, (size_t)w->w * sizeof *p->win);
	return c0_cov_acc_add(a, p->win);
}

static int add_tiles(void *ctx, int64_t t, const float *mine)
{
	const struct tiles_pass *p = ctx;
	const struct c0_support_share *s = p->s;
	int st = c0_cov_acc_add(s->acc, mine);
	for (int k = s->k0; k < s->k1 && !st; k++) {
		struct c0_cov_acc *a = t % 2 ? s->odd[k - s->k0] : s->even ? s->even[k - s->k0] : NULL;
		if (a)
			st = add_window(p, a, &s->tl.t[k], mine);
	}
	return st;
}

/* the share's accumulators, the even bands with several stacks */
static int tiles_open(const struct c0_support_conf *c, int W, int H, int n, struct c0_support_share *s)
{
	const int rows = s->yb - s->ya, d = c0_support_lag(c), block = c0_cov_block_frames((size_t)W * H);
	int st = c0_support_acc_new(c, W, rows, d, 0, s->ya, &s->acc);
	if (!st)
		st = c0_cov_acc_set_block(s->acc, block);
	if (!st && n > 1 && !(s->even = c0_alloc((size_t)(s->k1 - s->k0) + 1, sizeof *s->even)))
		st = C0_ENOMEM;
	for (int k = s->k0; k < s->k1 && !st; k++) {
		const struct c0_tile *t = &s->tl.t[k];
		struct c0_cov_acc **pair[2] = { &s->odd[k - s->k0], s->even ? &s->even[k - s->k0] : NULL };
		for (int h = 0; h < 2 && !st && s->sub[k]; h++)
			if (pair[h] && !(st = c0_support_acc_new(c, t->w, t->h, d, t->x0, t->y0, pair[h])))
				st = c0_cov_acc_set_block(*pair[h], block);
	}
	return st;
}

/* the share's accumulators start stack c's segment: its noise map */
static int tiles_next(const struct c0_support_conf *c, struct c0_support_share *s)
{
	int st = c0_cov_acc_next(s->acc);
	if (!st && c->noise_map)
		c0_cov_acc_set_noise(s->acc, c->noise_map, c->noise_map_w, 0, s->ya);
	for (int k = s->k0; k < s->k1 && !st; k++)
		for (int h = 0; h < 2 && !st; h++) {
			struct c0_cov_acc *a = h ? s->even[k - s->k0] : s->odd[k - s->k0];
			if (a && !(st = c0_cov_acc_next(a)) && c->noise_map)
				c0_cov_acc_set_noise(a, c->noise_map, c->noise_map_w, s->tl.t[k].x0, s->tl.t[k].y0);
		}
	return st;
}

int c0_support_stream_tiles(const struct c0_support_conf *c, struct c0_frames *in, int n, struct c0_support_share *s)
{
	const int W = in[0].width, rows = s->yb - s->ya;
	int st = tiles_open(&c[0], W, in[0].height, n, s);
	size_t wmax = 0;
	for (int k = s->k0; k < s->k1; k++)
		wmax = s->sub[k] && (size_t)s->tl.t[k].w * s->tl.t[k].h > wmax ? (size_t)s->tl.t[k].w * s->tl.t[k].h : wmax;
	struct tiles_pass p = { s, W, NULL };
	if (!st && wmax && !(p.win = c0_alloc(wmax, sizeof *p.win)))
		st = C0_ENOMEM;
	for (int q = 0; q < n && !st; q++) {
		if (q)
			st = tiles_next(&c[q], s);
		if (!st)
			st = each_frame(&c[q], &in[q], 1, s->ya, rows, "covariance", add_tiles, &p);
	}
	free(p.win);
	return st;
}
