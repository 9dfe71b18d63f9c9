#include "solve/nnqp.h"
#include "core/c0math.h"

#include <string.h>

#define VLOAD(v, p) memcpy(&(v), (p), sizeof(v))
#define VSTORE(p, v) memcpy((p), &(v), sizeof(v))

/* Baseline (a CPU without AVX2, the sanitizer build): the blocked kernel
 * below at 4 lanes, SSE2's width. Plain loops over a row of the chunk, which
 * store their accumulators every term, took 1.3x as long in a baseline
 * build and about 4x under the sanitizer. */
#define NNQP_NAME batch4
#define NNQP_LANES 4
#define NNQP_TARGET
#include "solve/nnqp_batch_kernel.h"
#undef NNQP_NAME
#undef NNQP_LANES
#undef NNQP_TARGET

/* AVX2 and AVX-512: the same kernel at the CPU's width, chosen at run
 * time, each with vectors of its own size (one 16-float version split into
 * SSE2 vectors took twice as long as plain loops) */
#if C0_WIDE
#define NNQP_NAME batch8
#define NNQP_LANES 8
#define NNQP_TARGET __attribute__((target("avx2")))
#include "solve/nnqp_batch_kernel.h"
#undef NNQP_NAME
#undef NNQP_LANES
#undef NNQP_TARGET

#define NNQP_NAME batch16
#define NNQP_LANES 16
#define NNQP_TARGET __attribute__((target("avx512f")))
#include "solve/nnqp_batch_kernel.h"
#undef NNQP_NAME
#undef NNQP_LANES
#undef NNQP_TARGET
#endif

void c0_nnqp_batch(int n, const float *H, float step, float beta, int steps, const float *g, float *u)
{
#if C0_WIDE
	if (__builtin_cpu_supports("avx512f"))
		batch16(n, H, step, beta, steps, g, u);
	else if (__builtin_cpu_supports("avx2"))
		batch8(n, H, step, beta, steps, g, u);
	else
#endif
		batch4(n, H, step, beta, steps, g, u);
}
