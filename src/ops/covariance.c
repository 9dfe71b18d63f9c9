#define _DEFAULT_SOURCE   /* madvise */
#include "ops/covariance.h"
#include "ops/covsum.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/order.h"

#include <math.h>

#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#define BLOCK 32                 /* at most this many frames per pass over the sums */
#define BLOCK_BYTES (64 << 20)   /* and at most this much memory for them */

struct c0_cov_acc {
	int W, H, d, nlag;
	int *dy, *dx;
	int64_t frames;
	float *sum;         /* nlag * H * W sums of products of shifted values */
	float *shift;       /* first frame: sums are of y - shift, which keeps them small */
	double *s1;
	double *st;         /* sum over frames of t (y - shift): the linear trend */
	float *blk;         /* up to `block` frames, shifted */
	int nb, block;
	int dropped;        /* rows [0, dropped) of sum are given back */
	int fresh;          /* sum untouched since calloc: the first flush writes each sum before adding (add_lags) */
	int lost;           /* a flush's thread had no memory for its ring: its rows were not added */
	double guard;       /* c0_cov_acc_set_guard's g; 0: none */
	const float *noise; /* c0_cov_acc_set_noise's map (NULL: none), its width and this accumulator's origin in it */
	int noise_w, noise_x0, noise_y0;
	int *span, *span_at; /* c0_cov_acc_set_region's row spans [x0, x1): row y's from span_at[y] to span_at[y + 1] (NULL: none) */
	/* c0_cov_acc_next's finished segments: their cross-products are in sum */
	int64_t seg_frames; /* their frames */
	double seg_dof;     /* the sum of their T - 2 */
	double *seg_sum;    /* n: the sum of their frames (unshifted), for the mean; NULL: none yet */
	double *seg_noise;  /* n: the sum of their noise maps, each times its T - 2; NULL: none */
};

static void subtract_noise(const struct c0_cov_acc *a, int y0, int x0, struct c0_cov *c);

/* lag (dy, dx) is stored: in the disk of radius d, and in the half that
 * stands for its mirror (dy > 0, or dy = 0 and dx >= 0) */
static int kept_lag(int dy, int dx, int d)
{
	return (dy > 0 || dx >= 0) && dy * dy + dx * dx <= d * d;
}

int c0_cov_lag_count(int d)
{
	int n = 0;
	for (int dy = 0; dy <= d; dy++)
		for (int dx = -d; dx <= d; dx++)
			n += kept_lag(dy, dx, d);
	return n;
}

int c0_cov_acc_new(int W, int H, int d, struct c0_cov_acc **out)
{
	*out = NULL;
	if (W < 1 || H < 1 || d < 0)
		return c0_fail(C0_EINVAL, "covariance: invalid size %dx%d or lag %d", W, H, d);
	struct c0_cov_acc *a = c0_alloc(1, sizeof *a);
	if (!a)
		return C0_ENOMEM;
	a->W = W, a->H = H, a->d = d;
	a->nlag = c0_cov_lag_count(d);
	size_t n = (size_t)W * H;
	a->block = c0_cov_block_frames(n);
	a->dy = c0_alloc((size_t)a->nlag, sizeof(int));
	a->dx = c0_alloc((size_t)a->nlag, sizeof(int));
	a->sum = c0_alloc((size_t)a->nlag * n, sizeof(float));
	a->shift = c0_alloc(n, sizeof(float));
	a->s1 = c0_alloc(n, sizeof(double));
	a->st = c0_alloc(n, sizeof(double));
	a->blk = c0_alloc(n * (size_t)a->block, sizeof(float));
	if (!a->dy || !a->dx || !a->sum || !a->shift || !a->s1 || !a->st || !a->blk) {
		c0_cov_acc_free(a);
		return c0_fail(C0_ENOMEM, "covariance: out of memory for %dx%d pixels x %d lags", W, H, a->nlag);
	}
	a->fresh = 1;
	int l = 0;
	for (int dy = 0; dy <= d; dy++)
		for (int dx = -d; dx <= d; dx++)
			if (kept_lag(dy, dx, d))
				a->dy[l] = dy, a->dx[l] = dx, l++;
	*out = a;
	return C0_OK;
}

