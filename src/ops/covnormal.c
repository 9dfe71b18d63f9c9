#include "ops/covnormal.h"
#include "core/c0math.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/threads.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Rows of T = V Hx held by one thread: row base + j in slot j, zero outside
 * the columns [lo[j], hi[j]) its last scatter wrote. Three bands' worth of
 * rows and a gather block's: the rows kept are moved down about once per
 * two bands of output rows. */
#define BUF_BANDS 3
struct c0_covnormal_buf {
	int rows;
	double *T;           /* rows x TLD */
	int *lo, *hi;
	struct gitem *it;    /* GATHER_ROWS x GATHER_COLS */
};
/* The gather goes through blocks of output rows and columns, so that the
 * part of T it reads stays in the first-level cache. */
#define GATHER_ROWS 16
#define GATHER_COLS 96
/* one group of the set to gather: its column of T from the band's first
 * row, its band row of Hy, the group */
struct gitem {
	const double *t, *h;
	size_t g;
};

/* T's row stride: 3 columns past the grid's, never written, so that a group
 * of 4 at the row's end reads its lanes within the row */
#define TLD(Lx) ((size_t)(Lx) + 3)

static void ws_index(struct c0_covnormal *w)
{
	const int Ly = w->op->Ly, Lx = w->op->Lx;
	size_t k = 0, j = 0, g = 0;
	for (int a = 0; a < Ly; a++) {
		w->rs[a] = j;
		for (; k < w->nws && w->ws[k] < (size_t)(a + 1) * Lx; k++) {
			w->col[k] = (int)(w->ws[k] - (size_t)a * Lx);
			if (k == 0 || w->rs[a] == j || w->ws[k] != w->ws[k - 1] + 1)
				w->run[j++] = k;
		}
	}
	w->rs[Ly] = j, w->run[j] = k;
	for (int a = 0; a < Ly; a++) {
		w->rg[a] = g;
		for (size_t r = w->rs[a]; r < w->rs[a + 1]; r++)
			for (k = w->run[r]; k < w->run[r + 1]; k += 4)
				w->grp[g++] = k;
	}
	w->rg[Ly] = g, w->grp[g] = w->nws;
}

int c0_covnormal_init(struct c0_covnormal *w, const struct c0_covop *op)
{
	const size_t Ly = (size_t)op->Ly, L = Ly * op->Lx;
	/* inside another team (tiles side by side) the set's loops run alone */
	const int nbuf = c0_threads_here();
	*w = (struct c0_covnormal){ op, c0_alloc(L, sizeof(size_t)), 0, c0_alloc(Ly + 1, sizeof(size_t)),
				    c0_alloc(L + 1, sizeof(size_t)), c0_alloc(L, sizeof(int)), c0_alloc(Ly + 1, sizeof(size_t)),
				    c0_alloc(L + 1, sizeof(size_t)), nbuf, c0_alloc((size_t)nbuf, sizeof *w->buf) };
	int ok = w->ws && w->rs && w->run && w->col && w->rg && w->grp && w->buf;
	for (int i = 0; ok && i < nbuf; i++) {
		struct c0_covnormal_buf *b = &w->buf[i];
		b->rows = BUF_BANDS * op->Hy.w + GATHER_ROWS;
		b->T = c0_alloc((size_t)b->rows * TLD(op->Lx), sizeof(double));
		b->lo = c0_alloc((size_t)b->rows, sizeof(int)), b->hi = c0_alloc((size_t)b->rows, sizeof(int));
		b->it = c0_alloc(GATHER_ROWS * GATHER_COLS, sizeof *b->it);
		ok = b->T && b->lo && b->hi && b->it;
		for (int j = 0; ok && j < b->rows; j++)
			b->lo[j] = op->Lx, b->hi[j] = 0;
	}
	return ok ? C0_OK : C0_ENOMEM;
}

