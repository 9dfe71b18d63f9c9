#include "core/err.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static _Thread_local char msg[1024];

int c0_fail(int code, const char *fmt, ...)
{
	char m[sizeof msg];   /* the arguments may include c0_errmsg() itself */
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(m, sizeof m, fmt, ap);
	va_end(ap);
	memcpy(msg, m, sizeof msg);
	return code;
}

const char *c0_errmsg(void)
{
	return msg[0] ? msg : "unknown error";
}

void c0_clear_error(void)
{
	msg[0] = '\0';
}

const char *c0_last_error(void)
{
	return c0_errmsg();
}