int c0_cov_block_frames(size_t pixels)
{
	size_t b = BLOCK_BYTES / (pixels * sizeof(float));
	return b < 1 ? 1 : b > BLOCK ? BLOCK : (int)b;
}

int c0_cov_acc_set_block(struct c0_cov_acc *a, int frames)
{
	if (a->frames || frames < 1)
		return c0_fail(C0_EINVAL, "covariance: the block size is set before the first frame (got %d)", frames);
	float *b = c0_alloc((size_t)a->W * a->H * (size_t)frames, sizeof *b);
	if (!b)
		return C0_ENOMEM;
	free(a->blk);
	a->blk = b, a->block = frames;
	return C0_OK;
}

void c0_cov_free(struct c0_cov *c)
{
	free(c->dy), free(c->dx), free(c->r), free(c->mean);
	memset(c, 0, sizeof *c);
}

void c0_cov_acc_free(struct c0_cov_acc *a)
{
	if (!a)
		return;
	free(a->dy), free(a->dx), free(a->sum), free(a->shift), free(a->s1), free(a->st), free(a->blk);
	free(a->span), free(a->span_at), free(a->seg_sum), free(a->seg_noise);
	free(a);
}

/* the lags c0_cov_guard reads (and the variance): kept on every pixel */
static int whole_lag(int dy, int dx)
{
	return (dy == 0 && dx <= 1) || (dy == 1 && dx == 0);
}

int c0_cov_acc_set_region(struct c0_cov_acc *a, const uint8_t *keep)
{
	if (a->frames)
		return c0_fail(C0_EINVAL, "covariance: the region is set before the first frame");
	const int W = a->W, H = a->H;
	size_t ns = 0;
	for (size_t i = 0; i < (size_t)W * H; i++)   /* span starts */
		ns += keep[i] && (i % W == 0 || !keep[i - 1]);
	int *span = c0_alloc(2 * ns + 2, sizeof *span), *at = c0_alloc((size_t)H + 1, sizeof *at);
	if (!span || !at) {
		free(span), free(at);
		return C0_ENOMEM;
	}
	int k = 0;
	for (int y = 0; y < H; y++) {
		at[y] = k;
		const uint8_t *m = keep + (size_t)y * W;
		for (int x = 0; x < W; x++)
			if (m[x] && (x == 0 || !m[x - 1])) {
				int e = x;
				while (e < W && m[e])
					e++;
				span[2 * k] = x, span[2 * k + 1] = e, k++;
			}
	}
	at[H] = k;
	free(a->span), free(a->span_at);
	a->span = span, a->span_at = at;
	return C0_OK;
}

/* flush's unit of work: rows of a strip of columns [c0, c0 + w). Per
 * thread, the block's rows y..y+d of the strip (a ring of d + 1 slots) as
 * doubles, converted once each, with `pad` zero columns either side: a lag
 * that reaches past the image adds products of 0 to sums never read. Frame
 * b of row y, column c0 + x at ring_row(g, y) + b S + x. A strip's ring
 * (d + 1 rows of nb frames, 250 kB at d = 6, 16 frames) stays in L2. */
enum { STRIP = 256, ROWS = 32 };   /* columns (a multiple of 16: whole cache lines of sums) and rows per task */

struct ring {
	double *v;
	size_t S;
	int slots, pad, c0, w;
};

static int ring_new(struct ring *g, const struct c0_cov_acc *a)
{
	g->pad = (a->d + 7) / 8 * 8;
	g->S = (size_t)STRIP + 2 * g->pad;
	g->S += g->S % 512 ? 0 : 8;   /* rows 4 kB apart would share L1's sets */
	g->slots = a->d + 1;
	g->v = aligned_alloc(64, sizeof *g->v * (size_t)g->slots * a->nb * g->S);
	return g->v ? C0_OK : C0_ENOMEM;
}

static double *ring_row(const struct ring *g, const struct c0_cov_acc *a, int y)
{
	return g->v + (size_t)(y % g->slots) * a->nb * g->S + g->pad;
}

