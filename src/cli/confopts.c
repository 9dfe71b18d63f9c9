#include "cli/confopts.h"
#include "core/err.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

struct row {
	const char *param;
	struct c0_opt opt;
};

/* Rows in the order of the help text; dst points into *m. */
static int rows(struct c0_conf_cli *m, struct row *r)
{
	struct c0_run_conf *c = &m->c;
	const struct row all[] = {
		{ "pixel_nm", { "pixel-size", 0, C0_OPT_DOUBLE, &c->pixel_nm, "NM", "camera pixel size in the sample", "from the TIFF calibration", 0, &m->pixel_given } },
		{ "channel", { "channel", 0, C0_OPT_INT, &m->channel, "K", "read only channel K of multi-channel files", "every channel, one stack per angle in order", 0, NULL } },
		{ "fwhm_nm", { "fwhm", 0, C0_OPT_DOUBLE, &c->fwhm_nm, "NM", "PSF full width at half maximum", "0.51 emission / NA", 0, NULL } },
		{ "psf_image", { "psf", 0, C0_OPT_STRING, &c->psf_image, "IMAGE.tif", "measured PSF (a bead, or the mean of several centred ones): its fitted Gaussian FWHM, instead of --fwhm", "none", 0, NULL } },
		{ "emission_nm", { "emission", 0, C0_OPT_DOUBLE, &c->emission_nm, "NM", "emission wavelength (with --na, instead of --fwhm)", "none", 0, NULL } },
		{ "na", { "na", 0, C0_OPT_DOUBLE, &c->na, "NA", "numerical aperture of the objective (with --emission)", "none", 0, NULL } },
		{ "srf", { "srf", 0, C0_OPT_INT, &c->srf, "R", "super-resolution factor: fine pixel = pixel size / R", NULL, 0, NULL } },
		{ "support_stacks", { "support-angles", 0, C0_OPT_INTS, c->support_stacks, "I,J", "1-based stack numbers whose supports are joined", "the smallest angle", C0_MAX_STACKS, &c->nsupport_stacks } },
		{ "penalty", { "penalty", 0, C0_OPT_STRING, &m->penalty, "l1|cel0", "support sparsity penalty", NULL, 0, NULL } },
		{ "lambda", { "lambda", 0, C0_OPT_DOUBLE, &c->lambda, "F", "support regularisation relative to lambda_max (the smallest that gives an empty support)", "automatic: max(2e-2 of the correlation's 90th percentile, 4 noise sds) for l1 (see the guide)", 0, NULL } },
		{ "drift", { "drift", 0, C0_OPT_STRING, &m->drift, "on|off", "estimate lateral drift from block means and undo it before the covariance and the means", NULL, 0, NULL } },
		{ "no_drift", { "no-drift", 0, C0_OPT_FLAG, &m->no_drift, NULL, "the same as --drift off", NULL, 0, NULL } },
		{ "pixel_guard", { "pixel-guard", 0, C0_OPT_STRING, &m->pixel_guard, "on|off", "clip each pixel's variance to what its covariances with its neighbours allow (noisy sCMOS pixels)", NULL, 0, NULL } },
		{ "frc", { "frc", 0, C0_OPT_INT, &c->frc, "0|1", "solve each half of the frames too, for the FRC resolution and the localisation precision", NULL, 0, NULL } },
		{ "support_solver", { "support-solver", 0, C0_OPT_STRING, &m->support_solver, "fista|pruned", "l1 support solver, both FISTA on a working set re-made every 100 iterations (momentum kept): with the whole grid's step, or with the set's own step (converges, see the guide)", NULL, 0, NULL } },
		{ "iterations", { "iterations", 0, C0_OPT_INT, &c->iterations, "N", "maximum FISTA iterations (per reweighting for cel0)", "2000, or 10000 with pruned", 0, NULL } },
		{ "tol", { "tol", 0, C0_OPT_DOUBLE, &c->tol, "F", "stop when the relative change of the iterate falls below this", "0 with fista on l1 (every iteration: the capped iterate is the estimator), 1e-5 with pruned and cel0", 0, NULL } },
		{ "reweightings", { "reweightings", 0, C0_OPT_INT, &c->reweightings, "N", "CEL0 reweighting steps", NULL, 0, NULL } },
		{ "lag", { "lag", 0, C0_OPT_INT, &c->lag, "PX", "covariance lag radius in pixels", "ceil(6 sigma / pixel)", 0, NULL } },
		{ "tile", { "tile", 0, C0_OPT_INT, &c->tile, "PX", "support tile side in camera pixels (tiles overlap by two lags)", "256, or the image when smaller", 0, NULL } },
		{ "background", { "background", 0, C0_OPT_STRING, &m->background, "MODE", "none, constant or smooth", NULL, 0, NULL } },
		{ "beta", { "beta", 0, C0_OPT_DOUBLE, &c->beta, "B", "background smoothness weight", NULL, 0, NULL } },
		{ "nu", { "nu", 0, C0_OPT_DOUBLE, &c->nu, "F", "intensity discrepancy factor: residual^2 = nu^2 HW sigma2 / T (0: sqrt(T))", NULL, 0, NULL } },
		{ "mu", { "mu", 0, C0_OPT_DOUBLE, &c->mu, "M", "fixed smoothness weight instead of the discrepancy principle", "0 (discrepancy)", 0, NULL } },
		{ "discrepancy", { "discrepancy", 0, C0_OPT_STRING, &m->discrepancy, "relative|plain", "intensity mu: residual = the model's floor (at mu = 1e-3) plus the noise level, or the noise level alone", NULL, 0, NULL } },
		{ "cg_tol", { "tol", 0, C0_OPT_DOUBLE, &c->cg_tol, "F", "CG stopping tolerance (relative residual)", NULL, 0, NULL } },
		{ "graph_radius", { "graph-radius", 0, C0_OPT_DOUBLE, &c->graph_radius, "PX", "intensity smoothness couples support pixels up to this far apart (fine pixels)", NULL, 0, NULL } },
		{ "noise_variance", { "noise-variance", 0, C0_OPT_DOUBLES, c->noise_variance, "V,...", "per-stack noise variance (camera units^2)", "estimated on the support", C0_MAX_STACKS, &c->nnoise_variance } },
		{ "depth_pool_nm", { "depth-pool", 0, C0_OPT_DOUBLE, &c->depth_pool_nm, "NM", "window over which intensities are summed for each pixel's depth (0: off)", "0.75 FWHM", 0, NULL } },
		{ "depth_pool_range_nm", { "depth-pool-range", 0, C0_OPT_DOUBLE, &c->depth_pool_range_nm, "NM", "only window pixels whose first depth guess is within NM of the centre's are summed (0: all)", "50", 0, NULL } },
		{ "bleach", { "bleach", 0, C0_OPT_STRING, &m->bleach, "estimate|off", "photobleaching across the stacks: estimate the fade and divide each stack's intensity by its factor before MA-TIRF, or off", NULL, 0, NULL } },
		{ "bleach_factors", { "bleach-factors", 0, C0_OPT_DOUBLES, c->bleach_factors, "F,...", "known bleaching factors: each stack's mean population relative to the start of the acquisition", "estimated", C0_MAX_STACKS, &c->nbleach_factors } },
		{ "acquisition", { "acquisition", 0, C0_OPT_STRING, &m->acquisition, "sequential|interleaved", "how the stacks were recorded: one after another, or frame by frame in turn", NULL, 0, NULL } },
		{ "acquisition_order", { "acquisition-order", 0, C0_OPT_INTS, c->acquisition_order, "I,J,...", "the stack numbers (1-based, as given) in the order they were recorded", "as given", C0_MAX_STACKS, &c->nacquisition_order } },
		{ "gaps_frames", { "gaps", 0, C0_OPT_DOUBLES, c->gaps_frames, "FRAMES,...", "illuminated but unrecorded time between consecutive recorded stacks, in frames (one value: all)", "none", C0_MAX_STACKS, &c->ngaps_frames } },
		{ "baseline", { "baseline", 0, C0_OPT_FLAG, &c->baseline, NULL, "also reconstruct the standard MA-TIRF volume from the background-corrected means (baseline_*)", NULL, 0, NULL } },
		{ "angles", { "angles", 0, C0_OPT_DOUBLES, c->angles, "DEG,...", "incidence angle in the glass of each stack/image, same order", "none", C0_MAX_STACKS, &c->nangles } },
		{ "n_glass", { "n-glass", 0, C0_OPT_DOUBLE, &c->n_glass, "N", "refractive index of the coverslip and immersion", NULL, 0, NULL } },
		{ "n_sample", { "n-sample", 0, C0_OPT_DOUBLE, &c->n_sample, "N", "refractive index of the sample", NULL, 0, NULL } },
		{ "wavelength_nm", { "wavelength", 0, C0_OPT_DOUBLE, &c->wavelength_nm, "NM", "excitation wavelength in vacuum", NULL, 0, NULL } },
		{ "s_fraction", { "s-fraction", 0, C0_OPT_DOUBLE, &c->s_fraction, "F", "share of s-polarised excitation in I0", NULL, 0, NULL } },
		{ "gains", { "gains", 0, C0_OPT_DOUBLES, c->gains, "G,...", "per-angle gain calibration (multiplies I0)", "1 for every angle", C0_MAX_STACKS, &c->ngains } },
		{ "z_range_nm", { "z-range", 0, C0_OPT_DOUBLES, c->z_range_nm, "MIN,MAX,STEP", "depth bins in nm", "0,400,20", 3, &m->nz } },
		{ "reg", { "reg", 0, C0_OPT_STRING, &m->reg, "tv|hessian", "regulariser: total variation or Hessian-Schatten", NULL, 0, NULL } },
		{ "kappa", { "kappa", 0, C0_OPT_DOUBLE, &c->kappa, "K", "regularisation weight (images scaled to a maximum of 1)", NULL, 0, NULL } },
		{ "sparsity", { "sparsity", 0, C0_OPT_DOUBLE, &c->sparsity, "S", "weight of the l1 term that keeps few depths per pixel", NULL, 0, NULL } },
		{ "axial_weight", { "axial-weight", 0, C0_OPT_DOUBLE, &c->axial_weight, "W", "axial weight of the regulariser relative to lateral", NULL, 0, NULL } },
		{ "matirf_iterations", { "matirf-iterations", 0, C0_OPT_INT, &c->matirf_iterations, "N", "maximum primal-dual iterations", NULL, 0, NULL } },
		{ "matirf_solver", { "matirf-solver", 0, C0_OPT_STRING, &m->solver, "exact|diag|auto|apg", "exact per-pixel data steps, diagonal steps, or apg: the per-pixel steps by projected gradient (auto: apg)", NULL, 0, NULL } },
		{ "matirf_coarse", { "matirf-coarse", 0, C0_OPT_INT, &c->matirf_coarse, "N", "levels of the warm start from 2x2-binned images (apg and exact with TV)", "2 with apg, else 0", 0, NULL } },
		{ "offset", { "offset", 0, C0_OPT_DOUBLE, &c->offset, "ADU", "camera offset subtracted from every image (refused at or above an image's mean)", NULL, 0, NULL } },
		{ "matirf_background", { "background", 0, C0_OPT_DOUBLE, &c->matirf_background, "V", "constant background subtracted after the offset", NULL, 0, NULL } },
		{ "estimate_background", { "estimate-background", 0, C0_OPT_FLAG, &c->estimate_background, NULL, "estimate a smooth background common to all angles jointly (background.tif)", NULL, 0, NULL } },
		{ "background_smooth", { "background-smooth", 0, C0_OPT_DOUBLE, &c->background_smooth, "PX2", "smoothness weight of the estimated background", NULL, 0, NULL } },
		{ "psf_fwhm_nm", { "psf-fwhm", 0, C0_OPT_DOUBLE, &c->psf_fwhm_nm, "NM", "joint deconvolution: the images are the volume's projections blurred by a Gaussian PSF of this FWHM", "none", 0, NULL } },
	};
	if (r)
		memcpy(r, all, sizeof all);
	return (int)(sizeof all / sizeof *all);
}
enum { MAXROWS = 64 };

