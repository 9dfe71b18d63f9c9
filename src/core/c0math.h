#pragma once
#define C0_PI 3.14159265358979323846
#define C0_FWHM_TO_SIGMA 0.42466090014400953   /* 1 / (2 sqrt(2 ln 2)) */

/* Inner loops of the solvers are also built for AVX2+FMA and picked at load
 * time (results differ from the baseline build only by FMA rounding). An
 * OpenMP loop body is outlined without the attribute: put the work in a
 * C0_HOT function that the loop calls. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__SANITIZE_ADDRESS__)
#define C0_HOT __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define C0_HOT
#endif
/* AVX-512 and AVX2 without FMA: the same operations in the same order as
 * the baseline build, so the same numbers (ISO C does not contract them
 * into FMAs); for loops whose results must not move (an OpenMP loop calls
 * it, as C0_HOT) */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__SANITIZE_ADDRESS__) && (!defined(__clang__) || __clang_major__ >= 14)
#define C0_WIDE 1   /* AVX2 and AVX-512 versions may be built beside the baseline (also by hand) */
#define C0_HOT_SAME __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define C0_WIDE 0
#define C0_HOT_SAME
#endif
/* four doubles in one vector (GCC's vector extension): a C0_HOT loop's lanes */
typedef double c0_v4 __attribute__((vector_size(32)));

/* Parallel sums run over fixed blocks of this many elements, each summed by
 * one thread, and the blocks' sums are added in block order: the same bits
 * for any number of threads (a reduction clause splits the sum by thread,
 * and a sum that moves the iterates or a stopping test would then make the
 * results depend on the thread count). */
#define C0_SUM_BLOCK 16384

#include <stddef.h>

/* The first index in [lo, hi) of the increasing a whose value is at or past v
 * (hi when none): a raster index's place among sorted pixel indices. */
static inline size_t c0_lower_bound(const int *a, size_t lo, size_t hi, size_t v)
{
	while (lo < hi) {
		const size_t mid = lo + (hi - lo) / 2;
		if ((size_t)a[mid] < v)
			lo = mid + 1;
		else
			hi = mid;
	}
	return lo;
}

/* The smallest n' >= n, even if asked, with no prime factor above p: the
 * lengths FFTW transforms fast (a prime length is 5x slower than a smooth
 * one near it; for a real FFT an odd length 2x: 315^2 1.07 ms a pair,
 * 320^2 0.46 ms). */
static inline int c0_fft_size(int n, int p, int even)
{
	for (n += even && (n & 1);; n += even ? 2 : 1) {
		int m = n;
		for (int f = 2; f <= p; f++)
			while (m % f == 0)
				m /= f;
		if (m == 1)
			return n;
	}
}

/* Index i of a sequence of n extended half-sample symmetrically (v[-1-k] =
 * v[k], v[n+k] = v[n-1-k]: period 2n), as an index in [0, n). */
static inline int c0_mirror(int i, int n)
{
	i %= 2 * n;
	if (i < 0)
		i += 2 * n;
	return i < n ? i : 2 * n - 1 - i;
}
