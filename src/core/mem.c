#define _DEFAULT_SOURCE   /* madvise, MADV_HUGEPAGE */
#include "core/mem.h"
#include "core/err.h"

#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <sys/resource.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

/* The step that runs now, for the out-of-memory message: set by the
 * pipeline between steps, read by any thread that allocates. */
static _Atomic(const char *) g_stage;

void c0_mem_stage(const char *name)
{
	atomic_store(&g_stage, name);
}

const char *c0_mem_stage_name(void)
{
	return atomic_load(&g_stage);
}

double c0_mem_peak_mb(void)
{
	struct rusage ru;
	if (getrusage(RUSAGE_SELF, &ru))
		return 0;
	return (double)ru.ru_maxrss / 1024;   /* kB on Linux */
}

int c0_mem_fail(double bytes)
{
	/* the step's name not before a colon: the CLI would take it for a parameter */
	const char *s = c0_mem_stage_name();
	char in[96] = "";
	if (s)
		snprintf(in, sizeof in, " in the %s step", s);
	if (bytes > 0)
		return c0_fail(C0_ENOMEM, "out of memory%s allocating %.1f MB (peak resident so far %.0f MB)", in, bytes / 1e6,
			       c0_mem_peak_mb());
	return c0_fail(C0_ENOMEM, "out of memory%s (peak resident so far %.0f MB)", in, c0_mem_peak_mb());
}

/* Large buffers ask for transparent huge pages where the kernel gives them
 * only on request (THP "madvise", a common default): a first touch
 * then faults in 2 MB at a time instead of 4 kB, and the covariance's lag
 * sums and the solves' grids miss the TLB less (docs/speed.md, "Huge
 * pages"). Only the 2 MB-aligned inside of the block is advised: its edges
 * may share pages with other blocks. Where THP is off, madvise fails and
 * nothing changes. */
#define C0_HUGE ((uintptr_t)2 << 20)

static void advise_huge(void *p, size_t bytes)
{
#ifdef MADV_HUGEPAGE
	const uintptr_t a = ((uintptr_t)p + C0_HUGE - 1) & ~(C0_HUGE - 1), e = ((uintptr_t)p + bytes) & ~(C0_HUGE - 1);
	if (bytes >= 2 * C0_HUGE && e > a)
		(void)madvise((void *)a, e - a, MADV_HUGEPAGE);
#else
	(void)p, (void)bytes;
#endif
}

void *c0_alloc(size_t n, size_t size)
{
	if (size && n > SIZE_MAX / size) {
		c0_fail(C0_ENOMEM, "allocation of %zu x %zu bytes overflows", n, size);
		return NULL;
	}
	void *p = calloc(n ? n : 1, size ? size : 1);
	if (!p)
		c0_mem_fail((double)n * size);
	else
		advise_huge(p, n * size);
	return p;
}

void c0_mem_release(void)
{
#ifdef __GLIBC__
	malloc_trim(0);
#endif
}

double c0_mem_available(void)
{
	FILE *f = fopen("/proc/meminfo", "r");
	char line[256];
	double kb = 0;
	while (f && fgets(line, sizeof line, f))
		if (sscanf(line, "MemAvailable: %lf kB", &kb) == 1)
			break;
	if (f)
		fclose(f);
	return kb * 1024;
}
