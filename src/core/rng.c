#include "core/rng.h"

#include "core/c0math.h"

#include <math.h>

static uint64_t splitmix(uint64_t *x)
{
	uint64_t z = (*x += 0x9E3779B97F4A7C15ull);
	z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
	z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
	return z ^ (z >> 31);
}

void c0_rng_init(struct c0_rng *r, uint64_t seed, uint64_t stream)
{
	uint64_t x = seed ^ (stream * 0xD1B54A32D192ED03ull);
	splitmix(&x);
	x ^= stream;
	for (int i = 0; i < 4; i++)
		r->s[i] = splitmix(&x);
}

static inline uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

uint64_t c0_rng_u64(struct c0_rng *r)
{
	uint64_t *s = r->s;
	uint64_t out = rotl(s[1] * 5, 7) * 9;
	uint64_t t = s[1] << 17;
	s[2] ^= s[0];
	s[3] ^= s[1];
	s[1] ^= s[2];
	s[0] ^= s[3];
	s[2] ^= t;
	s[3] = rotl(s[3], 45);
	return out;
}

double c0_rng_uniform(struct c0_rng *r)
{
	return ((c0_rng_u64(r) >> 11) + 0.5) * 0x1.0p-53;
}

double c0_rng_normal(struct c0_rng *r)
{
	/* Box-Muller; one value per call keeps streams simple to reason about */
	double u = c0_rng_uniform(r), v = c0_rng_uniform(r);
	return sqrt(-2 * log(u)) * cos(2 * C0_PI * v);
}

double c0_rng_exp(struct c0_rng *r, double mean)
{
	return -mean * log(c0_rng_uniform(r));
}

uint64_t c0_rng_poisson(struct c0_rng *r, double mean)
{
	if (mean <= 0)
		return 0;
	if (mean < 30) {        /* Knuth: exact, cheap for small means */
		double l = exp(-mean), p = 1;
		uint64_t k = 0;
		do {
			k++;
			p *= c0_rng_uniform(r);
		} while (p > l);
		return k - 1;
	}
	/* PTRS (Hormann 1993): exact transformed rejection for larger means */
	double slam = sqrt(mean), loglam = log(mean);
	double b = 0.931 + 2.53 * slam, a = -0.059 + 0.02483 * b;
	double invalpha = 1.1239 + 1.1328 / (b - 3.4), vr = 0.9277 - 3.6224 / (b - 2);
	for (;;) {
		double u = c0_rng_uniform(r) - 0.5, v = c0_rng_uniform(r);
		double us = 0.5 - fabs(u);
		double k = floor((2 * a / us + b) * u + mean + 0.43);
		if (us >= 0.07 && v <= vr)
			return (uint64_t)k;
		if (k < 0 || (us < 0.013 && v > us))
			continue;
		if (log(v) + log(invalpha) - log(a / (us * us) + b) <= -mean + k * loglam - lgamma(k + 1))
			return (uint64_t)k;
	}
}
