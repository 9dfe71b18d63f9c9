/* The covariance fit of COL0RME as a smooth objective for the solvers:
 *   f(x) = min_{s >= 0} 1/2 ||R - A x - s I||_F^2
 * over the lag band (A: ops/covop.h), s in closed form, from C = A^T R,
 * tr R and ||R||^2 alone; on the whole grid and on a working set of pixels
 * (ops/covnormal.h), with the l1 problem's duality gap. */
#pragma once
#include "ops/covnormal.h"

struct c0_covfit {
	struct c0_covop *op;
	const double *C;     /* A^T R, Ly x Lx */
	double trR, R2, HW;  /* tr R, ||R||^2 (the band's weights), the pixel count */
	double *Ax;          /* Ly x Lx: A^T A x of the last whole-grid call */
	double lam;          /* the l1 weight (for the gap) */
	double *part;        /* 4 per C0_SUM_BLOCK of the grid: the sums' blocks */
};

/* f(x) and its gradient g on the whole grid (c0_fista_nn's smooth term). */
double c0_covfit_smooth(void *fit, const double *x, double *g);
/* Relative duality gap (P - D) / P of f + lam ||x||_1 at x >= 0. */
double c0_covfit_gap(void *fit, const double *x);

/* The same on a working set: x and g hold only the set's pixels, the
 * others are 0. */
struct c0_covfit_ws {
	struct c0_covfit *f;
	struct c0_covnormal N;
	double *cw, *nw;     /* C and the column norms at the set's pixels */
};
int c0_covfit_ws_init(struct c0_covfit_ws *w, struct c0_covfit *f);
void c0_covfit_ws_free(struct c0_covfit_ws *w);
/* The set := the pixels with in[i], in grid order; xw := x on it. */
int c0_covfit_ws_set(struct c0_covfit_ws *w, const uint8_t *in, const double *x, double *xw);
/* v := the set's values vw on the grid, 0 elsewhere. */
void c0_covfit_ws_scatter(const struct c0_covfit_ws *w, const double *vw, double *v);
double c0_covfit_ws_smooth(void *ws, const double *xw, double *gw);
/* A step for the set: min(lip, the largest row sum of A^T A on it), which
 * bounds its largest eigenvalue there (Gershgorin; A^T A >= 0 entrywise).
 * one and g: workspaces of the set's size. */
double c0_covfit_ws_lip(struct c0_covfit_ws *w, double lip, double *one, double *g);
