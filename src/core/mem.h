/* Allocation helpers that report failure through c0_fail. */
#pragma once
#include <stddef.h>

void *c0_alloc(size_t n, size_t size);    /* zeroed; NULL + message on failure */
void c0_free(void *p);
