/* Status codes and the per-thread error message.
 * Library functions never exit or print: they return a status and leave one
 * line in c0_errmsg() that names the file or parameter at fault. */
#pragma once

enum c0_status {
	C0_OK = 0,
	C0_EINVAL,      /* bad parameter or argument */
	C0_EIO,         /* cannot open, read, write or rename a file */
	C0_EFORMAT,     /* a file is not what it claims or is damaged */
	C0_EUNSUPPORTED,/* a valid file we do not handle (RGB, complex, ...) */
	C0_ENOMEM,
};

/* Record a message (printf-style) and return code. The arguments may
 * include c0_errmsg() itself. */
int c0_fail(int code, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Prepends "prefix: " to the current message and returns code. */
int c0_fail_prefix(int code, const char *prefix);
const char *c0_errmsg(void);
void c0_clear_error(void);
