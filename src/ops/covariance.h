/* Banded spatial covariance of a stack, streamed frame by frame.
 *
 * Only pixel pairs within the lag radius d per axis are kept, and only half
 * of them (R is symmetric): lags (dy, dx) with dy > 0, or dy = 0 and dx >= 0.
 * r[l][y][x] = cov(pixel (y, x), pixel (y + dy_l, x + dx_l)) over time, each
 * pixel's mean and linear trend in time removed (a fade would otherwise add
 * to every covariance), normalised by T - 2; 0 where the partner falls outside. */
#pragma once
#include <stdint.h>

struct c0_cov {
	int W, H, d, nlag;
	int *dy, *dx;          /* nlag lags; lag 0 is (0, 0) */
	double *r;             /* nlag * H * W */
	double *mean;          /* H * W temporal mean */
	int64_t frames;
};

struct c0_cov_acc;

int c0_cov_acc_new(int W, int H, int d, struct c0_cov_acc **out);
int c0_cov_acc_add(struct c0_cov_acc *a, const float *frame);
/* Finishes (needs >= 3 frames) and frees the accumulator. */
int c0_cov_acc_finish(struct c0_cov_acc *a, struct c0_cov *out);
void c0_cov_acc_free(struct c0_cov_acc *a);
void c0_cov_free(struct c0_cov *c);
/* Weight of lag l in the Frobenius product over the full band (2 off the diagonal). */
static inline double c0_cov_weight(const struct c0_cov *c, int l) { return c->dy[l] == 0 && c->dx[l] == 0 ? 1 : 2; }
