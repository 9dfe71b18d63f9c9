/* Checks of the input stacks made before any heavy work: each stack is
 * opened once (headers only), so that a bad size, calibration or frame
 * count is refused in a second, not after another stack's solve. */
#pragma once
#include <stdint.h>

struct c0_inputs {
	int n;                     /* stacks after channel expansion */
	char **names;              /* FILE, or FILE:cK for channel K of a multi-channel file */
	int64_t width, height;     /* common to all stacks */
	int64_t min_frames;        /* fewest frames of any stack */
	double pixel_nm;           /* --pixel-size, else the stacks' common calibration (0: none) */
};

/* Fills in from the nargs files in args: a multi-channel file gives one
 * stack per channel, in order (or only channel `channel` when >= 1).
 * Refuses, with one line naming the file or option and the value: a file
 * that does not open, stacks of different sizes, fewer than min_frames
 * frames, more than max_stacks stacks, an outdir that holds an input, and
 * a pixel size that is not positive: pixel_opt (NaN: not given) must be a
 * positive finite number of nm; without it the calibrations must agree
 * (and exist when need_pixel). */
int c0_inputs_check(struct c0_inputs *in, char **args, int nargs, int channel, double pixel_opt, int need_pixel,
		    int64_t min_frames, int max_stacks, const char *outdir);
void c0_inputs_free(struct c0_inputs *in);
