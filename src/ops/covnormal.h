/* A^T A of the covariance operator (ops/covop.h) restricted to a working
 * set of fine pixels: N = P A^T A P, P the set's selection. Vectors hold
 * only the set's pixels (in grid order); the others are 0. It costs 2 band
 * products per pixel of the set instead of per grid pixel: a support is a
 * few percent of the grid. Cache-blocked: each thread takes a band of
 * output rows and holds only the rows of T = V Hx those rows reach, and the
 * numbers do not depend on the thread count. */
#pragma once
#include "ops/covop.h"

#include <stddef.h>
#include <stdint.h>

struct c0_covnormal_buf;

struct c0_covnormal {
	const struct c0_covop *op;   /* its Hy, Hx (not owned) */
	size_t *ws;          /* the set's grid indices */
	size_t nws;
	size_t *rs;          /* Ly + 1: row a's runs are run[rs[a]..rs[a+1]) */
	size_t *run;         /* runs of adjacent columns: ws[run[j]..run[j+1]) */
	int *col;            /* column of each ws pixel */
	size_t *rg;          /* Ly + 1: row a's groups are grp[rg[a]..rg[a+1]) */
	size_t *grp;         /* groups of up to 4 adjacent pixels of a run: ws[grp[g]..grp[g + 1]) */
	int nbuf;            /* threads that may share a product */
	struct c0_covnormal_buf *buf;   /* one each */
};

/* For op's grid (an empty set); inside a parallel region the products run
 * on the calling thread alone. */
int c0_covnormal_init(struct c0_covnormal *N, const struct c0_covop *op);
void c0_covnormal_free(struct c0_covnormal *N);
/* The set := the pixels i with in[i] != 0 (Ly x Lx), in grid order. */
void c0_covnormal_set(struct c0_covnormal *N, const uint8_t *in);
/* out = N v: v and out hold the set's N->nws pixels. */
void c0_covnormal_apply(struct c0_covnormal *N, const double *v, double *out);