void c0_conf_cli_init(struct c0_conf_cli *m)
{
	c0_run_conf_init(&m->c);
	m->penalty = "l1", m->support_solver = "fista", m->background = "smooth", m->reg = "tv", m->solver = "auto", m->nz = 0, m->pixel_given = 0, m->channel = 0;
	m->discrepancy = "relative", m->bleach = "estimate", m->acquisition = "sequential";
	m->drift = "on", m->no_drift = 0, m->pixel_guard = "on";
}

int c0_conf_cli_opts(struct c0_conf_cli *m, const char *const *params, struct c0_opt *o)
{
	struct row all[MAXROWS];
	int nall = rows(m, all), k = 0;
	for (; params[k]; k++)
		for (int i = 0; i < nall; i++)
			if (!strcmp(all[i].param, params[k]))
				o[k] = all[i].opt;
	return k;
}

int c0_conf_cli_table(struct c0_conf_cli *m, const char *const *params, const char **outdir, int *force, int *verbose,
		      struct c0_opt *o)
{
	o[0] = (struct c0_opt){ "output", 'o', C0_OPT_STRING, outdir, "DIR", "output directory (created; must be empty unless --force)", NULL, 0, NULL };
	int n = 1 + c0_conf_cli_opts(m, params, o + 1);
	o[n++] = (struct c0_opt){ "force", 0, C0_OPT_FLAG, force, NULL, "write into a non-empty output directory", NULL, 0, NULL };
	o[n++] = (struct c0_opt){ "verbose", 0, C0_OPT_FLAG, verbose, NULL, "show progress even when not on a terminal", NULL, 0, NULL };
	return n;
}

