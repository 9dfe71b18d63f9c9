/* The depth map read out of an MA-TIRF volume. The intensity-weighted mean
 * over bins is biased deep: the solve stops where the objective is flat in
 * the directions that spread a column's mass over neighbouring depths
 * (0.2 % of the objective), and a smeared mix of exponentials has a deeper
 * mean than its single depth (+3.3 nm on noise-free intensities, +4 nm on
 * the 5-angle simulations; docs/parameters.md, "Depth bias"). The column's
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
 * w_q(z) = g_q I0(alpha_q) e^{-p_q z}: on a grid of at most 1 nm, refined
 * by a parabola through the best three. */
int c0_depth_fit(const struct c0_tirf *t, int nq, const double *angles, const double *gain, int nz, double z0,
		 double dz, const float *f, size_t np, float *depth);
