/* The depth map read out of an MA-TIRF volume. The intensity-weighted mean
 * over bins is biased deep: the solve stops where the objective is flat in
 * the directions that spread a column's mass over neighbouring depths
 * (0.2 % of the objective), and a smeared mix of exponentials has a deeper
 * mean than its single depth (+3.3 nm on noise-free intensities, +4 nm on
 * the 5-angle simulations; docs/method.md#the-depth-readout). The column's
 * projections W f are what the data fix, and they barely move along those
 * directions, so each pixel's depth is the single depth whose exponential
 * fits them best. */
#pragma once
#include "optics/tirf.h"

#include <stddef.h>

/* depth[p] for each of the np columns of f (nz x np, bins of width dz from
 * z0; 0 where the column is empty): the depth z in [z0, z0 + nz dz] that
 * maximises <w(z), y>^2 / |w(z)|^2 with <w(z), y> > 0, y = W f_p the
 * column's projections at the nq angles (W: nq x nz, c0_tirf_weights) and
 * w_q(z) = g_q I0(alpha_q) e^{-p_q z}: on a grid of at most 1 nm, refined by
 * a parabola through the best three. */
int c0_depth_fit(const struct c0_tirf *t, int nq, const double *angles, const double *gain, int nz, double z0,
		 double dz, const float *f, size_t np, float *depth);
/* The same fit on intensities y[q] (np values each) over depths [z0, z0 +
 * range], the angles weighted by 1 / var (nq x np, var[q * np + p] > 0;
 * c0_depth_noise), or alike with var NULL: the inner products are then
 * <u, v> = sum_q u_q v_q / var_qp. */
int c0_depth_fit_y(const struct c0_tirf *t, int nq, const double *angles, const double *gain, double z0, double range,
		   const float *const *y, size_t np, const float *var, float *depth);

/* The noise of pooled intensities, for a fit that weighs the angles by it
 * (docs/defaults.md#depth_noise_block).
 * Under sparse blinking a pooled intensity's error is mostly the blinking's,
 * a share of the signal that differs from angle to angle; the plain fit
 * weighs every angle by its intensity squared. y[q] (np values each): the
 * pooled intensities; d[q]: the same pooling of a draw of their noise (the
 * intensity of the difference of two halves of the frames). Fitted
 * from the data alone:
 *  - each angle's random variance s_q m_q^2 + c_q, m the plain single-depth
 *    fit's model, by non-negative least squares of d^2 over the pixels;
 *  - one absolute variance more, the systematic misfit (depths mixed in a
 *    pool, crosstalk, a camera's pattern), which the halves share and so
 *    their difference does not hold: what the weighted fit's residuals hold
 *    beyond the random part, each residual's expectation taken through the
 *    fit's projector. Where the residuals are mostly misfit it dominates
 *    and the weights stay near equal.
 * var[q * np + p] := s_q m_qp^2 + c_q + sys (depth range [z0, z0 + range]). */
/* A run reads the pooled intensities with these weights only where the
 * halves' noise explains most of the residuals (resid_ratio at most this:
 * two thirds of them noise or more, as under sparse blinking at 1.1-1.5);
 * where the misfit is the larger part (dense or standard blinking at 500
 * frames: 2.5-8.5) the weights are near equal and the MA-TIRF volume's
 * projections, smoothed across pixels, read better
 * (docs/defaults.md#depth_noise_block). */
#define C0_DEPTH_NOISE_RATIO 1.5
#define C0_DEPTH_MAXQ 64     /* angles a depth fit takes */
struct c0_depth_noise {
	int nq;
	double rel_sd[C0_DEPTH_MAXQ];     /* sqrt(s_q): the random noise's relative sd per angle */
	double abs_share[C0_DEPTH_MAXQ];  /* c_q / (s_q mean m_q^2): its absolute part's share */
	double sys_var;        /* the systematic variance */
	double resid_ratio;    /* the weighted fit's squared residuals over the random part's expectation */
	size_t pixels;         /* the pixels fitted */
};
int c0_depth_noise(const struct c0_tirf *t, int nq, const double *angles, const double *gain, double z0, double range,
		   const float *const *y, const float *const *d, size_t np, float *var, struct c0_depth_noise *out);
