/* Status codes and the per-thread error message.
 * Library functions never exit or print: they return a status and leave one
 * line in c0_errmsg() that names the file or parameter at fault. */
#pragma once

#include "col0rme.h"   /* the status codes */

/* Record a message (printf-style) and return code. The arguments may
 * include c0_errmsg() itself. */
int c0_fail(int code, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Prepends "prefix: " to the current message and returns code. */
int c0_fail_prefix(int code, const char *prefix);
const char *c0_errmsg(void);
void c0_clear_error(void);
