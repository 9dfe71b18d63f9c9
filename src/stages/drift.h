/* Lateral drift of a run: estimated from block means of the frames by
 * cross-correlation (sub-pixel peak) and undone frame by frame in the
 * streaming passes (a c0_frame_fn, see stages/support.h).
 *
 * The block means are filtered by the PSF before they are correlated
 * (psf_sigma_px: a camera's fixed pattern, which does not move, then
 * weighs less). Each stack's blocks are first chained (each against the one before),
 * then refined against the other blocks of their stack moved back; there
 * is no correlation across angles, whose images differ. Stacks recorded one
 * after another are then joined, in recording order, each to the one before
 * by continuity; stacks recorded frame by frame in turn (interleaved) share
 * one clock, and the trajectory is their mean, each at its own level. The
 * blocks' shifts are linearly interpolated between block centres (and
 * extrapolated from the nearest two beyond them) to every frame. An axis
 * whose shifts all stay within 6 sds of the estimates' own noise (the joins'
 * included) is left uncorrected (undoing noise only adds jitter). */
#pragma once
#include <stddef.h>
#include <stdint.h>

#define C0_DRIFT_MAX 64

struct c0_drift_conf {
	int block;          /* 50 frames per block mean (fewer when a stack has < 2 blocks) */
	int interleaved;    /* 0: stacks recorded one after another; 1: frame t of every stack in turn (same frame counts) */
	double start[C0_DRIFT_MAX];   /* stack q's first frame on the acquisition's clock, in frames (stages/bleach.h's */
	int nstart;                   /* c0_bleach_clock: order and gaps); nstart 0: one after another as given */
	double psf_sigma_px;          /* 0: the block means correlated as they are; > 0: both filtered by this PSF */
	int read_ahead;               /* 0: frames read ahead in batches of 32 MiB; > 0: this many frames a batch */
};
#define C0_DRIFT_DEFAULTS { 50, 0, { 0 }, 0, 0, 0 }

struct c0_drift;

struct c0_frames;
/* One streaming pass over each stack (n of them, same size). Errors: a
 * stack too short to hold two blocks of >= 5 frames; interleaved stacks of
 * different block counts; a shift beyond a quarter of the field (the
 * correlation cannot be trusted there). */
int c0_drift_estimate(const struct c0_drift_conf *c, struct c0_frames *f, int n, struct c0_drift **out);
void c0_drift_free(struct c0_drift *d);
/* The frame hook for stack q: pass c0_drift_frame_fn with this context. */
void *c0_drift_hook(struct c0_drift *d, int q);
int c0_drift_frame_fn(void *ctx, int64_t t, float *frame, int H, int W);
/* Shift of frame t of stack q in pixels (content position minus the first block's). */
void c0_drift_at(const struct c0_drift *d, int q, int64_t t, double *dx, double *dy);

/* var (H x W: independent pixels' variances, a camera's read noise) as
 * stack q's corrected frames see it: moved and spread with each frame's
 * shift (ops/fshift.h's c0_fshift_variance), averaged over the stack's
 * frames; the shifts taken to 1/8 pixel. */
int c0_drift_variance(const struct c0_drift *d, int q, const float *var, float *out);
/* img (H x W: a camera's fixed pattern, its dark levels) as stack q's
 * corrected frames see it: moved with each frame's shift and averaged over
 * the stack's frames (shifts to 1/8 pixel, as above). */
int c0_drift_image(const struct c0_drift *d, int q, const float *img, float *out);
/* img, an image of stack q's corrected frames, back where the camera saw
 * it: moved back by the stack's mean shift, in place. */
int c0_drift_unmove(const struct c0_drift *d, int q, float *img);

struct c0_drift_info {
	int stacks, blocks, block;  /* blocks over all stacks */
	double frames;              /* the acquisition clock's length (frames) */
	const int64_t *stack_frames;
	const double *start;        /* stack q's first frame on the clock */
	const double *bt, *bx, *by; /* block centre (on the clock), shift (px) */
	double max_px, seconds;
	double noise_px[2];         /* sd of one block's shift (x, y), from second differences */
	int corrected[2];           /* 0: the axis' drift stayed within 6 noise sds, left uncorrected */
};
void c0_drift_get_info(const struct c0_drift *d, struct c0_drift_info *out);