void c0_covnormal_free(struct c0_covnormal *w)
{
	free(w->ws), free(w->rs), free(w->run), free(w->col), free(w->rg), free(w->grp);
	for (int i = 0; w->buf && i < w->nbuf; i++)
		free(w->buf[i].T), free(w->buf[i].lo), free(w->buf[i].hi), free(w->buf[i].it);
	free(w->buf);
	memset(w, 0, sizeof *w);
}

void c0_covnormal_set(struct c0_covnormal *w, const uint8_t *in)
{
	const size_t L = (size_t)w->op->Ly * w->op->Lx;
	w->nws = 0;
	for (size_t i = 0; i < L; i++)
		if (in[i])
			w->ws[w->nws++] = i;
	ws_index(w);
}


/* Row a of T = V Hx: the set's non-zero pixels in row a, scattered (Hx
 * symmetric: row b of Hx is its column b); [lo, hi) the columns written. */
C0_HOT static void ws_row_scatter(const struct c0_covnormal *w, const struct c0_band *Hx, int a, const double *v,
				  double *t, int *lo, int *hi)
{
	for (size_t k = w->run[w->rs[a]]; k < w->run[w->rs[a + 1]]; k++) {
		if (v[k] == 0)
			continue;
		const int s = Hx->start[w->col[k]];
		const double vk = v[k], *h = Hx->v + (size_t)w->col[k] * Hx->w;
		double *tb = t + s;
		for (int u = 0; u < Hx->w; u++)
			tb[u] += vk * h[u];
		*lo = *lo < s ? *lo : s, *hi = *hi > s + Hx->w ? *hi : s + Hx->w;
	}
}

/* out = Hy T at the groups it[0..n): a column dot product per pixel, a
 * group of 4 adjacent pixels of a run in one vector, and four groups side
 * by side, whose sums are independent chains: one chain of Hy->w dependent
 * additions is bound by the addition's latency. Each lane sums in the
 * order of a scalar loop over u, so the grouping does not change a bit. */
static inline void put_group(const struct c0_covnormal *w, size_t g, const c0_v4 *ax, double *out)
{
	for (size_t k = w->grp[g]; k < w->grp[g + 1]; k++)
		out[k] = (*ax)[k - w->grp[g]];
}
C0_HOT static void ws_gather(const struct c0_covnormal *w, int hw, size_t ld, const struct gitem *it, int n,
			     double *out)
{
	int i = 0;
	for (; i + 4 <= n; i += 4) {
		const double *t0 = it[i].t, *t1 = it[i + 1].t, *t2 = it[i + 2].t, *t3 = it[i + 3].t;
		const double *h0 = it[i].h, *h1 = it[i + 1].h, *h2 = it[i + 2].h, *h3 = it[i + 3].h;
		c0_v4 a0 = { 0, 0, 0, 0 }, a1 = a0, a2 = a0, a3 = a0, v0, v1, v2, v3;
		for (int u = 0; u < hw; u++) {
			const size_t o = (size_t)u * ld;
			memcpy(&v0, t0 + o, sizeof v0), memcpy(&v1, t1 + o, sizeof v1);
			memcpy(&v2, t2 + o, sizeof v2), memcpy(&v3, t3 + o, sizeof v3);
			a0 += h0[u] * v0, a1 += h1[u] * v1, a2 += h2[u] * v2, a3 += h3[u] * v3;
		}
		put_group(w, it[i].g, &a0, out), put_group(w, it[i + 1].g, &a1, out);
		put_group(w, it[i + 2].g, &a2, out), put_group(w, it[i + 3].g, &a3, out);
	}
	for (; i < n; i++) {
		c0_v4 ax = { 0, 0, 0, 0 }, tu;
		for (int u = 0; u < hw; u++) {
			memcpy(&tu, it[i].t + (size_t)u * ld, sizeof tu);
			ax += it[i].h[u] * tu;
		}
		put_group(w, it[i].g, &ax, out);
	}
}

