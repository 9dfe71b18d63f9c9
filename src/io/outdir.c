#define _XOPEN_SOURCE 700
#include "io/outdir.h"
#include "io/atomic.h"
#include "core/err.h"

#include <dirent.h>
#include <limits.h>
#include <stdlib.h>
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int is_empty(const char *path)
{
	DIR *d = opendir(path);
	if (!d)
		return 0;
	int empty = 1;
	for (struct dirent *e; empty && (e = readdir(d));)
		empty = !strcmp(e->d_name, ".") || !strcmp(e->d_name, "..");
	closedir(d);
	return empty;
}

int c0_outdir_open(struct c0_outdir *o, const char *path, int force)
{
	memset(o, 0, sizeof o[0]);
	if (!path || !path[0])
		return c0_fail(C0_EINVAL, "outdir: an output directory is required");
	snprintf(o->path, sizeof o->path, "%s", path);
	struct stat sb;
	if (!stat(path, &sb)) {
		if (!S_ISDIR(sb.st_mode))
			return c0_fail(C0_EIO, "outdir %s: exists and is not a directory", path);
		if (!force && !is_empty(path))
			return c0_fail(C0_EIO, "outdir %s: directory is not empty (write into it with force)", path);
		if (access(path, W_OK))
			return c0_fail(C0_EIO, "outdir %s: not writable", path);
		return C0_OK;
	}
	if (mkdir(path, 0777))
		return c0_fail(C0_EIO, "outdir %s: cannot create directory: %s", path, strerror(errno));
	o->created = 1;
	return C0_OK;
}

const char *c0_outdir_file(struct c0_outdir *o, const char *name)
{
	static _Thread_local char buf[4352];
	snprintf(buf, sizeof buf, "%s/%s", o->path, name);
	if (o->nfiles < 64)
		snprintf(o->files[o->nfiles++], sizeof o->files[0], "%s", name);
	return buf;
}

void c0_outdir_rollback(struct c0_outdir *o)
{
	char p[4352];
	for (int i = 0; i < o->nfiles; i++) {
		snprintf(p, sizeof p, "%s/%s", o->path, o->files[i]);
		remove(p);
	}
	if (o->created)
		rmdir(o->path);
}

int c0_write_file_named(struct c0_outdir *o, const char *name, const void *data, unsigned long n)
{
	return c0_write_file(c0_outdir_file(o, name), data, n);
}

int c0_outdir_check_inputs(const char *path, const char *const *inputs, int n)
{
	char od[PATH_MAX] = "";
	if (!path || !realpath(path, od))
		return C0_OK;          /* does not exist yet: cannot hold an input */
	for (int i = 0; i < n; i++) {
		char in[PATH_MAX];
		if (!inputs[i] || !realpath(inputs[i], in))
			continue;
		char *slash = strrchr(in, '/');
		if (slash)
			*slash = '\0';
		if (!strcmp(in[0] ? in : "/", od))
			return c0_fail(C0_EINVAL, "outdir %s: is the directory of input %s; write results elsewhere", path, inputs[i]);
	}
	return C0_OK;
}
