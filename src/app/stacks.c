/* The input stacks of a run: opened as frame sources, their pixel size and
 * sizes checked, and the start every run shares (c0_pipe_begin). */
#include "app/stacks.h"
#include "app/result.h"
#include "app/pipeline_conf.h"
#include "app/calib.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

int c0_stacks_keep_cached(const double *bytes, int n, double avail)
{
	if (!(avail > 0))
		return n;
	int k = 0;
	for (double kept = 0; k < n && kept + bytes[k] <= 0.75 * avail; k++)
		kept += bytes[k];
	return k;
}

/* The stacks are read three times (drift, the covariance, the intensity
 * step's means); between the passes the kernel keeps them in its page cache
 * when they fit beside the run. When they do not, each pass over them in
 * turn evicted the pages the next pass reads first, and the kernel's
 * reclaim took more CPU than the reading (5 x 2048^2 x 500, 21 GB, on a
 * 23 GB machine: docs/speed.md). The first stacks that fit stay cached; the
 * others are given back as they are read. Files only: an array is memory. */
static void cache_plan(const struct c0_stack *s, struct c0_frames *f, int n)
{
	double bytes[C0_MAX_STACKS];
	for (int i = 0; i < n; i++) {
		struct stat sb;
		bytes[i] = s[i].path && !stat(s[i].path, &sb) ? (double)sb.st_size : 0;
	}
	for (int i = c0_stacks_keep_cached(bytes, n, c0_mem_available()); i < n; i++)
		c0_frames_drop_behind(&f[i], 1);
}

int c0_stacks_open(const struct c0_stack *s, int n, struct c0_frames *f)
{
	int st = C0_OK, i;
	for (i = 0; i < n && !st; i++) {
		char name[32];
		snprintf(name, sizeof name, "array %d", i + 1);
		if (s[i].path)
			st = c0_frames_open(&f[i], s[i].path);
		else
			st = c0_frames_wrap(&f[i], s[i].data, s[i].frames, s[i].height, s[i].width, s[i].pixel_nm, name);
		if (!st && s[i].pixel_nm > 0)
			f[i].pixel_nm = s[i].pixel_nm;
		if (!st && (f[i].width != f[0].width || f[i].height != f[0].height))
			st = c0_fail(C0_EINVAL, "%s: %dx%d pixels differs from %s (%dx%d)", f[i].name, f[i].width, f[i].height,
				     f[0].name, f[0].width, f[0].height);
	}
	if (st)
		c0_stacks_close(f, i);
	else
		cache_plan(s, f, n);
	return st;
}

void c0_stacks_close(struct c0_frames *f, int n)
{
	for (int i = 0; i < n; i++)
		c0_frames_close(&f[i]);
}

int c0_stacks_pixel(const struct c0_run_conf *c, const struct c0_frames *f, int n, double *pixel_nm)
{
	if (!(c->pixel_nm >= 0 && isfinite(c->pixel_nm)))
		return c0_fail(C0_EINVAL, "pixel_nm %g: must be a positive number of nm (0: the stacks' calibration)", c->pixel_nm);
	*pixel_nm = c->pixel_nm > 0 ? c->pixel_nm : f[0].pixel_nm;
	if (!(*pixel_nm > 0))
		return c0_fail(C0_EINVAL, "pixel_nm: %s has no pixel calibration; give the camera pixel size in nm", f[0].name);
	/* without the parameter, the stacks' calibrations must agree: which one is right is unknown */
	for (int i = 1; !(c->pixel_nm > 0) && i < n; i++)
		if (!(fabs(f[i].pixel_nm - f[0].pixel_nm) <= 1e-3 * f[0].pixel_nm))
			return c0_fail(C0_EINVAL, "%s: pixel size %s%.6g nm, but %s has %.6g nm (give pixel_nm to override)", f[i].name,
				       f[i].pixel_nm > 0 ? "" : "uncalibrated, not ", f[i].pixel_nm, f[0].name, f[0].pixel_nm);
	return C0_OK;
}

int c0_stacks_check(const struct c0_support_conf *sc, const struct c0_frames *f, int n)
{
	for (int i = 0; i < n; i++) {
		int st = c0_support_check(sc, f[i].width, f[i].height, f[i].count, f[i].name);
		if (st)
			return st;
	}
	return C0_OK;
}

int c0_pipe_begin(const char *command, const struct c0_run_conf *c, const struct c0_stack *stacks, int n,
		  struct c0_frames *f, struct c0_stage_confs *sc, struct c0_result **out)
{
	*out = NULL;
	if (n < 1 || n > C0_MAX_STACKS || !stacks || !c)
		return c0_fail(C0_EINVAL, "stacks: %d given, expected 1..%d", n, C0_MAX_STACKS);
	int st = c0_stacks_open(stacks, n, f);
	if (st)
		return st;
	const char *names[C0_MAX_STACKS];
	int is_file[C0_MAX_STACKS];
	double pixel_nm;
	for (int i = 0; i < n; i++)
		names[i] = f[i].name, is_file[i] = stacks[i].path != NULL;
	st = c0_stacks_pixel(c, f, n, &pixel_nm);
	if (!st)
		st = c0_run_conf_stages(c, pixel_nm, sc);
	if (!st)   /* every stack's size and frames, before the first one's work */
		st = c0_stacks_check(&sc->support, f, n);
	if (!st)
		st = c0_result_new(command, n, names, is_file, out);
	if (!st && (st = c0_calib_attach(c, f, n, sc, *out)))
		c0_result_free(*out), *out = NULL;
	if (st)
		c0_stacks_close(f, n);
	return st;
}

int c0_pipe_run(const char *command, const struct c0_run_conf *c, const struct c0_stack *stacks, int n,
		c0_pipe_body body, const void *arg, struct c0_result **out)
{
	struct c0_frames f[C0_MAX_STACKS];
	struct c0_stage_confs sc;
	struct c0_result *r;
	*out = NULL;
	c0_mem_stage("opening");   /* each step names itself from here on */
	struct c0_progress_sink ps;   /* the caller's progress callback, for the run's stages */
	c0_progress_attach(&ps, c ? c->progress : NULL, c ? c->progress_user : NULL);
	int st = c0_pipe_begin(command, c, stacks, n, f, &sc, &r);
	if (!st) {
		st = body(c, &sc, f, n, r, arg);
		if (st == C0_ENOMEM && !strstr(c0_errmsg(), "out of memory"))
			c0_mem_fail(0);   /* a plain malloc's failure: the step, without the size */
		c0_stacks_close(f, n);
		st = c0_progress_detach(&ps, st);
		if (st)
			c0_result_free(r);
		else
			*out = r;
	}
	c0_mem_stage(NULL);
	return c0_progress_detach(&ps, st);
}
