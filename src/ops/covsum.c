#include "ops/covsum.h"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define C0_COVSUM_X86 1
#include <immintrin.h>
#endif

enum { GROUP = 12 };   /* lags whose sums stay in registers together: 12 + p + q of 16 ymm */

/* the obvious loop: every lag, every x, every frame in order */
static void lags_portable(float *acc, size_t plane, const double *p, const double *q, int len, int nlag, int nb,
			  size_t s)
{
	for (int k = 0; k < nlag; k++)
		for (int x = 0; x < len; x++) {
			double v = acc[k * plane + x];
			for (int b = 0; b < nb; b++)
				v += p[b * s + x] * q[b * s + x + k];
			acc[k * plane + x] = (float)v;
		}
}

#ifdef C0_COVSUM_X86
/* One vector of columns, n lags (a constant where it is inlined, so the
 * loops unroll and the sums live in registers); V: the vector type, the
 * rest its intrinsics */
#define C0_COVSUM_GROUP(name, V, LOAD, FMA, TO_D, TO_F, FLOAD, FSTORE, tgt)                                       \
	static inline __attribute__((always_inline, target(tgt))) void name(float *acc, size_t plane, const double *p, \
									  const double *q, int n, int nb, size_t s)     \
	{                                                                                                              \
		V v[GROUP];                                                                                            \
		_Pragma("GCC unroll 12") for (int k = 0; k < n; k++) v[k] = TO_D(FLOAD(acc + k * plane));             \
		for (int b = 0; b < nb; b++) {                                                                         \
			const V pb = LOAD(p + b * s);                                                                  \
			const double *qb = q + b * s;                                                                  \
			_Pragma("GCC unroll 12") for (int k = 0; k < n; k++) v[k] = FMA(pb, LOAD(qb + k), v[k]);       \
		}                                                                                                      \
		_Pragma("GCC unroll 12") for (int k = 0; k < n; k++) FSTORE(acc + k * plane, TO_F(v[k]));             \
	}

/* every whole vector of L columns, the lags in groups; the rest of the
 * columns by the plain loop */
#define C0_COVSUM_LAGS(name, group, L, tgt)                                                                            \
	__attribute__((target(tgt))) static void name(float *acc, size_t plane, const double *p, const double *q,       \
						      int len, int nlag, int nb, size_t s)                       \
	{                                                                                                              \
		int x = 0;                                                                                             \
		for (; x + L <= len; x += L)                                                                           \
			for (int k = 0; k < nlag; k += GROUP) {                                                        \
				float *a = acc + k * plane + x;                                                        \
				const double *px = p + x, *qx = q + x + k;                                             \
				switch (nlag - k < GROUP ? nlag - k : GROUP) {                                         \
				case 1: group(a, plane, px, qx, 1, nb, s); break;                                      \
				case 2: group(a, plane, px, qx, 2, nb, s); break;                                      \
				case 3: group(a, plane, px, qx, 3, nb, s); break;                                      \
				case 4: group(a, plane, px, qx, 4, nb, s); break;                                      \
				case 5: group(a, plane, px, qx, 5, nb, s); break;                                      \
				case 6: group(a, plane, px, qx, 6, nb, s); break;                                      \
				case 7: group(a, plane, px, qx, 7, nb, s); break;                                      \
				case 8: group(a, plane, px, qx, 8, nb, s); break;                                      \
				case 9: group(a, plane, px, qx, 9, nb, s); break;                                      \
				case 10: group(a, plane, px, qx, 10, nb, s); break;                                    \
				case 11: group(a, plane, px, qx, 11, nb, s); break;                                    \
				default: group(a, plane, px, qx, 12, nb, s); break;                                    \
				}                                                                                      \
			}                                                                                              \
		if (x < len)                                                                                           \
			lags_portable(acc + x, plane, p + x, q + x, len - x, nlag, nb, s);                             \
	}

C0_COVSUM_GROUP(group_avx2, __m256d, _mm256_loadu_pd, _mm256_fmadd_pd, _mm256_cvtps_pd, _mm256_cvtpd_ps,
		_mm_loadu_ps, _mm_storeu_ps, "avx2,fma")
C0_COVSUM_LAGS(lags_avx2, group_avx2, 4, "avx2,fma")
C0_COVSUM_GROUP(group_avx512, __m512d, _mm512_loadu_pd, _mm512_fmadd_pd, _mm512_cvtps_pd, _mm512_cvtpd_ps,
		_mm256_loadu_ps, _mm256_storeu_ps, "avx512f")
C0_COVSUM_LAGS(lags_avx512, group_avx512, 8, "avx512f")
#endif

void c0_covsum_lags(float *acc, size_t plane, const double *p, const double *q, int len, int nlag, int nb, size_t s)
{
#ifdef C0_COVSUM_X86
	if (__builtin_cpu_supports("avx512f")) {
		lags_avx512(acc, plane, p, q, len, nlag, nb, s);
		return;
	}
	if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
		lags_avx2(acc, plane, p, q, len, nlag, nb, s);
		return;
	}
#endif
	lags_portable(acc, plane, p, q, len, nlag, nb, s);
}
