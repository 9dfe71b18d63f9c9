/* The intensity step (steps_intensity.c). */
#pragma once
#include "app/result.h"
#include "io/frames.h"

/* Intensity and background of every stack on r->mask: the support step's
 * mean and noise variance where it ran on the stack, else one pass (the
 * mean when sigma2[i] > 0, else the covariance, for the noise variance on
 * the mask). With corrected, keeps each mean minus its background. With
 * share (NULL or one flag per stack, and mu not given), the flagged stacks
 * get one mu, the largest of their discrepancy ones. */
int c0_step_intensity(struct c0_result *r, const struct c0_intensity_conf *ic, const struct c0_support_conf *sc,
		      struct c0_frames *f, const double *sigma2, int corrected, const int *share);
