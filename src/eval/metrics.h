/* Accuracy metrics against ground truth. */
#pragma once
#include <stdint.h>

struct c0_jaccard {
	int tp, fp, fn;
	double index;       /* tp / (tp + fp + fn); 1 when both are empty */
};

/* One-to-one matching of pixel centres within radius_nm, shortest pairs
 * first, ignoring pixels closer than margin pixels to the border. */
int c0_jaccard_index(const uint8_t *est, const uint8_t *truth, int H, int W, double px_nm,
		     double radius_nm, int margin, struct c0_jaccard *out);
/* 10 log10(max(truth)^2 / MSE) over the pixels at least margin from the border. */
double c0_psnr(const float *est, const float *truth, int H, int W, int margin);

struct c0_depth_err {
	int pixels, truth_pixels;    /* compared; with a true depth */
	double median, mean, bias;   /* |error| median and mean; median signed error (nm) */
};

/* Depth map est (eh x ew, 0 = no signal) against truth (th x tw) on the
 * pixels of truth_mask (NULL: truth > 0) where est has signal. A coarser est
 * whose size divides the truth's is compared pixel for pixel after nearest
 * upsampling (the standard MA-TIRF baseline on the camera grid). */
int c0_depth_error(const float *est, int eh, int ew, const float *truth, const uint8_t *truth_mask, int th, int tw,
		   int margin, struct c0_depth_err *out);
