#define _POSIX_C_SOURCE 200809L
#include "io/atomic.h"
#include "core/err.h"

#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

void c0_tmp_name(const char *path, char *out, size_t n)
{
	static atomic_int counter;
	const char *slash = strrchr(path, '/');
	int dirlen = slash ? (int)(slash - path + 1) : 0;
	snprintf(out, n, "%.*s.%s.tmp%ld-%d", dirlen, path, slash ? slash + 1 : path,
		 (long)getpid(), atomic_fetch_add(&counter, 1));
}

int c0_commit_file(const char *tmp, const char *path)
{
	if (rename(tmp, path)) {
		int e = errno;
		remove(tmp);
		return c0_fail(C0_EIO, "%s: cannot rename into place: %s", path, strerror(e));
	}
	return C0_OK;
}

int c0_write_file(const char *path, const void *data, size_t n)
{
	char tmp[4096];
	c0_tmp_name(path, tmp, sizeof tmp);
	FILE *f = fopen(tmp, "wb");
	if (!f)
		return c0_fail(C0_EIO, "%s: cannot create: %s", path, strerror(errno));
	int ok = fwrite(data, 1, n, f) == n;
	ok &= fclose(f) == 0;
	if (!ok) {
		remove(tmp);
		return c0_fail(C0_EIO, "%s: write failed: %s", path, strerror(errno));
	}
	return c0_commit_file(tmp, path);
}