static void ring_fill(const struct ring *g, const struct c0_cov_acc *a, int y)
{
	const size_t n = (size_t)a->W * a->H;
	double *dst = ring_row(g, a, y);
	const int lo = g->c0 - g->pad < 0 ? -g->c0 : -g->pad;
	const int hi = g->c0 + g->w + g->pad > a->W ? a->W - g->c0 : g->w + g->pad;
	for (int b = 0; b < a->nb; b++) {
		const float *src = a->blk + b * n + (size_t)y * a->W + g->c0;
		double *d = dst + b * g->S;
		for (int x = -g->pad; x < lo; x++)
			d[x] = 0;
		for (int x = lo; x < hi; x++)
			d[x] = src[x];
		for (int x = hi; x < g->w + g->pad; x++)
			d[x] = 0;
	}
}

/* s1 and st of row y's columns [x0, x0 + w) from the block's frames in
 * order, as c0_cov_acc_add once did frame by frame (t v is exact in
 * double: the same sums); p: the ring's column x0 */
static void row_moments(struct c0_cov_acc *a, int y, int x0, int w, const double *p, size_t S)
{
	double *s1 = a->s1 + (size_t)y * a->W + x0, *st = a->st + (size_t)y * a->W + x0;
	const double t0 = (double)(a->frames - a->nb);
	int x = 0;
	for (; x + 4 <= w; x += 4) {   /* the frames inner: 4 pixels' sums stay in registers */
		double u[4], v[4];
		for (int k = 0; k < 4; k++)
			u[k] = s1[x + k], v[k] = st[x + k];
		for (int b = 0; b < a->nb; b++)
			for (int k = 0; k < 4; k++)
				u[k] += p[b * S + x + k], v[k] += (t0 + b) * p[b * S + x + k];
		for (int k = 0; k < 4; k++)
			s1[x + k] = u[k], st[x + k] = v[k];
	}
	for (; x < w; x++)
		for (int b = 0; b < a->nb; b++)
			s1[x] += p[b * S + x], st[x] += (t0 + b) * p[b * S + x];
}

/* lags [l, l + m) (one dy, consecutive dx) of row y over the strip's
 * columns [x0, x1); on the first flush the sums are zeroed first. A first
 * touch that read would map the zero page, whose copy on the write then
 * flushes every thread's TLB (7 % of `support`'s CPU time on a 1024^2
 * frame); zeroing only what is added keeps the pages a region leaves out
 * (c0_cov_acc_set_region) unmade, as calloc left them. */
static void add_lags(struct c0_cov_acc *a, int y, const struct ring *g, int l, int m, int x0, int x1)
{
	const size_t n = (size_t)a->W * a->H;
	float *acc = a->sum + (size_t)l * n + (size_t)y * a->W + g->c0 + x0;
	for (int k = 0; a->fresh && k < m; k++)
		memset(acc + k * n, 0, sizeof *acc * (size_t)(x1 - x0));
	const double *p = ring_row(g, a, y) + x0, *q = ring_row(g, a, y + a->dy[l]) + x0 + a->dx[l];
	c0_covsum_lags(acc, n, p, q, x1 - x0, m, a->nb, g->S);
}

/* a region's columns in the strip where row y's restricted lags are
 * summed: its spans, widened to whole vectors of 8 from the strip's start
 * (the sums outside are cleared when read); `r` gets [x0, x1) pairs,
 * strip-relative, in order; returns their number */
static int region_runs(const struct c0_cov_acc *a, int y, const struct ring *g, int *r)
{
	int m = 0;
	for (int k = a->span_at[y]; k < a->span_at[y + 1]; k++) {
		int s0 = a->span[2 * k] - g->c0, s1 = a->span[2 * k + 1] - g->c0;
		s0 = s0 < 0 ? 0 : s0 / 8 * 8;
		s1 = s1 > g->w ? g->w : (s1 + 7) / 8 * 8 < g->w ? (s1 + 7) / 8 * 8 : g->w;
		if (s1 <= s0)
			continue;
		if (m && s0 <= r[2 * m - 1])
			r[2 * m - 1] = s1 > r[2 * m - 1] ? s1 : r[2 * m - 1];
		else
			r[2 * m] = s0, r[2 * m + 1] = s1, m++;
	}
	return m;
}

/* flush's work on row y of the strip, the ring holding rows y..y+d: the
 * lags of each dy together (one load of p serves them all) */
