/* Two-state photophysics integrated within each frame, with bleaching
 * driven by the cumulative ON time (reference/peers.md: the SOFI simulator's
 * model; bleaching is excitation-driven, so an emitter that is off does not
 * bleach). */
#include "sim/sim.h"
#include "core/rng.h"

#include <math.h>
#include <stddef.h>

void c0_sim_blink_slots(const struct c0_sim_conf *c, uint64_t stream, const int64_t *slot, int frames, float *on)
{
	struct c0_rng r;
	c0_rng_init(&r, c->seed, stream);
	const double ton = c->tau_on_ms * 1e-3, toff = c->tau_off_ms * 1e-3, dt = 1 / c->fps;
	double budget = c->tau_bleach_s > 0 ? c0_rng_exp(&r, c->tau_bleach_s) : INFINITY;   /* ON time left */
	int state = c0_rng_uniform(&r) < ton / (ton + toff);   /* stationary start */
	/* exponential lifetimes are memoryless, so the first dwell is a full draw */
	double t = 0, next = c0_rng_exp(&r, state ? ton : toff);
	int64_t s = 0;   /* the slot (frame period) being simulated */
	for (int f = 0; f < frames; f++) {
		const int64_t want = slot ? slot[f] : f;
		double acc = 0;
		for (; s <= want; s++) {
			double end = (double)(s + 1) * dt;
			acc = 0;
			while (t < end && budget > 0) {
				double upto = fmin(next, end);
				if (state && upto - t >= budget) {   /* bleaches during this ON dwell */
					acc += budget;
					budget = 0;
					break;
				}
				if (state)
					acc += upto - t, budget -= upto - t;
				t = upto;
				if (t >= next) {
					state = !state;
					next = t + c0_rng_exp(&r, state ? ton : toff);
				}
			}
			if (budget <= 0)
				t = end;
		}
		on[f] = (float)(acc / dt);
	}
}

void c0_sim_blink(const struct c0_sim_conf *c, uint64_t stream, int frames, float *on)
{
	c0_sim_blink_slots(c, stream, NULL, frames, on);
}

double c0_sim_onfrac_variance(const struct c0_sim_conf *c)
{
	/* time average over D of a telegraph process: p(1-p) * 2 (tc/D)^2 (D/tc - 1 + e^{-D/tc}) */
	double ton = c->tau_on_ms * 1e-3, toff = c->tau_off_ms * 1e-3, D = 1 / c->fps;
	double p = ton / (ton + toff), tc = ton * toff / (ton + toff), x = D / tc;
	return p * (1 - p) * 2 / (x * x) * (x - 1 + exp(-x));
}

double c0_sim_bleach_rate(const struct c0_sim_conf *c)
{
	if (!(c->tau_bleach_s > 0))
		return 0;
	/* slowest eigenvalue of the on/off/bleached chain: the population's decay rate */
	double a = 1e3 / c->tau_on_ms, b = 1e3 / c->tau_off_ms, k = 1 / c->tau_bleach_s;
	double tr = a + b + k, det = b * k;
	return (tr - sqrt(tr * tr - 4 * det)) / 2;
}

int64_t c0_sim_slot(const struct c0_sim_conf *c, int q, int t)
{
	if (c->order == C0_ORDER_RESTART)
		return t;
	if (c->order == C0_ORDER_INTERLEAVED)
		return (int64_t)t * c->nangles + q;
	int64_t s = (int64_t)q * c->frames + t;
	for (int k = 0; k < q && c->ngaps; k++)
		s += llround(c->gap_s[c->ngaps == 1 ? 0 : k] * c->fps);
	return s;
}
