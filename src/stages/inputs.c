#define _XOPEN_SOURCE 700
#include "stages/inputs.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/mem.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void c0_inputs_free(struct c0_inputs *in)
{
	for (int i = 0; in->names && i < in->n; i++)
		free(in->names[i]);
	free(in->names);
	memset(in, 0, sizeof *in);
}

static int add_name(struct c0_inputs *in, int cap, const char *file, int k)
{
	if (in->n >= cap)
		return c0_fail(C0_EINVAL, "%s: more than %d stacks in all (one per angle)", file, cap);
	size_t l = strlen(file) + 16;
	if (!(in->names[in->n] = malloc(l)))
		return C0_ENOMEM;
	if (k)
		snprintf(in->names[in->n], l, "%s:c%d", file, k);
	else
		snprintf(in->names[in->n], l, "%s", file);
	in->n++;
	return C0_OK;
}

/* The directory an input lives in must not be OUTDIR: it is replaced. */
static int check_outdir(const char *outdir, const char *name)
{
	char od[PATH_MAX], in[PATH_MAX], file[PATH_MAX];
	if (!outdir || !realpath(outdir, od))
		return C0_OK;          /* does not exist yet: cannot hold an input */
	if (!c0_tiff_channel_spec(name, file, sizeof file) || realpath(name, in))
		snprintf(file, sizeof file, "%s", name);
	if (!realpath(file, in))
		return C0_OK;
	char *slash = strrchr(in, '/');
	if (slash)
		*slash = '\0';
	if (!strcmp(in[0] ? in : "/", od))
		return c0_fail(C0_EINVAL, "-o %s: is the directory of input %s; write results elsewhere", outdir, name);
	return C0_OK;
}

int c0_inputs_check(struct c0_inputs *in, char **args, int nargs, int channel, double pixel_opt, int need_pixel,
		    int64_t min_frames, int max_stacks, const char *outdir)
{
	memset(in, 0, sizeof *in);
	if (!isnan(pixel_opt) && !(pixel_opt > 0 && isfinite(pixel_opt)))
		return c0_fail(C0_EINVAL, "--pixel-size %g: must be a positive number of nm", pixel_opt);
	if (channel < 0)
		return c0_fail(C0_EINVAL, "--channel %d: channels are numbered from 1", channel);
	int cap = max_stacks > 0 ? max_stacks : 4096;
	if (!(in->names = c0_alloc((size_t)cap, sizeof *in->names)))
		return C0_ENOMEM;
	int st = C0_OK, cal = -1, uncal = -1;   /* the first calibrated and uncalibrated stacks */
	double cal_nm = 0;
	for (int a = 0; a < nargs && !st; a++) {
		struct c0_tiff_reader *r;
		if ((st = c0_tiff_open(args[a], &r)))
			break;
		const struct c0_tiff_info fi = *c0_tiff_get_info(r);
		c0_tiff_close(r);
		int first = in->n;
		if (fi.channels > 1 && !fi.channel) {
			if (channel > fi.channels)
				st = c0_fail(C0_EINVAL, "--channel %d: %s has %lld channels", channel, args[a], (long long)fi.channels);
			for (int k = channel ? channel : 1; !st && k <= (channel ? channel : fi.channels); k++)
				st = add_name(in, cap, args[a], k);
		} else {
			if (channel > 1 && !fi.channel)
				st = c0_fail(C0_EINVAL, "--channel %d: %s has one channel", channel, args[a]);
			if (!st)
				st = add_name(in, cap, args[a], 0);
		}
		for (int i = first; !st && i < in->n; i++) {
			const char *name = in->names[i];
			struct c0_tiff_info si = fi;
			if (strcmp(name, args[a])) {   /* one channel of the file: its own frame count */
				if ((st = c0_tiff_open(name, &r)))
					break;
				si = *c0_tiff_get_info(r);
				c0_tiff_close(r);
			}
			if ((st = check_outdir(outdir, name)))
				break;
			if (i == 0)
				in->width = si.width, in->height = si.height, in->min_frames = si.pages;
			else if (si.width != in->width || si.height != in->height)
				st = c0_fail(C0_EINVAL, "%s: %lldx%lld pixels, but %s is %lldx%lld (all stacks must have one size)", name,
					     (long long)si.width, (long long)si.height, in->names[0], (long long)in->width,
					     (long long)in->height);
			if (!st && si.pages < min_frames)
				st = c0_fail(C0_EINVAL, "%s: %lld frame%s; at least %lld are needed", name, (long long)si.pages,
					     si.pages == 1 ? "" : "s", (long long)min_frames);
			if (!st && in->min_frames > si.pages)
				in->min_frames = si.pages;
			if (st || !isnan(pixel_opt))
				continue;
			if (!(si.pixel_size_nm > 0) && uncal < 0)
				uncal = i;
			if (si.pixel_size_nm > 0 && cal < 0)
				cal = i, cal_nm = si.pixel_size_nm;
			else if (si.pixel_size_nm > 0 && fabs(si.pixel_size_nm - cal_nm) > 1e-3 * cal_nm)
				st = c0_fail(C0_EINVAL, "%s: pixel size %.6g nm, but %s has %.6g nm (give --pixel-size to override)", name,
					     si.pixel_size_nm, in->names[cal], cal_nm);
		}
	}
	if (!st && !in->n)
		st = c0_fail(C0_EINVAL, "no input stack");
	if (!st) {
		in->pixel_nm = !isnan(pixel_opt) ? pixel_opt : cal_nm;
		/* a stack without calibration beside calibrated ones: which is right is unknown */
		if (cal >= 0 && uncal >= 0)
			st = c0_fail(C0_EINVAL, "%s: no pixel calibration, but %s has %.6g nm (give --pixel-size)", in->names[uncal],
				     in->names[cal], cal_nm);
		if (!st && need_pixel && !(in->pixel_nm > 0))
			st = c0_fail(C0_EINVAL, "--pixel-size: %s has no pixel calibration; give the camera pixel size in nm", in->names[0]);
	}
	if (st)
		c0_inputs_free(in);
	return st;
}