static void flush_row(struct c0_cov_acc *a, int y, const struct ring *g, int *runs)
{
	const int nr = a->d + 1 < a->H - y ? a->d + 1 : a->H - y;
	row_moments(a, y, g->c0, g->w, ring_row(g, a, y), g->S);
	const int nrun = a->span ? region_runs(a, y, g, runs) : 0;
	for (int l = 0; l < a->nlag;) {
		int e = l + 1;   /* [l, e): the lags of one dy, whole or not alike */
		const int wl = !a->span || whole_lag(a->dy[l], a->dx[l]);
		while (e < a->nlag && a->dy[e] == a->dy[l] && (!a->span || whole_lag(a->dy[e], a->dx[e]) == wl))
			e++;
		if (a->dy[l] < nr) {
			if (wl)
				add_lags(a, y, g, l, e - l, 0, g->w);
			for (int k = 0; !wl && k < nrun; k++)
				add_lags(a, y, g, l, e - l, runs[2 * k], runs[2 * k + 1]);
		}
		l = e;
	}
}

/* The sums are float (half the memory of the band: whole sCMOS frames fit);
 * each pass adds a block of frames in double and rounds once. Each (lag,
 * row, strip) owns its accumulators: no races. Fails, now and at every
 * later flush, once a thread could not add its rows. */
static int flush(struct c0_cov_acc *a)
{
	const int nb = a->nb, H = a->H, ns = (a->W + STRIP - 1) / STRIP, nt = (H + ROWS - 1) / ROWS * ns;
	if (!nb)
		goto done;
#pragma omp parallel
	{
		struct ring g;
		int *runs = malloc(sizeof *runs * (STRIP + 2));
		int ok = !ring_new(&g, a) && runs;
#pragma omp for schedule(dynamic, 1)
		for (int t = 0; t < nt; t++) {
			const int y0 = t / ns * ROWS, y1 = y0 + ROWS < H ? y0 + ROWS : H;
			g.c0 = t % ns * STRIP, g.w = g.c0 + STRIP < a->W ? STRIP : a->W - g.c0;
			for (int y = y0; ok && y < y1; y++) {
				for (int r = y == y0 ? y : y + a->d; r <= y + a->d && r < H; r++)
					ring_fill(&g, a, r);
				flush_row(a, y, &g, runs);
			}
		}
		if (!ok)
#pragma omp atomic write
			a->lost = 1;
		free(g.v), free(runs);
	}
	a->nb = 0, a->fresh = 0;
done:
	return a->lost ? c0_fail(C0_ENOMEM, "covariance: out of memory for a thread's rows of frames") : C0_OK;
}

int c0_cov_acc_add(struct c0_cov_acc *a, const float *frame)
{
	const size_t n = (size_t)a->W * a->H;
	if (!a->blk && !(a->blk = c0_alloc(n * (size_t)a->block, sizeof(float))))
		return C0_ENOMEM;
	if (a->frames == 0)
		memcpy(a->shift, frame, n * sizeof *frame);
	/* the frame's sums (s1, st) are added by flush, from the block; the
	 * copy on every thread (it bounds the stream between the flushes) */
	float *dst = a->blk + a->nb * n;
#pragma omp parallel for schedule(static) if (n >= 65536)
	for (size_t i = 0; i < n; i++)
		dst[i] = frame[i] - a->shift[i];
	a->frames++;
	return ++a->nb == a->block ? flush(a) : C0_OK;
}

/* a_i / sqrt(Stt) of pixel k */
static double trend(const struct c0_cov_acc *a, size_t k)
{
	const double T = (double)a->frames, tbar = (T - 1) / 2, Stt = T * (T * T - 1) / 12;
	return (a->st[k] - tbar * a->s1[k]) / sqrt(Stt);
}

