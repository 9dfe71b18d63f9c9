#include "core/err.h"

#include <stdarg.h>
#include <stdio.h>

static _Thread_local char msg[1024];

int c0_fail(int code, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(msg, sizeof msg, fmt, ap);
	va_end(ap);
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
