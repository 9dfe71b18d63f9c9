#include "solve/nnqp.h"
#include "core/c0math.h"

#include <math.h>
#include <string.h>

#define VLOAD(v, p) memcpy(&(v), (p), sizeof(v))
#define VSTORE(p, v) memcpy((p), &(v), sizeof(v))

/* Baseline (a CPU without AVX2, the sanitizer build): plain loops over a
 * row of the chunk, which the compiler vectorises at the target's width;
 * the same sums in the same order as the blocked kernel */
static void batch_plain(int n, const float *H, float step, float beta, int steps, const float *g, float *u)
{
	enum { B = C0_NNQP_BATCH };
	float v[C0_NNQP_MAX * B], w[C0_NNQP_MAX * B], acc[B];
	memcpy(v, u, sizeof(float) * n * B);
	for (int it = 0; it < steps; it++) {
		for (int l = 0; l < n; l++) {
			for (int i = 0; i < B; i++)
				acc[i] = -g[l * B + i];
			for (int m = 0; m < n; m++) {
				const float h = H[l * n + m], *vm = v + m * B;
				for (int i = 0; i < B; i++)
					acc[i] += h * vm[i];
			}
			for (int i = 0; i < B; i++) {
				const float p = v[l * B + i] - step * acc[i];
				w[l * B + i] = 0.5f * (p + fabsf(p));
			}
		}
		for (int i = 0; i < n * B; i++) {   /* the momentum step */
			v[i] = w[i] + beta * (w[i] - u[i]);
			u[i] = w[i];
		}
	}
}

/* AVX2 and AVX-512: the blocked kernel (its accumulators in registers,
 * where the loops above store them every term) at the CPU's width, chosen at
 * run time, each with vectors of its own size (one 16-float version split
 * into SSE2 vectors took twice as long as the loops) */
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
		batch_plain(n, H, step, beta, steps, g, u);
}
