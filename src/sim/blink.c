/* Two-state photophysics integrated within each frame. */
#include "sim/sim.h"
#include "core/rng.h"

#include <math.h>

void c0_sim_blink(const struct c0_sim_conf *c, uint64_t stream, int frames, float *on)
{
	struct c0_rng r;
	c0_rng_init(&r, c->seed, stream);
	const double ton = c->tau_on_ms * 1e-3, toff = c->tau_off_ms * 1e-3, dt = 1 / c->fps;
	double bleach = c->tau_bleach_s > 0 ? c0_rng_exp(&r, c->tau_bleach_s) : INFINITY;
	int state = c0_rng_uniform(&r) < ton / (ton + toff);   /* stationary start */
	/* exponential lifetimes are memoryless, so the first dwell is a full draw */
	double t = 0, next = c0_rng_exp(&r, state ? ton : toff);
	for (int f = 0; f < frames; f++) {
		double end = (f + 1) * dt, acc = 0;
		while (t < end) {
			double upto = fmin(fmin(next, end), bleach);
			if (state && upto > t)
				acc += upto - t;
			t = fmax(t, upto);
			if (t >= bleach) {
				t = end;
				state = 0;
				next = INFINITY;
				break;
			}
			if (t >= next) {
				state = !state;
				next = t + c0_rng_exp(&r, state ? ton : toff);
			}
		}
		on[f] = (float)(acc / dt);
	}
}

double c0_sim_onfrac_variance(const struct c0_sim_conf *c)
{
	/* time average over D of a telegraph process: p(1-p) * 2 (tc/D)^2 (D/tc - 1 + e^{-D/tc}) */
	double ton = c->tau_on_ms * 1e-3, toff = c->tau_off_ms * 1e-3, D = 1 / c->fps;
	double p = ton / (ton + toff), tc = ton * toff / (ton + toff), x = D / tc;
	return p * (1 - p) * 2 / (x * x) * (x - 1 + exp(-x));
}
