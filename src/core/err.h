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

/* The first failure of a parallel loop: the message is per thread, so a
 * failing iteration notes its status and message here and the loop's
 * caller raises it on its own thread afterwards. */
struct c0_first_fail {
	int code;
	char msg[512];
};
/* Keeps code and the calling thread's message unless a failure is held (or code is 0). */
void c0_first_fail_note(struct c0_first_fail *f, int code);
/* C0_OK, or the held code with its message made the current one. */
int c0_first_fail_raise(const struct c0_first_fail *f);
