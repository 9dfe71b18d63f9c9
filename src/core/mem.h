/* Allocation helpers that report failure through c0_fail. */
#pragma once
#include <stddef.h>

void *c0_alloc(size_t n, size_t size);    /* zeroed; NULL + message on failure */
/* Gives the free memory inside the heap back to the system (glibc keeps
 * freed blocks below the heap's top resident): after a stage frees its big
 * buffers, before the next allocates others of other sizes. */
void c0_mem_release(void);
/* The step running now (a static string, or NULL), named by the
 * out-of-memory message: "out of memory in the intensity step allocating
 * 812.3 MB (peak resident so far 1234 MB)". */
void c0_mem_stage(const char *name);
const char *c0_mem_stage_name(void);
/* C0_ENOMEM with that message (bytes <= 0: the size is not known). */
int c0_mem_fail(double bytes);
/* The process's peak resident memory so far (getrusage), in MiB. */
double c0_mem_peak_mb(void);
/* The memory the kernel says is available to start new work without
 * swapping (MemAvailable, /proc/meminfo), in bytes; 0 where unknown. */
double c0_mem_available(void);