/* a region's restricted lags are 0 outside it in the window at (y0, x0) */
static void clear_outside(const struct c0_cov_acc *a, int y0, int x0, struct c0_cov *c)
{
	const size_t n = (size_t)c->W * c->H;
	for (int l = 0; l < c->nlag; l++) {
		if (whole_lag(c->dy[l], c->dx[l]))
			continue;
		for (int y = 0; y < c->H; y++) {
			double *r = c->r + (size_t)l * n + (size_t)y * c->W;
			int x = 0;   /* window column */
			for (int k = a->span_at[y0 + y]; k <= a->span_at[y0 + y + 1]; k++) {
				const int e = k < a->span_at[y0 + y + 1] ? a->span[2 * k] - x0 : c->W;   /* next span's start */
				for (; x < (e < c->W ? e : c->W); x++)
					r[x] = 0;
				if (k < a->span_at[y0 + y + 1] && a->span[2 * k + 1] - x0 > x)
					x = a->span[2 * k + 1] - x0;
			}
		}
	}
}

int c0_cov_acc_window(struct c0_cov_acc *a, int y0, int x0, int h, int w, struct c0_cov *out)
{
	memset(out, 0, sizeof *out);
	if (a->frames < 3)
		return c0_fail(C0_EINVAL, "covariance needs at least 3 frames (got %lld)", (long long)a->frames);
	if (y0 < 0 || x0 < 0 || h < 1 || w < 1 || y0 + h > a->H || x0 + w > a->W)
		return c0_fail(C0_EINVAL, "covariance: window %dx%d at (%d, %d) outside %dx%d", w, h, x0, y0, a->W, a->H);
	if (y0 < a->dropped)
		return c0_fail(C0_EINVAL, "covariance: window from row %d, but rows up to %d were dropped", y0, a->dropped);
	int st = flush(a);
	if (st)
		return st;
	struct c0_cov *c = out;
	c->W = w, c->H = h, c->d = a->d, c->nlag = a->nlag, c->frames = a->frames + a->seg_frames;
	const size_t n = (size_t)w * h, N = (size_t)a->W * a->H;
	c->dy = c0_alloc((size_t)c->nlag, sizeof(int));
	c->dx = c0_alloc((size_t)c->nlag, sizeof(int));
	c->r = c0_alloc((size_t)c->nlag * n, sizeof(double));
	c->mean = c0_alloc(n, sizeof(double));
	if (!c->dy || !c->dx || !c->r || !c->mean) {
		c0_cov_free(c);
		return c0_fail(C0_ENOMEM, "covariance: out of memory for a %dx%d window x %d lags", w, h, a->nlag);
	}
	memcpy(c->dy, a->dy, sizeof(int) * (size_t)c->nlag);
	memcpy(c->dx, a->dx, sizeof(int) * (size_t)c->nlag);
	const double T = (double)a->frames;
	/* a per-pixel linear trend (bleaching, slow drift of the lamp) is not
	 * fluctuation: remove it. With a_i = sum_t (t - tbar) y_i and
	 * Stt = sum_t (t - tbar)^2, the detrended cross-product is
	 * sum (y_i - ybar_i)(y_j - ybar_j) - a_i a_j / Stt, over T - 2 degrees of freedom. */
	double *tr = c0_alloc(n, sizeof *tr);
	if (!tr) {
		c0_cov_free(c);
		return C0_ENOMEM;
	}
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			const size_t k = (size_t)(y0 + y) * a->W + x0 + x, i = (size_t)y * w + x;
			c->mean[i] = a->s1[k] / T;   /* shifted mean */
			tr[i] = trend(a, k);
		}
	/* each entry only from its own pixels' sums: a window gives the same
	 * numbers as the whole image, whatever the tiling */
	for (int l = 0; l < c->nlag; l++) {
		const int dy = c->dy[l], dx = c->dx[l];
		for (int y = 0; y + dy < h; y++)
			for (int x = dx < 0 ? -dx : 0; x < (dx > 0 ? w - dx : w); x++) {
				size_t i = (size_t)y * w + x, j = (size_t)(y + dy) * w + x + dx;
				double s = a->sum[(size_t)l * N + (size_t)(y0 + y) * a->W + x0 + x];
				c->r[(size_t)l * n + i] = (s - T * c->mean[i] * c->mean[j] - tr[i] * tr[j]) / (a->seg_dof + T - 2);
			}
	}
	free(tr);
	if (a->span)
		clear_outside(a, y0, x0, c);
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			const size_t i = (size_t)y * w + x, k = (size_t)(y0 + y) * a->W + x0 + x;
			c->mean[i] += a->shift[k];
			if (a->seg_sum)   /* every segment's frames */
				c->mean[i] = (a->seg_sum[k] + T * c->mean[i]) / (double)c->frames;
		}
	subtract_noise(a, y0, x0, c);
	st = a->guard > 0 ? c0_cov_guard(c, a->guard, NULL) : C0_OK;
	if (st)
		c0_cov_free(c);
	return st;
}

