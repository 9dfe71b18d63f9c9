/* The render (render.c). */
#pragma once
#include "app/result.h"

/* render: each intensity splatted with a Gaussian of the support's
 * localisation precision (at least half a fine pixel; ops/splat.h). */
int c0_step_render(struct c0_result *r);
/* Plane q of the render (Ly x Lx) into plane, after the render step. */
int c0_render_plane(const struct c0_result *r, int q, float *plane);
