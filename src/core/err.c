#include "core/err.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static _Thread_local char msg[1024];

/* Formats into a local buffer first: the arguments may point into msg
 * itself (c0_fail(st, "%s: %s", name, c0_errmsg())), and vsnprintf into
 * the buffer it reads from is undefined. */
int c0_fail(int code, const char *fmt, ...)
{
	char tmp[sizeof msg];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(tmp, sizeof tmp, fmt, ap);
	va_end(ap);
	memcpy(msg, tmp, sizeof msg);
	return code;
}

int c0_fail_prefix(int code, const char *prefix)
{
	char tmp[sizeof msg];
	const char *cur = c0_errmsg();
	size_t k = (size_t)snprintf(tmp, sizeof tmp, "%s: ", prefix);
	if (k < sizeof tmp)
		snprintf(tmp + k, sizeof tmp - k, "%s", cur);
	memcpy(msg, tmp, sizeof msg);
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

void c0_first_fail_note(struct c0_first_fail *f, int code)
{
	if (!code)
		return;
#pragma omp critical(c0_first_fail)
	if (!f->code)
		f->code = code, snprintf(f->msg, sizeof f->msg, "%s", c0_errmsg());
}

int c0_first_fail_raise(const struct c0_first_fail *f)
{
	return f->code ? c0_fail(f->code, "%s", f->msg) : C0_OK;
}