int c0_conf_cli_finish(struct c0_conf_cli *m)
{
	int st = c0_run_conf_set(&m->c, "penalty", m->penalty);
	if (!st)
		st = c0_run_conf_set(&m->c, "support_solver", m->support_solver);
	if (!st)
		st = c0_run_conf_set(&m->c, "background", m->background);
	if (!st)
		st = c0_run_conf_set(&m->c, "reg", m->reg);
	if (!st)
		st = c0_run_conf_set(&m->c, "matirf_solver", m->solver);
	if (!st && m->pixel_given && !(m->c.pixel_nm > 0 && isfinite(m->c.pixel_nm)))
		st = c0_fail(C0_EINVAL, "pixel_nm %g: must be a positive number of nm", m->c.pixel_nm);
	if (!st)
		st = c0_run_conf_set(&m->c, "discrepancy", m->discrepancy);
	if (!st)
		st = c0_run_conf_set(&m->c, "bleach", m->bleach);
	if (!st)
		st = c0_run_conf_set(&m->c, "acquisition", m->acquisition);
	if (!st)
		st = c0_run_conf_set(&m->c, "drift", m->no_drift ? "off" : m->drift);
	if (!st)
		st = c0_run_conf_set(&m->c, "pixel_guard", m->pixel_guard);
	if (!st && m->nz && m->nz != 3)
		st = c0_fail(C0_EINVAL, "z_range_nm: expected MIN,MAX,STEP in nm");
	return st;
}

