#define _GNU_SOURCE
#include "io/outdir.h"
#include "io/atomic.h"
#include "core/err.h"
#include "io/tiff.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

/* Unlinks every entry of dir and the directory itself with system calls
 * only (no malloc, no stdio): callable from a signal handler. Only plain
 * entries are expected (outputs are files). */
void c0_outdir_remove_flat(const char *dir)
{
	int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
	if (fd >= 0) {
		char buf[4096] __attribute__((aligned(8)));
		for (int pass = 0; pass < 8; pass++) {   /* deleting while listing may skip entries */
			int left = 0;
			long n;
			lseek(fd, 0, SEEK_SET);
			while ((n = syscall(SYS_getdents64, fd, buf, sizeof buf)) > 0)
				for (long off = 0; off < n;) {
					struct { unsigned long long ino; long long off; unsigned short reclen; unsigned char type; char name[]; }
						*e = (void *)(buf + off);
					off += e->reclen;
					if (strcmp(e->name, ".") && strcmp(e->name, "..") && !unlinkat(fd, e->name, 0))
						left = 1;
				}
			if (!left)
				break;
		}
		close(fd);
	}
	rmdir(dir);
}

/* Scans dir: empty, holds a subdirectory (its name in sub), or unreadable (-1 and errno). */
static int scan(const char *path, int *empty, char *sub, size_t n)
{
	DIR *d = opendir(path);
	if (!d)
		return -1;
	*empty = 1;
	sub[0] = '\0';
	for (struct dirent *e; (e = readdir(d));) {
		if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
			continue;
		*empty = 0;
		char p[8192];
		struct stat sb;
		snprintf(p, sizeof p, "%s/%s", path, e->d_name);
		if (!sub[0] && !lstat(p, &sb) && S_ISDIR(sb.st_mode))
			snprintf(sub, n, "%s", e->d_name);
	}
	closedir(d);
	return 0;
}

/* Removes staging and swap directories beside path left by runs that died;
 * a previous result moved aside by a run killed in the middle of its swap
 * goes back into place when nothing replaced it. */
static void clean_stale(const char *parent, const char *base, const char *path)
{
	DIR *d = opendir(parent);
	if (!d)
		return;
	size_t bl = strlen(base);
	for (struct dirent *e; (e = readdir(d));) {
		const char *s = e->d_name;
		if (strncmp(s, base, bl) || (strncmp(s + bl, ".c0tmp-", 7) && strncmp(s + bl, ".c0old-", 7)))
			continue;
		char *end;
		long pid = strtol(s + bl + 7, &end, 10);
		if (*end || pid <= 0 || pid == (long)getpid() || !(kill((pid_t)pid, 0) && errno == ESRCH))
			continue;   /* malformed, ours, or its run is still alive */
		char p[8192];
		struct stat sb;
		snprintf(p, sizeof p, "%s/%s", parent, s);
		if (!strncmp(s + bl, ".c0old-", 7) && lstat(path, &sb) && errno == ENOENT && !rename(p, path))
			continue;
		c0_outdir_remove_flat(p);
	}
	closedir(d);
}

