/* Counter-friendly random numbers: xoshiro256** seeded by splitmix64.
 * A stream is derived from (seed, stream id), so each emitter or frame gets
 * its own sequence and results do not depend on the thread count. */
#pragma once
#include <stdint.h>

struct c0_rng { uint64_t s[4]; };

void c0_rng_init(struct c0_rng *r, uint64_t seed, uint64_t stream);
uint64_t c0_rng_u64(struct c0_rng *r);
double c0_rng_uniform(struct c0_rng *r);       /* (0, 1) open */
double c0_rng_normal(struct c0_rng *r);
double c0_rng_exp(struct c0_rng *r, double mean);
uint64_t c0_rng_poisson(struct c0_rng *r, double mean);
