/* col0rme eval: accuracy of results against ground truth. */
#include "cli/commands.h"
#include "cli/opts.h"
#include "eval/metrics.h"
#include "io/atomic.h"
#include "io/report.h"
#include "io/tiff.h"
#include "core/err.h"
#include "core/mem.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

struct img { struct c0_tiff_info in; float *v; };

static int load2d(const char *path, struct img *m)
{
	int st = c0_tiff_load_f32(path, &m->in, &m->v);
	if (!st && m->in.pages != 1) {
		free(m->v), m->v = NULL;
		return c0_fail(C0_EINVAL, "%s: %lld planes; expected a 2D image", path, (long long)m->in.pages);
	}
	return st;
}

static int same_size(const char *a, const struct img *x, const char *b, const struct img *y)
{
	if (x->in.width != y->in.width || x->in.height != y->in.height)
		return c0_fail(C0_EINVAL, "%s: %lldx%lld pixels, but %s has %lldx%lld", a, (long long)x->in.width,
			       (long long)x->in.height, b, (long long)y->in.width, (long long)y->in.height);
	return C0_OK;
}

/* an estimate and its truth, 2D and of one size */
static int load_pair(const char *est, struct img *e, const char *truth, struct img *t)
{
	int st = load2d(est, e);
	if (!st)
		st = load2d(truth, t);
	if (!st)
		st = same_size(est, e, truth, t);
	return st;
}

static uint8_t *binary(const struct img *m)
{
	size_t n = (size_t)m->in.width * m->in.height;
	uint8_t *b = c0_alloc(n, 1);
	for (size_t i = 0; b && i < n; i++)
		b[i] = m->v[i] > 0;
	return b;
}

static int eval_support(const char *est, const char *truth, double px, double radius, int margin, cJSON *rep)
{
	struct img e = { 0 }, t = { 0 };
	int st = load_pair(est, &e, truth, &t);
	if (!st && !(px > 0) && !((px = t.in.pixel_size_nm) > 0))
		st = c0_fail(C0_EINVAL, "--pixel-size: %s has no calibration; give the fine pixel size in nm", truth);
	uint8_t *a = st ? NULL : binary(&e), *b = st ? NULL : binary(&t);
	struct c0_jaccard j;
	if (!st)
		st = a && b ? c0_jaccard_index(a, b, (int)t.in.height, (int)t.in.width, px, radius, margin, &j) : C0_ENOMEM;
	if (!st) {
		cJSON *o = cJSON_AddObjectToObject(rep, "support");
		cJSON_AddStringToObject(o, "estimate", est);
		cJSON_AddStringToObject(o, "truth", truth);
		cJSON_AddNumberToObject(o, "jaccard", j.index);
		cJSON_AddNumberToObject(o, "tp", j.tp);
		cJSON_AddNumberToObject(o, "fp", j.fp);
		cJSON_AddNumberToObject(o, "fn", j.fn);
		cJSON_AddNumberToObject(o, "radius_nm", radius);
		cJSON_AddNumberToObject(o, "pixel_nm", px);
	}
	free(a), free(b), free(e.v), free(t.v);
	return st;
}

static int eval_intensity(const char *est, const char *truth, int margin, cJSON *arr)
{
	struct img e = { 0 }, t = { 0 };
	int st = load_pair(est, &e, truth, &t);
	if (!st) {
		cJSON *o = cJSON_CreateObject();
		cJSON_AddStringToObject(o, "estimate", est);
		cJSON_AddStringToObject(o, "truth", truth);
		cJSON_AddNumberToObject(o, "psnr_db", c0_psnr(e.v, t.v, (int)t.in.height, (int)t.in.width, margin));
		cJSON_AddItemToArray(arr, o);
	}
	free(e.v), free(t.v);
	return st;
}

static int eval_depth(const char *key, const char *est, const char *truth, const char *tmask, int margin, cJSON *rep)
{
	struct img e = { 0 }, t = { 0 }, m = { 0 };
	int st = load2d(est, &e);
	if (!st)
		st = load2d(truth, &t);
	if (!st && tmask && !(st = load2d(tmask, &m)))
		st = same_size(tmask, &m, truth, &t);
	uint8_t *b = !st && tmask ? binary(&m) : NULL;
	struct c0_depth_err d;
	if (!st && tmask && !b)
		st = C0_ENOMEM;
	if (!st && (st = c0_depth_error(e.v, (int)e.in.height, (int)e.in.width, t.v, b, (int)t.in.height,
					 (int)t.in.width, margin, &d)))
		c0_fail_prefix(st, est);
	if (!st) {
		cJSON *o = cJSON_AddObjectToObject(rep, key);
		cJSON_AddStringToObject(o, "estimate", est);
		cJSON_AddStringToObject(o, "truth", truth);
		cJSON_AddNumberToObject(o, "pixels", d.pixels);
		cJSON_AddNumberToObject(o, "truth_pixels", d.truth_pixels);
		cJSON_AddNumberToObject(o, "coverage", d.truth_pixels ? (double)d.pixels / d.truth_pixels : 0);
		cJSON_AddNumberToObject(o, "median_abs_error_nm", d.median);
		cJSON_AddNumberToObject(o, "mean_abs_error_nm", d.mean);
		cJSON_AddNumberToObject(o, "median_signed_error_nm", d.bias);
	}
	free(b), free(e.v), free(t.v), free(m.v);
	return st;
}

static const char *join(const char *dir, const char *name)
{
	static char buf[8][4352];
	static int k;
	k = (k + 1) % 8;
	snprintf(buf[k], sizeof buf[k], "%s/%s", dir, name);
	return buf[k];
}

