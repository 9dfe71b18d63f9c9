/* Lateral drift of a run: estimated from block means of the frames by
 * cross-correlation with the first block of the first stack (sub-pixel peak),
 * continued across the stacks in their order, and undone frame by frame in
 * the streaming passes (a c0_frame_fn, see stages/support.h).
 *
 * The blocks are first chained (each against the one before), then refined
 * against the other blocks of their stack moved back; each stack is then
 * joined to the one before by continuity (no correlation across angles,
 * whose images differ). The blocks' shifts are linearly interpolated
 * between block centres (and extrapolated from the nearest two beyond them)
 * to every frame. An axis whose shifts all stay within 6 sds of the
 * estimates' own noise (the joins' included) is left uncorrected (undoing
 * noise only adds jitter). */
#pragma once
#include <stddef.h>
#include <stdint.h>

struct c0_drift_conf {
	int block;          /* 50 frames per block mean (fewer when a stack has < 2 blocks) */
};
#define C0_DRIFT_DEFAULTS { 50 }

struct c0_drift;

struct c0_frames;
/* One streaming pass over each stack (n of them, same size, in acquisition
 * order). Errors: a stack too short to hold two blocks of >= 5 frames; a
 * shift beyond a quarter of the field (the correlation cannot be trusted there). */
int c0_drift_estimate(const struct c0_drift_conf *c, struct c0_frames *f, int n, struct c0_drift **out);
void c0_drift_free(struct c0_drift *d);
/* The frame hook for stack q: pass c0_drift_frame_fn with this context. */
void *c0_drift_hook(struct c0_drift *d, int q);
int c0_drift_frame_fn(void *ctx, int64_t t, float *frame, int H, int W);
/* Shift of frame t of stack q in pixels (content position minus the first block's). */
void c0_drift_at(const struct c0_drift *d, int q, int64_t t, double *dx, double *dy);

struct c0_drift_info {
	int stacks, blocks, block;  /* blocks over all stacks */
	int64_t frames;             /* over all stacks */
	const int64_t *stack_frames;
	const double *bt, *bx, *by; /* block centre (frame index over all stacks), shift (px) */
	double max_px, seconds;
	double noise_px[2];         /* sd of one block's shift (x, y), from second differences */
	int corrected[2];           /* 0: the axis' drift stayed within 6 noise sds, left uncorrected */
};
void c0_drift_get_info(const struct c0_drift *d, struct c0_drift_info *out);
