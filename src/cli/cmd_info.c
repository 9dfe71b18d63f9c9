/* col0rme info FILE...: what a stack is, without loading it whole. */
#include "cli/commands.h"
#include "cli/opts.h"
#include "io/tiff.h"
#include "io/report.h"
#include "core/err.h"
#include "core/mem.h"
#include "core/progress.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

struct stats { double min, max, mean; };

static int scan(struct c0_tiff_reader *r, const struct c0_tiff_info *in, struct stats *s)
{
	size_t n = (size_t)in->width * in->height;
	double *plane = c0_alloc(n, sizeof *plane);
	if (!plane)
		return C0_ENOMEM;
	double sum = 0, lo = INFINITY, hi = -INFINITY;
	struct c0_progress pr;
	c0_progress_begin(&pr, "info", (double)in->pages);
	int st = C0_OK;
	for (int64_t p = 0; p < in->pages && !st; p++) {
		st = c0_tiff_read_f64(r, p, plane);
		for (size_t i = 0; i < n && !st; i++) {
			sum += plane[i];
			lo = plane[i] < lo ? plane[i] : lo;
			hi = plane[i] > hi ? plane[i] : hi;
		}
		c0_progress_update(&pr, (double)p + 1);
	}
	c0_progress_end(&pr);
	free(plane);
	s->min = lo, s->max = hi, s->mean = sum / ((double)n * in->pages);
	return st;
}

int cmd_info(int argc, char **argv)
{
	int json = 0, nostats = 0, verbose = 0;
	const struct c0_opt opts[] = {
		{ "json", 0, C0_OPT_FLAG, &json, NULL, "print one JSON object per file", NULL, 0, NULL },
		{ "no-stats", 0, C0_OPT_FLAG, &nostats, NULL, "skip min/mean/max (reads headers only)", NULL, 0, NULL },
		{ "verbose", 0, C0_OPT_FLAG, &verbose, NULL, "show progress even when not on a terminal", NULL, 0, NULL },
	};
	const struct c0_cmd_spec spec = { "info", "[options] FILE...",
		"Print dimensions, frames, sample type, calibration and min/mean/max of TIFF stacks.",
		opts, C0_NOPTS(opts), 1, -1, 0 };
	char **files = malloc(sizeof(char *) * (size_t)argc);
	int nf = 0, rc = c0_opts_parse(&spec, argc, argv, &nf, files);
	if (rc) {
		free(files);
		return rc == 1 ? 0 : 2;
	}
	for (int f = 0; f < nf && !rc; f++) {
		struct c0_tiff_reader *r;
		if (c0_tiff_open(files[f], &r)) {
			rc = c0_cli_error("info");
			break;
		}
		c0_tiff_allow_nonfinite(r);   /* describe such a file rather than refuse it */
		const struct c0_tiff_info *in = c0_tiff_get_info(r);
		struct stats s = { 0, 0, 0 };
		if (!nostats && scan(r, in, &s)) {
			c0_tiff_close(r);
			rc = c0_cli_error("info");
			break;
		}
		if (json) {
			cJSON *o = cJSON_CreateObject();
			cJSON_AddStringToObject(o, "file", files[f]);
			cJSON_AddNumberToObject(o, "width", (double)in->width);
			cJSON_AddNumberToObject(o, "height", (double)in->height);
			cJSON_AddNumberToObject(o, "pages", (double)in->pages);
			cJSON_AddNumberToObject(o, "channels", (double)in->channels);
			cJSON_AddNumberToObject(o, "slices", (double)in->slices);
			cJSON_AddNumberToObject(o, "frames", (double)in->frames);
			cJSON_AddNumberToObject(o, "channel", in->channel);
			cJSON_AddNumberToObject(o, "file_pages", (double)in->file_pages);
			cJSON_AddStringToObject(o, "dtype", c0_dtype_name(in->dtype));
			cJSON_AddNumberToObject(o, "pixel_size_nm", in->pixel_size_nm);
			cJSON_AddNumberToObject(o, "z_spacing_nm", in->z_spacing_nm);
			cJSON_AddStringToObject(o, "compression", in->compression);
			cJSON_AddBoolToObject(o, "big_endian", in->big_endian);
			cJSON_AddBoolToObject(o, "bigtiff", in->bigtiff);
			cJSON_AddBoolToObject(o, "tiled", in->tiled);
			cJSON_AddBoolToObject(o, "imagej", in->imagej);
			cJSON_AddBoolToObject(o, "ome", in->ome);
			if (!nostats) {
				cJSON_AddNumberToObject(o, "min", s.min);
				cJSON_AddNumberToObject(o, "mean", s.mean);
				cJSON_AddNumberToObject(o, "max", s.max);
			}
			char *txt = cJSON_PrintUnformatted(o);
			printf("%s\n", txt);
			free(txt);
			cJSON_Delete(o);
		} else {
			printf("%s\n", files[f]);
			printf("  size        %lld x %lld pixels (W x H), %lld pages\n", (long long)in->width, (long long)in->height, (long long)in->pages);
			printf("  hyperstack  %lld channels, %lld slices, %lld frames%s\n", (long long)in->channels,
			       (long long)in->slices, (long long)in->frames, in->imagej ? " (ImageJ)" : in->ome ? " (OME)" : "");
			printf("  samples     %s, %s-endian%s%s, compression %s\n", c0_dtype_name(in->dtype), in->big_endian ? "big" : "little",
			       in->bigtiff ? ", BigTIFF" : "", in->tiled ? ", tiled" : "", in->compression);
			if (in->pixel_size_nm > 0)
				printf("  pixel size  %.6g nm", in->pixel_size_nm);
			else
				printf("  pixel size  not calibrated");
			if (in->z_spacing_nm > 0)
				printf(", z spacing %.6g nm", in->z_spacing_nm);
			printf("\n");
			if (in->channels > 1 && !in->channel)
				printf("  channels    %lld, read as %lld stacks (one per angle, in order) by run, support and intensity;\n"
				       "              --channel K (or FILE:cK) selects one\n", (long long)in->channels, (long long)in->channels);
			if (!nostats)
				printf("  values      min %.6g, mean %.6g, max %.6g\n", s.min, s.mean, s.max);
		}
		c0_tiff_close(r);
	}
	free(files);
	return rc;
}
