/* Fourier ring correlation of two independent images of the same field
 * (e.g. from the two interleaved halves of the frames), and the resolution
 * where it falls below 1/7 (Nieuwenhuizen et al., Nat Methods 2013). */
#pragma once

struct c0_frc {
	int n;               /* rings, of width 1 / max(H, W) cycles per pixel */
	double *freq;        /* ring centre, cycles per pixel */
	double *corr;        /* FRC per ring (3-ring moving average) */
	double resolution_px;/* 1 / frequency of the first 1/7 crossing; 0: never crosses
			      * (the resolution is finer than 2 pixels) */
};

/* Both images H x W; each is mean-removed and Hann-windowed first. */
int c0_frc_compute(const float *a, const float *b, int H, int W, struct c0_frc *out);
void c0_frc_free(struct c0_frc *f);

/* Localisation precision (sd per axis, pixels) of one estimate from two
 * independent ones on the same grid: every pixel of a is matched to the
 * nearest pixel of b within radius_px; the difference of two estimates has
 * twice the variance of one, so sd = sqrt(mean d^2 / 4). -1 if nothing matches. */
/* Its sums, for images cut in tiles: squared distances (pixels^2) and matches. */
void c0_pair_sums(const unsigned char *a, const unsigned char *b, int H, int W, int radius_px, double *s2, double *n);
double c0_pair_precision(const unsigned char *a, const unsigned char *b, int H, int W, int radius_px);
