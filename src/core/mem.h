/* Allocation helpers that report failure through c0_fail. */
#pragma once
#include <stddef.h>

void *c0_alloc(size_t n, size_t size);    /* zeroed; NULL + message on failure */
void c0_free(void *p);
/* Gives the free memory inside the heap back to the system (glibc keeps
 * freed blocks below the heap's top resident): after a stage frees its big
 * buffers, before the next allocates others of other sizes. */
void c0_mem_release(void);