void c0_cov_acc_set_guard(struct c0_cov_acc *a, double g) { a->guard = g; }

void c0_cov_acc_set_noise(struct c0_cov_acc *a, const float *map, int map_w, int x0, int y0)
{
	a->noise = map, a->noise_w = map_w, a->noise_x0 = x0, a->noise_y0 = y0;
}

/* lag 0 of the window at (y0, x0) of a minus a's noise map there */
static void subtract_noise(const struct c0_cov_acc *a, int y0, int x0, struct c0_cov *c)
{
	/* the current segment's share of its map (1 without segments), and the finished segments' */
	const double D = a->seg_dof + (double)(a->frames - 2), f = (double)(a->frames - 2) / D;
	for (int y = 0; a->noise && y < c->H; y++)
		for (int x = 0; x < c->W; x++)
			c->r[(size_t)y * c->W + x] -=
				f * a->noise[(size_t)(a->noise_y0 + y0 + y) * a->noise_w + a->noise_x0 + x0 + x];
	for (int y = 0; a->seg_noise && y < c->H; y++)
		for (int x = 0; x < c->W; x++)
			c->r[(size_t)y * c->W + x] -= a->seg_noise[(size_t)(y0 + y) * a->W + x0 + x] / D;
}

static int lag_index(const struct c0_cov *c, int dy, int dx)
{
	for (int l = 0; l < c->nlag; l++)
		if (c->dy[l] == dy && c->dx[l] == dx)
			return l;
	return -1;
}

int c0_cov_guard(struct c0_cov *c, double g, size_t *set)
{
	const int w = c->W, h = c->H, lr = lag_index(c, 0, 1), ld = lag_index(c, 1, 0);
	const size_t n = (size_t)w * h;
	if (set)
		*set = 0;
	if (!(g > 0) || lr < 0 || ld < 0 || c->frames < 3)
		return C0_OK;
	double *v = c->r, *fill = c0_alloc(n, sizeof *fill);
	if (!fill)
		return c0_fail(C0_ENOMEM, "covariance: out of memory for the pixel guard of a %dx%d window", w, h);
	const double *cr = c->r + (size_t)lr * n, *cd = c->r + (size_t)ld * n;
	const double margin = 1 + C0_COV_GUARD_Z * sqrt(2.0 / ((double)c->frames - 2));
	/* every value from the variances as measured (NAN: kept), then the setting;
	 * a variance that overflowed stays so: the callers refuse it */
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			const size_t i = (size_t)y * w + x;
			double s = 0, nb[4];
			int m = 0;
			if (x + 1 < w)
				s += cr[i], nb[m++] = v[i + 1];
			if (x > 0)
				s += cr[i - 1], nb[m++] = v[i - 1];
			if (y + 1 < h)
				s += cd[i], nb[m++] = v[i + w];
			if (y > 0)
				s += cd[i - w], nb[m++] = v[i - w];
			fill[i] = NAN;
			if (!m || !isfinite(v[i]))
				continue;
			const double sig = fmax(0, s / m) / g, noise = fmax(0, c0_median(nb, (size_t)m));
			if (v[i] > sig + margin * noise)
				fill[i] = sig + noise;
		}
	size_t k = 0;
	for (size_t i = 0; i < n; i++)
		if (!isnan(fill[i]))
			v[i] = fill[i], k++;
	free(fill);
	if (set)
		*set = k;
	return C0_OK;
}

double c0_cov_acc_variance(struct c0_cov_acc *a, int y, int x)
{
	if (flush(a))
		return NAN;
	const size_t i = (size_t)y * a->W + x;
	const double T = (double)a->frames, m = a->s1[i] / T, b = trend(a, i);
	return (a->sum[i] - T * m * m - b * b) / (a->seg_dof + T - 2);
}

