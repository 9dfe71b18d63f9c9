#include "core/mem.h"
#include "core/err.h"

#include <stdint.h>
#include <stdlib.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

void *c0_alloc(size_t n, size_t size)
{
	if (size && n > SIZE_MAX / size) {
		c0_fail(C0_ENOMEM, "allocation of %zu x %zu bytes overflows", n, size);
		return NULL;
	}
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
