#include "solve/nnqp.h"

#include <string.h>

#define VLOAD(v, p) memcpy(&(v), (p), sizeof(v))
#define VSTORE(p, v) memcpy((p), &(v), sizeof(v))

/* One version a vector width, each with vectors of its own size, chosen at
 * run time: GCC splits a vector wider than the target's into slow pieces (16
 * floats on SSE2 took 2.5x the time of 4). */
#define NNQP_NAME batch4
#define NNQP_LANES 4
#define NNQP_TARGET
#include "solve/nnqp_batch_kernel.h"
#undef NNQP_NAME
#undef NNQP_LANES
#undef NNQP_TARGET

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__SANITIZE_ADDRESS__) && (!defined(__clang__) || __clang_major__ >= 14)
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
#define C0_NNQP_WIDE 1
#endif

void c0_nnqp_batch(int n, const float *H, float step, float beta, int steps, const float *g, float *u)
{
#ifdef C0_NNQP_WIDE
	if (__builtin_cpu_supports("avx512f"))
		batch16(n, H, step, beta, steps, g, u);
	else if (__builtin_cpu_supports("avx2"))
		batch8(n, H, step, beta, steps, g, u);
	else
#endif
		batch4(n, H, step, beta, steps, g, u);
}