int cmd_eval(int argc, char **argv)
{
	const char *run = NULL, *truth = NULL, *sup = NULL, *sup_t = NULL, *inten = NULL, *inten_t = NULL;
	const char *depth = NULL, *depth_t = NULL, *depth_m = NULL, *output = NULL;
	double radius = 40, px = 0;
	int margin = 0;
	const struct c0_opt opts[] = {
		{ "run", 0, C0_OPT_STRING, &run, "DIR", "outputs of 'col0rme run' (with --truth: evaluate all of them)", NULL, 0, NULL },
		{ "truth", 0, C0_OPT_STRING, &truth, "DIR", "outputs of 'col0rme simulate'", NULL, 0, NULL },
		{ "support", 0, C0_OPT_STRING, &sup, "TIF", "estimated support (nonzero = emitter)", NULL, 0, NULL },
		{ "support-truth", 0, C0_OPT_STRING, &sup_t, "TIF", "true support, same grid", NULL, 0, NULL },
		{ "radius", 0, C0_OPT_DOUBLE, &radius, "NM", "matching radius of the Jaccard index", NULL, 0, NULL },
		{ "pixel-size", 0, C0_OPT_DOUBLE, &px, "NM", "pixel size of the support grid", "from the truth's calibration", 0, NULL },
		{ "intensity", 0, C0_OPT_STRING, &inten, "TIF", "estimated intensity", NULL, 0, NULL },
		{ "intensity-truth", 0, C0_OPT_STRING, &inten_t, "TIF", "true intensity, same grid", NULL, 0, NULL },
		{ "depth", 0, C0_OPT_STRING, &depth, "TIF", "estimated depth map (nm; 0 = no signal), fine or camera grid", NULL, 0, NULL },
		{ "depth-truth", 0, C0_OPT_STRING, &depth_t, "TIF", "true depth map (nm)", NULL, 0, NULL },
		{ "depth-mask", 0, C0_OPT_STRING, &depth_m, "TIF", "pixels that hold emitters", "depth-truth > 0", 0, NULL },
		{ "margin", 0, C0_OPT_INT, &margin, "PX", "ignore pixels this close to the border", NULL, 0, NULL },
		{ "output", 'o', C0_OPT_STRING, &output, "FILE", "also write the JSON here", NULL, 0, NULL },
	};
	const struct c0_cmd_spec spec = { "eval", "[--run DIR --truth DIR | --support TIF --support-truth TIF | ...]",
		"Accuracy against ground truth, as JSON on stdout: Jaccard index of the support (one-to-one\n"
		"matching within --radius), PSNR of intensities, median and mean depth errors of depth maps.\n"
		"--run with --truth pairs support.tif, intensity_qNN.tif, depth.tif and baseline_depth.tif\n"
		"with the simulator's truth files.",
		opts, C0_NOPTS(opts), 0, 0, 0 };
	char *pos[1];
	int npos, rc = c0_opts_parse(&spec, argc, argv, &npos, pos);
	if (rc)
		return rc == 1 ? 0 : 2;
	int st = C0_OK;
	if (!run != !truth)
		st = c0_fail(C0_EINVAL, "--run and --truth go together");
	else if (!sup != !sup_t || !inten != !inten_t || !depth != !depth_t)
		st = c0_fail(C0_EINVAL, "each estimate needs its truth (--support-truth, --intensity-truth, --depth-truth)");
	else if (!run && !sup && !inten && !depth)
		st = c0_fail(C0_EINVAL, "nothing to evaluate: give --run and --truth, or an estimate and its truth");
	else if (margin < 0 || !(radius > 0))
		st = c0_fail(C0_EINVAL, "--margin must be >= 0 and --radius > 0");
	cJSON *rep = c0_report_new("eval", argc, argv);
	cJSON *arr = cJSON_AddArrayToObject(rep, "intensity");
	if (!st && run) {
		st = eval_support(join(run, "support.tif"), join(truth, "truth_support.tif"), px, radius, margin, rep);
		for (int q = 1; !st && q < 100; q++) {
			char a[32], b[40];
			snprintf(a, sizeof a, "intensity_q%02d.tif", q);
			snprintf(b, sizeof b, "truth_intensity_q%02d.tif", q);
			if (access(join(run, a), F_OK))
				break;
			st = eval_intensity(join(run, a), join(truth, b), margin, arr);
		}
		const char *ts = join(truth, "truth_support.tif");
		if (!st && !access(join(run, "depth.tif"), F_OK))
			st = eval_depth("depth", join(run, "depth.tif"), join(truth, "truth_depth.tif"), ts, margin, rep);
		if (!st && !access(join(run, "baseline_depth.tif"), F_OK))
			st = eval_depth("baseline_depth", join(run, "baseline_depth.tif"), join(truth, "truth_depth.tif"), ts,
					margin, rep);
	}
	if (!st && sup)
		st = eval_support(sup, sup_t, px, radius, margin, rep);
	if (!st && inten)
		st = eval_intensity(inten, inten_t, margin, arr);
	if (!st && depth)
		st = eval_depth("depth", depth, depth_t, depth_m, margin, rep);
	char *txt = st ? NULL : cJSON_Print(rep);
	if (!st && !txt)
		st = C0_ENOMEM;
	if (!st && output)
		st = c0_write_file(output, txt, strlen(txt));
	if (!st)
		printf("%s\n", txt);
	free(txt);
	cJSON_Delete(rep);
	return st ? c0_cli_error("eval") : 0;
}