/* sum's pair (i, j) of lag l less the segment's mean and trend products */
static void centre_segment(struct c0_cov_acc *a)
{
	const int W = a->W, H = a->H;
	const size_t n = (size_t)W * H;
	const double T = (double)a->frames;
#pragma omp parallel for schedule(static)
	for (int l = 0; l < a->nlag; l++) {
		const int dy = a->dy[l], dx = a->dx[l];
		for (int y = 0; y + dy < H; y++)
			for (int x = dx < 0 ? -dx : 0; x < (dx > 0 ? W - dx : W); x++) {
				const size_t i = (size_t)y * W + x, j = (size_t)(y + dy) * W + x + dx;
				const double s = a->sum[(size_t)l * n + i] - a->s1[i] * a->s1[j] / T - trend(a, i) * trend(a, j);
				a->sum[(size_t)l * n + i] = (float)s;
			}
	}
}

int c0_cov_acc_next(struct c0_cov_acc *a)
{
	const size_t n = (size_t)a->W * a->H;
	if (a->frames < 3)
		return c0_fail(C0_EINVAL, "covariance: a segment needs at least 3 frames (got %lld)", (long long)a->frames);
	if (a->dropped)
		return c0_fail(C0_EINVAL, "covariance: a new segment after rows were dropped");
	if (!a->seg_sum && !(a->seg_sum = c0_alloc(n, sizeof *a->seg_sum)))
		return C0_ENOMEM;
	if (a->noise && !a->seg_noise && !(a->seg_noise = c0_alloc(n, sizeof *a->seg_noise)))
		return C0_ENOMEM;
	int st = flush(a);
	if (st)
		return st;
	centre_segment(a);
	for (int y = 0; a->noise && y < a->H; y++)   /* each segment's own map, over its degrees of freedom */
		for (int x = 0; x < a->W; x++)
			a->seg_noise[(size_t)y * a->W + x] +=
				(double)(a->frames - 2) * a->noise[(size_t)(a->noise_y0 + y) * a->noise_w + a->noise_x0 + x];
	for (size_t i = 0; i < n; i++)
		a->seg_sum[i] += a->s1[i] + (double)a->frames * a->shift[i], a->s1[i] = a->st[i] = 0;
	a->seg_frames += a->frames, a->seg_dof += (double)(a->frames - 2), a->frames = 0;
	return C0_OK;
}

void c0_cov_acc_seal(struct c0_cov_acc *a)
{
	(void)flush(a);   /* a failure stays: the windows report it */
	free(a->blk), a->blk = NULL;
}

void c0_cov_acc_drop_rows(struct c0_cov_acc *a, int y1)
{
	y1 = y1 < a->H ? y1 : a->H;
	if (y1 <= a->dropped)
		return;
	a->dropped = y1;
	/* the whole pages inside rows [0, y1) of each lag's plane; the sums
	 * are not read again, so the pages need not keep their contents */
	const uintptr_t pg = (uintptr_t)sysconf(_SC_PAGESIZE);
	const size_t n = (size_t)a->W * a->H;
	for (int l = 0; l < a->nlag; l++) {
		const uintptr_t b = (uintptr_t)(a->sum + (size_t)l * n), e = (uintptr_t)(a->sum + (size_t)l * n + (size_t)y1 * a->W);
		const uintptr_t pb = (b + pg - 1) / pg * pg, pe = e / pg * pg;
		if (pe > pb)
			madvise((void *)pb, pe - pb, MADV_DONTNEED);
	}
}

