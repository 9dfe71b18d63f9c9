#include "ops/covsum.h"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define C0_COVSUM_X86 1
#include <immintrin.h>
#endif

/* the obvious loop: every x, every frame in order */
static void span_portable(float *acc, const double *p, const double *q, int len, int nb, size_t s)
{
	for (int x = 0; x < len; x++) {
		double v = acc[x];
		for (int b = 0; b < nb; b++)
			v += p[b * s + x] * q[b * s + x];
		acc[x] = (float)v;
	}
}

#ifdef C0_COVSUM_X86
/* 8 or 1 vectors of 4 lanes per pass: 8 independent chains of FMAs cover
 * their latency on two ports; p and q are in L1 (flush's chunks) */
__attribute__((target("avx2,fma"))) static void span_avx2(float *acc, const double *p, const double *q, int len,
							   int nb, size_t s)
{
	int x = 0;
	for (; x + 32 <= len; x += 32) {
		/* named registers: an array would live on the stack */
		__m256d v0 = _mm256_cvtps_pd(_mm_loadu_ps(acc + x)), v1 = _mm256_cvtps_pd(_mm_loadu_ps(acc + x + 4));
		__m256d v2 = _mm256_cvtps_pd(_mm_loadu_ps(acc + x + 8)), v3 = _mm256_cvtps_pd(_mm_loadu_ps(acc + x + 12));
		__m256d v4 = _mm256_cvtps_pd(_mm_loadu_ps(acc + x + 16)), v5 = _mm256_cvtps_pd(_mm_loadu_ps(acc + x + 20));
		__m256d v6 = _mm256_cvtps_pd(_mm_loadu_ps(acc + x + 24)), v7 = _mm256_cvtps_pd(_mm_loadu_ps(acc + x + 28));
		for (int b = 0; b < nb; b++) {
			const double *pb = p + b * s + x, *qb = q + b * s + x;
#define C0_FMA(v, k) v = _mm256_fmadd_pd(_mm256_loadu_pd(pb + k), _mm256_loadu_pd(qb + k), v)
			C0_FMA(v0, 0), C0_FMA(v1, 4), C0_FMA(v2, 8), C0_FMA(v3, 12);
			C0_FMA(v4, 16), C0_FMA(v5, 20), C0_FMA(v6, 24), C0_FMA(v7, 28);
#undef C0_FMA
		}
		_mm_storeu_ps(acc + x, _mm256_cvtpd_ps(v0)), _mm_storeu_ps(acc + x + 4, _mm256_cvtpd_ps(v1));
		_mm_storeu_ps(acc + x + 8, _mm256_cvtpd_ps(v2)), _mm_storeu_ps(acc + x + 12, _mm256_cvtpd_ps(v3));
		_mm_storeu_ps(acc + x + 16, _mm256_cvtpd_ps(v4)), _mm_storeu_ps(acc + x + 20, _mm256_cvtpd_ps(v5));
		_mm_storeu_ps(acc + x + 24, _mm256_cvtpd_ps(v6)), _mm_storeu_ps(acc + x + 28, _mm256_cvtpd_ps(v7));
	}
	for (; x + 4 <= len; x += 4) {
		__m256d v = _mm256_cvtps_pd(_mm_loadu_ps(acc + x));
		for (int b = 0; b < nb; b++)
			v = _mm256_fmadd_pd(_mm256_loadu_pd(p + b * s + x), _mm256_loadu_pd(q + b * s + x), v);
		_mm_storeu_ps(acc + x, _mm256_cvtpd_ps(v));
	}
	if (x < len)
		span_portable(acc + x, p + x, q + x, len - x, nb, s);
}

static int have_avx2(void)
{
	return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
}
#endif

void c0_covsum_span(float *acc, const double *p, const double *q, int len, int nb, size_t s)
{
#ifdef C0_COVSUM_X86
	if (have_avx2()) {
		span_avx2(acc, p, q, len, nb, s);
		return;
	}
#endif
	span_portable(acc, p, q, len, nb, s);
}
