/* Status codes and the per-thread error message.
 * Library functions never exit or print: they return a status and leave one
 * line in c0_errmsg() that names the file or parameter at fault. */
#pragma once

#include "col0rme.h"   /* the status codes */

/* Record a message (printf-style) and return code. */
int c0_fail(int code, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
const char *c0_errmsg(void);
void c0_clear_error(void);
