#define _POSIX_C_SOURCE 200809L
#include "io/outdir.h"
#include "io/atomic.h"
#include "core/err.h"

#include <dirent.h>
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
		return c0_fail(C0_EINVAL, "-o: an output directory is required");
	snprintf(o->path, sizeof o->path, "%s", path);
	struct stat sb;
	if (!stat(path, &sb)) {
		if (!S_ISDIR(sb.st_mode))
			return c0_fail(C0_EIO, "-o %s: exists and is not a directory", path);
		if (!force && !is_empty(path))
			return c0_fail(C0_EIO, "-o %s: directory is not empty (use --force to write into it)", path);
		if (access(path, W_OK))
			return c0_fail(C0_EIO, "-o %s: not writable", path);
		return C0_OK;
	}
	if (mkdir(path, 0777))
		return c0_fail(C0_EIO, "-o %s: cannot create directory: %s", path, strerror(errno));
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
