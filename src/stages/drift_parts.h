/* The drift stage's insides, shared by its files (not installed):
 *   drift.c         the stacks' block means, the chained first estimates, the trajectory and its use
 *   drift_xcorr.c   the correlation of a block mean against a reference
 *   drift_refine.c  the refinement against each stack's mean and the joins between stacks */
#pragma once
#include "stages/drift.h"
#include "ops/fshift.h"

#include <complex.h>
#include <fftw3.h>

#define MAXQ C0_DRIFT_MAX

struct hook {
	struct c0_drift *d;
	int q;
};

struct c0_drift {
	int nq, nb, block, H, W, interleaved;
	double sigma;                        /* the PSF's sd (pixels): the correlations' filter */
	int64_t frames[MAXQ];                /* per stack */
	double start[MAXQ];                  /* per stack: its first frame on the acquisition's clock */
	int rec[MAXQ], k0[MAXQ + 1];         /* stacks in recording order; the i-th's blocks k0[i]..k0[i+1]-1 */
	double *bt, *bx, *by;
	float **bm;                          /* block means, while estimating */
	double noise_px[2];                  /* sd of a block's shift estimate, per axis */
	int off[2];                          /* axis not corrected: its drift is within the noise */
	double max_px, seconds;
	struct hook hooks[MAXQ];
	struct c0_fshift *sh;
};

/* The correlation set-up: the reference block's spectrum, and the window
 * that keeps the image edges from correlating. The images are zero-padded
 * to PH x PW, enough for the lags up to LY, LX to be those of the linear
 * correlation: a drift beyond a quarter of the field is refused anyway, and
 * padding to twice the image would cost 2.5x the transforms. */
struct xcorr {
	int H, W, PH, PW, LY, LX;
	size_t ns;               /* spectrum length */
	double *win, *re;
	double *lp;              /* the PSF's transfer function on the spectrum (NULL: none) */
	fftw_complex *ref, *sp, *xs;   /* reference, image and cross spectra */
	fftw_plan f, b;
	int borrowed;            /* win, lp and ref are another xcorr's */
};
/* the correlation set-up of an H x W image at the PSF's sd sigma (pixels;
 * 0: no filter), another thread's against the same reference, its end */
int drift_xcorr_init(struct xcorr *x, int H, int W, double sigma);
int drift_xcorr_clone(struct xcorr *y, const struct xcorr *x);
void drift_xcorr_free(struct xcorr *x);
/* windowed, mean-removed spectrum of img into x->sp */
void drift_spectrum(struct xcorr *x, const double *img);
/* shift (px) of the content of img relative to the reference (in_ref: the
 * spectrum of img is to be computed first, else x->sp holds it) */
void drift_shift_of(struct xcorr *x, const double *img, int in_ref, double *dx, double *dy);
/* The chained estimates refined (drift_refine.c): each stack against the
 * mean of its own blocks, the stacks joined, the axes within the noise
 * switched off. */
int drift_refine(struct c0_drift *d);
