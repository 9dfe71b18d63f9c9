#include "core/mem.h"
#include "core/err.h"

#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
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

void *c0_alloc(size_t n, size_t size)
{
	if (size && n > SIZE_MAX / size) {
		c0_fail(C0_ENOMEM, "allocation of %zu x %zu bytes overflows", n, size);
		return NULL;
	}
	void *p = calloc(n ? n : 1, size ? size : 1);
	if (!p)
		c0_mem_fail((double)n * size);
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
