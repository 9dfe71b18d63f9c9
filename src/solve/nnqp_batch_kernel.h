/* The body of c0_nnqp_batch for one vector width, included once per width by
 * nnqp_batch.c with NNQP_NAME (the function), NNQP_LANES (floats a vector)
 * and NNQP_TARGET (its target attribute, or nothing). Element by element,
 * without FMA: every width gives the same numbers. */
NNQP_TARGET static void NNQP_NAME(int n, const float *H, float step, float beta, int steps, const float *g, float *u)
{
	typedef float vf __attribute__((vector_size(4 * NNQP_LANES)));
	typedef int vi __attribute__((vector_size(4 * NNQP_LANES)));
	enum { B = C0_NNQP_BATCH, L = NNQP_LANES };
	float v[C0_NNQP_MAX * B], w[C0_NNQP_MAX * B];
	memcpy(v, u, sizeof(float) * n * B);
	for (int it = 0; it < steps; it++) {
		for (int l = 0; l < n; l++)
			/* 4 vectors of columns at a time, their H v in registers:
			 * the same sums in the same order as one column at a time */
			for (int i0 = 0; i0 < B; i0 += 4 * L) {
				const float *gl = g + l * B + i0, *vl = v + l * B + i0;
				float *wl = w + l * B + i0;
				vf a0, a1, a2, a3, t0, t1, t2, t3;
				VLOAD(a0, gl), VLOAD(a1, gl + L), VLOAD(a2, gl + 2 * L), VLOAD(a3, gl + 3 * L);
				a0 = -a0, a1 = -a1, a2 = -a2, a3 = -a3;
				for (int m = 0; m < n; m++) {
					const float h = H[l * n + m], *vm = v + m * B + i0;
					VLOAD(t0, vm), VLOAD(t1, vm + L), VLOAD(t2, vm + 2 * L), VLOAD(t3, vm + 3 * L);
					a0 += h * t0, a1 += h * t1, a2 += h * t2, a3 += h * t3;
				}
				/* max(p, 0) as 1/2 (p + |p|), |p| by clearing the sign bit as fabsf does */
				VLOAD(t0, vl), VLOAD(t1, vl + L), VLOAD(t2, vl + 2 * L), VLOAD(t3, vl + 3 * L);
				t0 -= step * a0, t1 -= step * a1, t2 -= step * a2, t3 -= step * a3;
				t0 = 0.5f * (t0 + (vf)((vi)t0 & 0x7fffffff)), t1 = 0.5f * (t1 + (vf)((vi)t1 & 0x7fffffff));
				t2 = 0.5f * (t2 + (vf)((vi)t2 & 0x7fffffff)), t3 = 0.5f * (t3 + (vf)((vi)t3 & 0x7fffffff));
				VSTORE(wl, t0), VSTORE(wl + L, t1), VSTORE(wl + 2 * L, t2), VSTORE(wl + 3 * L, t3);
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
