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
