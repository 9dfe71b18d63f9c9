#include "solve/nnqp.h"
#include "core/c0math.h"

#include <string.h>

/* 16 floats: one AVX-512 register (lowered to narrower ones elsewhere) */
typedef float vf16 __attribute__((vector_size(64)));
typedef int vi16 __attribute__((vector_size(64)));
#define VLOAD(v, p) memcpy(&(v), (p), sizeof(v))
#define VSTORE(p, v) memcpy((p), &(v), sizeof(v))
/* max(p, 0) as 1/2 (p + |p|), |p| by clearing the sign bit as fabsf does */
#define PROJECT(p) (0.5f * ((p) + (vf16)((vi16)(p) & 0x7fffffff)))

/* Built also for AVX-512 and AVX2 (C0_HOT_SAME): element-wise, no FMA, the
 * same numbers on every build. */
C0_HOT_SAME void c0_nnqp_batch(int n, const float *H, float step, float beta, int steps, const float *g, float *u)
{
	enum { B = C0_NNQP_BATCH };
	float v[C0_NNQP_MAX * B], w[C0_NNQP_MAX * B];
	memcpy(v, u, sizeof(float) * n * B);
	for (int it = 0; it < steps; it++) {
		for (int l = 0; l < n; l++)
			/* 64 columns at a time, their H v in four vectors (registers
			 * on AVX-512): the same sums in the same order as one column
			 * at a time */
			for (int i0 = 0; i0 < B; i0 += 4 * 16) {
				const float *gl = g + l * B + i0, *vl = v + l * B + i0;
				float *wl = w + l * B + i0;
				vf16 a0, a1, a2, a3, t0, t1, t2, t3;
				VLOAD(a0, gl), VLOAD(a1, gl + 16), VLOAD(a2, gl + 32), VLOAD(a3, gl + 48);
				a0 = -a0, a1 = -a1, a2 = -a2, a3 = -a3;
				for (int m = 0; m < n; m++) {
					const float h = H[l * n + m], *vm = v + m * B + i0;
					VLOAD(t0, vm), VLOAD(t1, vm + 16), VLOAD(t2, vm + 32), VLOAD(t3, vm + 48);
					a0 += h * t0, a1 += h * t1, a2 += h * t2, a3 += h * t3;
				}
				VLOAD(t0, vl), VLOAD(t1, vl + 16), VLOAD(t2, vl + 32), VLOAD(t3, vl + 48);
				t0 = PROJECT(t0 - step * a0), t1 = PROJECT(t1 - step * a1);
				t2 = PROJECT(t2 - step * a2), t3 = PROJECT(t3 - step * a3);
				VSTORE(wl, t0), VSTORE(wl + 16, t1), VSTORE(wl + 32, t2), VSTORE(wl + 48, t3);
			}
		for (int l = 0; l < n; l++) {   /* the momentum step */
			float *ul = u + l * B, *vl = v + l * B;
			const float *wl = w + l * B;
			for (int i = 0; i < B; i++) {
				vl[i] = wl[i] + beta * (wl[i] - ul[i]);
				ul[i] = wl[i];
			}
		}
	}
}