int c0_cov_acc_window_even(struct c0_cov_acc *all, struct c0_cov_acc *odd, int y0, int x0, struct c0_cov *out)
{
	memset(out, 0, sizeof *out);
	const int h = odd->H, w = odd->W;
	const int64_t To = odd->frames, Te = all->frames - To;
	if (all->seg_sum || odd->seg_sum)
		return c0_fail(C0_EINVAL, "covariance: the even frames of several segments are not derived (accumulate them)");
	if (Te < 3 || To < 3 || Te - To < 0 || Te - To > 1 || odd->d != all->d)
		return c0_fail(C0_EINVAL, "covariance: %lld and %lld frames are not the even and odd halves of a stack",
			       (long long)all->frames, (long long)To);
	if (y0 < 0 || x0 < 0 || y0 + h > all->H || x0 + w > all->W)
		return c0_fail(C0_EINVAL, "covariance: window %dx%d at (%d, %d) outside %dx%d", w, h, x0, y0, all->W, all->H);
	int st = flush(all);
	if (st || (st = flush(odd)))
		return st;
	struct c0_cov *c = out;
	c->W = w, c->H = h, c->d = all->d, c->nlag = all->nlag, c->frames = Te;
	const size_t n = (size_t)w * h, N = (size_t)all->W * all->H;
	c->dy = c0_alloc((size_t)c->nlag, sizeof(int));
	c->dx = c0_alloc((size_t)c->nlag, sizeof(int));
	c->r = c0_alloc((size_t)c->nlag * n, sizeof(double));
	c->mean = c0_alloc(n, sizeof(double));
	double *s1 = c0_alloc(n, sizeof *s1), *dl = c0_alloc(n, sizeof *dl), *tr = c0_alloc(n, sizeof *tr);
	if (!c->dy || !c->dx || !c->r || !c->mean || !s1 || !dl || !tr) {
		free(s1), free(dl), free(tr);
		c0_cov_free(c);
		return c0_fail(C0_ENOMEM, "covariance: out of memory for a %dx%d window x %d lags", w, h, all->nlag);
	}
	memcpy(c->dy, all->dy, sizeof(int) * (size_t)c->nlag);
	memcpy(c->dx, all->dx, sizeof(int) * (size_t)c->nlag);
	/* all's sums are of y - a (a: frame 0), odd's of y - b (b: frame 1, its
	 * frame j is frame 2j + 1); with delta = b - a the odd frames' sums in
	 * all's shift are S1 + To delta, sum t (y - a) = 2 St + S1 + To^2 delta,
	 * and the products SB + delta' S1 + delta S1' + To delta delta'. The rest
	 * are the even frames, whose own index is t / 2: the same sums as an
	 * accumulator of the even frames alone would hold. */
	const double T = (double)Te, tbar = (T - 1) / 2, Stt = T * (T * T - 1) / 12, to = (double)To;
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++) {
			const size_t k = (size_t)(y0 + y) * all->W + x0 + x, i = (size_t)y * w + x;
			dl[i] = odd->shift[i] - all->shift[k];
			s1[i] = odd->s1[i];
			const double S1 = all->s1[k] - (odd->s1[i] + to * dl[i]);
			const double St = (all->st[k] - (2 * odd->st[i] + odd->s1[i] + to * to * dl[i])) / 2;
			c->mean[i] = S1 / T;
			tr[i] = (St - tbar * S1) / sqrt(Stt);
		}
	for (int l = 0; l < c->nlag; l++) {
		const int dy = c->dy[l], dx = c->dx[l];
		for (int y = 0; y + dy < h; y++)
			for (int x = dx < 0 ? -dx : 0; x < (dx > 0 ? w - dx : w); x++) {
				size_t i = (size_t)y * w + x, j = (size_t)(y + dy) * w + x + dx;
				double so = odd->sum[(size_t)l * n + i] + dl[j] * s1[i] + dl[i] * s1[j] + to * dl[i] * dl[j];
				double s = all->sum[(size_t)l * N + (size_t)(y0 + y) * all->W + x0 + x] - so;
				c->r[(size_t)l * n + i] = (s - T * c->mean[i] * c->mean[j] - tr[i] * tr[j]) / (T - 2);
			}
	}
	for (int y = 0; y < h; y++)
		for (int x = 0; x < w; x++)
			c->mean[(size_t)y * w + x] += all->shift[(size_t)(y0 + y) * all->W + x0 + x];
	free(s1), free(dl), free(tr);
	subtract_noise(all, y0, x0, c);
	st = all->guard > 0 ? c0_cov_guard(c, all->guard, NULL) : C0_OK;
	if (st)
		c0_cov_free(c);
	return st;
}

int c0_cov_acc_finish(struct c0_cov_acc *a, struct c0_cov *out)
{
	int st = c0_cov_acc_window(a, 0, 0, a->H, a->W, out);
	c0_cov_acc_free(a);
	return st;
}