/* Slot j of b (row base + j of T) := row r of T: cleared, then scattered */
static void buf_scatter(const struct c0_covnormal *w, struct c0_covnormal_buf *b, int j, int r, const double *v)
{
	const int Lx = w->op->Lx;
	double *t = b->T + (size_t)j * TLD(Lx);
	if (b->hi[j] > b->lo[j])
		memset(t + b->lo[j], 0, sizeof *t * (size_t)(b->hi[j] - b->lo[j]));
	b->lo[j] = Lx, b->hi[j] = 0;
	ws_row_scatter(w, &w->op->Hx, r, v, t, &b->lo[j], &b->hi[j]);
}

/* Slot j := slot k's row (k > j) */
static void buf_move(struct c0_covnormal_buf *b, int j, int k, int Lx)
{
	double *t = b->T + (size_t)j * TLD(Lx);
	const double *f = b->T + (size_t)k * TLD(Lx);
	if (b->hi[j] > b->lo[j])
		memset(t + b->lo[j], 0, sizeof *t * (size_t)(b->hi[j] - b->lo[j]));
	if (b->hi[k] > b->lo[k])
		memcpy(t + b->lo[k], f + b->lo[k], sizeof *t * (size_t)(b->hi[k] - b->lo[k]));
	b->lo[j] = b->lo[k], b->hi[j] = b->hi[k];
}

/* T = V Hx row by row, then Hy T at the set's pixels row by row. Each
 * thread takes a band of output rows and holds only the rows of T that its
 * next output rows reach (struct c0_covnormal_buf), so that they stay in
 * cache: the whole T, as large as the grid, went through memory three times
 * per product (cleared, scattered, gathered). A row of
 * T is made the same way wherever it is held, and each output from it in
 * the same order, so the numbers do not depend on the thread count. */
void c0_covnormal_apply(struct c0_covnormal *w, const double *v, double *out)
{
	const struct c0_covop *op = w->op;
	const struct c0_band *Hy = &op->Hy;
	const int Ly = op->Ly, Lx = op->Lx;
	const int par = w->nws > 20000 && w->nbuf > 1;
#pragma omp parallel num_threads(w->nbuf) if (par)
	{
		const int nt = omp_get_num_threads(), id = omp_get_thread_num();
		const int a0 = (int)((long long)Ly * id / nt), a1 = (int)((long long)Ly * (id + 1) / nt);
		struct c0_covnormal_buf *b = &w->buf[id];
		const size_t ld = TLD(Lx);
		int base = a0 < a1 ? Hy->start[a0] : 0, next = base;   /* slots hold rows [base, next) */
		for (int a = a0; a < a1; a += GATHER_ROWS) {
			const int ae = a + GATHER_ROWS < a1 ? a + GATHER_ROWS : a1;
			const int s = Hy->start[a], need = Hy->start[ae - 1] + Hy->w;
			if (need - base > b->rows) {    /* slide: rows [s, next) to the first slots */
				for (int r = s; r < next; r++)
					buf_move(b, r - s, r - base, Lx);
				base = s, next = next > s ? next : s;
			}
			for (; next < need; next++)
				buf_scatter(w, b, next - base, next, v);
			size_t cur[GATHER_ROWS];
			for (int r = a; r < ae; r++)
				cur[r - a] = w->rg[r];
			for (int c0 = 0; c0 < Lx; c0 += GATHER_COLS) {
				int n = 0;
				for (int r = a; r < ae; r++) {
					const double *tb = b->T + (size_t)(Hy->start[r] - base) * ld, *h = Hy->v + (size_t)r * Hy->w;
					size_t *g = &cur[r - a];
					for (; *g < w->rg[r + 1] && w->col[w->grp[*g]] < c0 + GATHER_COLS; ++*g)
						b->it[n++] = (struct gitem){ tb + w->col[w->grp[*g]], h, *g };
				}
				ws_gather(w, Hy->w, ld, b->it, n, out);
			}
		}
	}
}