int c0_outdir_open(struct c0_outdir *o, const char *path, int force)
{
	memset(o, 0, sizeof o[0]);
	if (!path || !path[0])
		return c0_fail(C0_EINVAL, "outdir: an output directory is required");
	size_t l = strlen(path);
	while (l > 1 && path[l - 1] == '/')
		l--;
	if (l >= sizeof o->path - 64)
		return c0_fail(C0_EINVAL, "outdir %s: path too long", path);
	memcpy(o->path, path, l);
	o->path[l] = '\0';
	const char *slash = strrchr(o->path, '/');
	char parent[4096];
	if (slash)
		snprintf(parent, sizeof parent, "%.*s", slash == o->path ? 1 : (int)(slash - o->path), o->path);
	else
		snprintf(parent, sizeof parent, ".");
	const char *base = slash ? slash + 1 : o->path;
	if (!strcmp(base, ".") || !strcmp(base, "..") || !strcmp(o->path, "/"))
		return c0_fail(C0_EINVAL, "outdir %s: name the output directory itself (it is replaced as a whole)", path);
	clean_stale(parent, base, o->path);   /* first: it may put a previous result back */
	struct stat sb;
	if (!stat(o->path, &sb)) {
		if (!S_ISDIR(sb.st_mode))
			return c0_fail(C0_EIO, "outdir %s: exists and is not a directory", path);
		int empty;
		char sub[256];
		if (scan(o->path, &empty, sub, sizeof sub))
			return c0_fail(C0_EIO, "outdir %s: not readable: %s", path, strerror(errno));
		if (!force && !empty)
			return c0_fail(C0_EIO, "outdir %s: directory is not empty (force: replace its contents)", path);
		if (sub[0])
			return c0_fail(C0_EIO, "outdir %s: holds the directory %s; force replaces the whole directory, so it may only hold files",
				       path, sub);
	} else if (errno != ENOENT) {
		return c0_fail(C0_EIO, "outdir %s: %s", path, strerror(errno));
	}
	errno = 0;
	if (stat(parent, &sb) || !S_ISDIR(sb.st_mode))
		return c0_fail(C0_EIO, "outdir %s: parent directory %s: %s", path, parent,
			       errno ? strerror(errno) : "not a directory");
	if (access(parent, W_OK | X_OK))
		return c0_fail(C0_EIO, "outdir %s: cannot write in %s: %s", path, parent, strerror(errno));
	snprintf(o->stage, sizeof o->stage, "%s.c0tmp-%ld", o->path, (long)getpid());
	c0_outdir_remove_flat(o->stage);   /* ours from an earlier command in this process */
	if (mkdir(o->stage, 0777))
		return c0_fail(C0_EIO, "outdir %s: cannot create %s: %s", path, o->stage, strerror(errno));
	o->open = 1;
	return C0_OK;
}

const char *c0_outdir_file(struct c0_outdir *o, const char *name)
{
	static _Thread_local char buf[4608];
	snprintf(buf, sizeof buf, "%s/%s", o->stage, name);
	return buf;
}

void c0_outdir_rollback(struct c0_outdir *o)
{
	if (!o->open)
		return;
	c0_outdir_remove_flat(o->stage);
	o->open = 0;
}

int c0_outdir_commit(struct c0_outdir *o)
{
	if (!o->open)
		return c0_fail(C0_EINVAL, "outdir %s: not open", o->path);
	/* no signal between moving the old result aside and the new one in */
	sigset_t block, prev;
	sigemptyset(&block);
	sigaddset(&block, SIGINT), sigaddset(&block, SIGTERM), sigaddset(&block, SIGHUP);
	sigprocmask(SIG_BLOCK, &block, &prev);
	char old[4200];
	snprintf(old, sizeof old, "%s.c0old-%ld", o->path, (long)getpid());
	struct stat sb;
	int st = C0_OK, moved = 0;
	if (!lstat(o->path, &sb)) {
		c0_outdir_remove_flat(old);
		if (rename(o->path, old))
			st = c0_fail(C0_EIO, "outdir %s: cannot move the previous result aside: %s", o->path, strerror(errno));
		moved = !st;
	}
	if (!st && rename(o->stage, o->path)) {
		st = c0_fail(C0_EIO, "outdir %s: cannot move the result into place: %s", o->path, strerror(errno));
		if (moved)
			rename(old, o->path);
	}
	if (st) {
		c0_outdir_remove_flat(o->stage);
	} else if (moved) {
		c0_outdir_remove_flat(old);
	}
	o->open = 0;
	sigprocmask(SIG_SETMASK, &prev, NULL);
	return st;
}

int c0_outdir_finish(struct c0_outdir *o, int st)
{
	if (st) {
		c0_outdir_rollback(o);
		return st;
	}
	return c0_outdir_commit(o);
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
		char in[PATH_MAX], file[PATH_MAX];
		if (!inputs[i])
			continue;
		if (!realpath(inputs[i], in) && !(c0_tiff_channel_spec(inputs[i], file, sizeof file) && realpath(file, in)))
			continue;
		char *slash = strrchr(in, '/');
		if (slash)
			*slash = '\0';
		if (!strcmp(in[0] ? in : "/", od))
			return c0_fail(C0_EINVAL, "outdir %s: is the directory of input %s; write results elsewhere", path, inputs[i]);
	}
	return C0_OK;
}
