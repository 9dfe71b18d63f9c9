#define _DEFAULT_SOURCE   /* madvise */
#include "core/mem.h"
#include "core/err.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#ifdef __linux__
#include <sys/mman.h>
#endif

/* Blocks of at least this size ask for transparent huge pages */
#define HUGE_MIN (4 << 20)
#define HUGE_PAGE ((uintptr_t)2 << 20)

void *c0_alloc(size_t n, size_t size)
{
	if (size && n > SIZE_MAX / size) {
		c0_fail(C0_ENOMEM, "allocation of %zu x %zu bytes overflows", n, size);
		return NULL;
	}
#if defined(__linux__) && defined(MADV_HUGEPAGE)
	/* the covariance sums and the solvers' grids are touched page by page
	 * once each: in 2 MB pages their first touches fault 512 times less
	 * (where the system gives them on request only: "madvise"). Zeroed
	 * after the request, as calloc would zero reused memory before it. */
	if (n * size >= HUGE_MIN) {
		void *p = malloc(n * size);
		if (!p) {
			c0_fail(C0_ENOMEM, "out of memory allocating %.1f MB", (double)n * size / 1e6);
			return NULL;
		}
		const uintptr_t b = ((uintptr_t)p + HUGE_PAGE - 1) & ~(HUGE_PAGE - 1);
		const uintptr_t e = ((uintptr_t)p + n * size) & ~(HUGE_PAGE - 1);
		if (e > b)
			madvise((void *)b, e - b, MADV_HUGEPAGE);
		return memset(p, 0, n * size);
	}
#endif
	void *p = calloc(n ? n : 1, size ? size : 1);
	if (!p)
		c0_fail(C0_ENOMEM, "out of memory allocating %.1f MB", (double)n * size / 1e6);
	return p;
}

void c0_free(void *p)
{
	free(p);
}

void c0_mem_release(void)
{
#ifdef __GLIBC__
	malloc_trim(0);
#endif
}