/* The flag of parameter name[0..l) (in extra first, if given), or NULL. */
static const char *flag_of(const char *name, size_t l, const struct c0_cli_name *extra, char *buf, size_t n)
{
	for (; extra && extra->param; extra++)
		if (strlen(extra->param) == l && !strncmp(extra->param, name, l))
			return extra->flag;
	if (l == 6 && !strncmp(name, "outdir", 6))
		return "-o";
	if (l == 5 && !strncmp(name, "force", 5))
		return "--force";
	struct c0_conf_cli m;
	struct row all[MAXROWS];
	int nall = rows(&m, all);
	for (int i = 0; i < nall; i++)
		if (strlen(all[i].param) == l && !strncmp(all[i].param, name, l)) {
			snprintf(buf, n, "--%s", all[i].opt.name);
			return buf;
		}
	return NULL;
}

static int word(int ch)
{
	return isalnum((unsigned char)ch) || ch == '_';
}

/* A parameter name in a message is the first word, or has an underscore, or
 * is followed by its value, a colon or a closing parenthesis: "3 angles for"
 * stays prose. */
void c0_cli_flags(const char *msg, const struct c0_cli_name *extra, char *buf, size_t n)
{
	size_t k = 0;
	for (const char *p = msg; *p && k + 1 < n;) {
		if (!word(*p) || (p > msg && (word(p[-1]) || p[-1] == '.' || p[-1] == '/' || p[-1] == '-'))) {
			buf[k++] = *p++;
			continue;
		}
		const char *e = p;
		while (word(*e))
			e++;
		char fb[64];
		const char *f = flag_of(p, (size_t)(e - p), extra, fb, sizeof fb);
		int cited = (p == msg && (!*e || *e == ' ' || *e == ':')) || memchr(p, '_', (size_t)(e - p)) ||
			    *e == ':' || *e == ')' || (*e == ' ' && (isdigit((unsigned char)e[1]) || e[1] == '-'));
		if (*e == '.' || *e == '/')
			cited = 0;   /* a file name */
		const char *src = f && cited ? f : p;
		size_t l = f && cited ? strlen(f) : (size_t)(e - p);
		for (size_t i = 0; i < l && k + 1 < n; i++)
			buf[k++] = src[i];
		p = e;
	}
	buf[k] = '\0';
}
