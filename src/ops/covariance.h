/* Banded spatial covariance of a stack, streamed frame by frame.
 *
 * Only pixel pairs within the lag radius d are kept (dy^2 + dx^2 <= d^2: a
 * pair r apart holds at most exp(-r^2 / 4 sigma^2) of an emitter's signal,
 * 1e-4 at the support's d = 6 sigma, 1.5e-8 at the corners of the square the
 * disk leaves out; 57 lags instead of 85 at d = 6), and only half of them (R
 * is symmetric): lags (dy, dx) with dy > 0, or dy = 0 and dx >= 0.
 * r[l][y][x] = cov(pixel (y, x), pixel (y + dy_l, x + dx_l)) over time, each
 * pixel's mean and linear trend in time removed (a fade would otherwise add
 * to every covariance), normalised by T - 2; 0 where the partner falls outside.
 * The accumulator holds float sums of products of values shifted by the
 * first frame, added in double a block of frames at a time (relative
 * rounding ~1e-7, far below the covariance's own sampling error): the
 * band of a 2048x2048 frame then fits in 1.4 GB (lag 6). */
#pragma once
#include <stddef.h>
#include <stdint.h>

struct c0_cov {
	int W, H, d, nlag;
	int *dy, *dx;          /* nlag lags; lag 0 is (0, 0) */
	double *r;             /* nlag * H * W */
	double *mean;          /* H * W temporal mean */
	int64_t frames;
	double dof;            /* degrees of freedom of r, where pooled from sets (c0_cov_pool_add); 0: frames - 2 */
};

struct c0_cov_acc;

int c0_cov_acc_new(int W, int H, int d, struct c0_cov_acc **out);
/* The number of lags kept for radius d. */
int c0_cov_lag_count(int d);
int c0_cov_acc_add(struct c0_cov_acc *a, const float *frame);
/* The covariance of the window (rows y0..y0+h-1, columns x0..x0+w-1) as if
 * the stack had only those pixels (pairs leaving the window are 0). The
 * accumulator is kept: windows of one image are cut from one pass. */
int c0_cov_acc_window(struct c0_cov_acc *a, int y0, int x0, int h, int w, struct c0_cov *out);
/* The window's covariance over the even frames only, from an accumulator
 * of all frames and one of the odd frames (frames 1, 3, ...) of that window
 * alone (odd's size): the same sums as an accumulator of the even frames,
 * up to the float sums' rounding. Both are kept. */
int c0_cov_acc_window_even(struct c0_cov_acc *all, struct c0_cov_acc *odd, int y0, int x0, struct c0_cov *out);
/* Windows cut from a then guard each pixel's variance (lag 0) against noise
 * of its own (sCMOS random-telegraph or hot pixels), which the model's single
 * noise variance would not explain. Over its 4 neighbours j in the window, a
 * point source's variance in the pixel is at most S = mean_j R_ij / g (g from
 * the PSF, at most 1), and its noise about N = median_j R_jj; a variance above
 * S + N (1 + C0_COV_GUARD_Z sqrt(2 / (T - 2))), beyond the sampling error of
 * T frames, is set to S + N. g = 0: no guard (the default). */
#define C0_COV_GUARD_Z 4.0
void c0_cov_acc_set_guard(struct c0_cov_acc *a, double g);
/* A per-pixel noise variance map (camera read noise, map_w wide; this
 * accumulator's pixel (0, 0) is its (y0, x0)) subtracted from every window's
 * lag 0 before the guard: the model's single noise variance then meets an
 * even noise. The map must outlive a. */
void c0_cov_acc_set_noise(struct c0_cov_acc *a, const float *map, int map_w, int x0, int y0);
/* Only where keep (H x W, this accumulator's pixels) are the lags other
 * than (0, 0), (0, 1) and (1, 0) summed; windows hold 0 for them elsewhere.
 * For a fit that reads them only near a known support (the noise variance
 * on it): every value kept is the one without a region, bit for bit, at a
 * fraction of the cost. Before the first frame. */
int c0_cov_acc_set_region(struct c0_cov_acc *a, const uint8_t *keep);
/* The same on a finished covariance; *set (or NULL): how many variances it set. */
int c0_cov_guard(struct c0_cov *c, double g, size_t *set);
/* Temporal variance of one pixel so far (NaN once a block of frames could
 * not be added for want of memory). */
double c0_cov_acc_variance(struct c0_cov_acc *a, int y, int x);
/* Adds the frames still in the block and gives the block's memory back (up
 * to 64 MB, next to the tiles' solves); call it before cutting windows from
 * several threads (they then only read). A later frame allocates it again.
 * Should adding the block fail (memory), the windows report it. */
void c0_cov_acc_seal(struct c0_cov_acc *a);
/* Rows [0, y1) will not be read again (windows below them are all cut):
 * their sums' memory goes back to the system, so that a tiled solve's
 * results can grow while the band shrinks. Windows from those rows fail. */
void c0_cov_acc_drop_rows(struct c0_cov_acc *a, int y1);
/* Frames added per pass over the sums for an image of this many pixels (the
 * sums round once per pass). An accumulator over some rows of an image sets
 * the whole image's value, so that it gives the same numbers bit for bit. */
int c0_cov_block_frames(size_t pixels);
int c0_cov_acc_set_block(struct c0_cov_acc *a, int frames);
/* Ends a segment of frames (one stack of several pooled into one
 * covariance): its sums become its own cross-products about its mean and
 * trend, and the next frame starts a segment with its own. Windows then
 * pool the segments: their summed cross-products over their summed degrees
 * of freedom (each T - 2), the mean over all their frames; the noise map
 * set now is the finished segment's (set the next one's before its frames),
 * each subtracted from its segment's lag 0 (c0_cov_acc_variance: none).
 * Before any row is dropped; each segment needs >= 3 frames. */
int c0_cov_acc_next(struct c0_cov_acc *a);
/* Finishes (needs >= 3 frames) and frees the accumulator. */
int c0_cov_acc_finish(struct c0_cov_acc *a, struct c0_cov *out);
void c0_cov_acc_free(struct c0_cov_acc *a);
void c0_cov_free(struct c0_cov *c);
/* Weight of lag l in the Frobenius product over the full band (2 off the diagonal). */
static inline double c0_cov_weight(const struct c0_cov *c, int l) { return c->dy[l] == 0 && c->dx[l] == 0 ? 1 : 2; }
