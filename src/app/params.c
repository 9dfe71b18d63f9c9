/* The run parameters' table (app/params.h) and setting one from text. */
#include "app/params.h"
#include "core/err.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define F(f) offsetof(struct c0_run_conf, f)
#define ROW(n, t, cnt, mx, ch, flag, mv, help, def) { #n, t, F(n), cnt, mx, ch, flag, mv, help, def, help " (default: " def ")" }
#define NUM(n, t, flag, mv, help, def) ROW(n, t, 0, 0, NULL, flag, mv, help, def)
#define LIST(x, t, flag, mv, help, def) ROW(x, t, F(n##x), C0_MAX_STACKS, NULL, flag, mv, help, def)
#define ENUM(n, ch, flag, help, def) ROW(n, C0_P_ENUM, 0, 0, ch, flag, ch, help, def)

static const struct c0_param table[] = {
	/* optics and grid */
	NUM(pixel_nm, C0_P_DOUBLE, "pixel-size", "NM", "camera pixel size in the sample, nm (0: the stacks' calibration)", "from the TIFF calibration"),
	NUM(fwhm_nm, C0_P_DOUBLE, "fwhm", "NM", "PSF full width at half maximum, nm", "0.51 emission / NA"),
	NUM(psf_image, C0_P_STRING, "psf", "IMAGE.tif", "measured PSF (a bead, or the mean of several centred ones): its fitted Gaussian FWHM, instead of --fwhm", "none"),
	NUM(emission_nm, C0_P_DOUBLE, "emission", "NM", "emission wavelength, nm (with --na, instead of --fwhm)", "none"),
	NUM(na, C0_P_DOUBLE, "na", "NA", "numerical aperture of the objective (with --emission)", "none"),
	NUM(srf, C0_P_INT, "srf", "R", "super-resolution factor: fine pixel = pixel size / R", "4"),
	/* support */
	LIST(support_stacks, C0_P_INTS, "support-angles", "I,J", "1-based stack numbers of the support (pooled, or with --support-pool 0 each solved and the supports joined)", "every stack pooled; with --support-pool 0 the smallest angle"),
	NUM(support_pool, C0_P_FLAG, "support-pool", "0|1", "1: one support from the support stacks' covariances pooled (one sample, the same emitters at every angle); 0: a support per stack, joined", "1"),
	NUM(label_radius_nm, C0_P_DOUBLE, "label-radius", "NM", "radius of the labelled structures about their axis (tube and label; 0: as thin as a line): the support holds every fine pixel whose centre lies within it and half a fine pixel of a ridge it marks, and the noise rule's lambda stands above what that width leaves beside the axis (docs/defaults.md#label_radius_nm)", "15"),
	ENUM(penalty, "l1|cel0", "penalty", "support sparsity penalty", "l1"),
	NUM(lambda, C0_P_DOUBLE, "lambda", "F", "support regularisation relative to lambda_max (the smallest that gives an empty support)",
	    "automatic (--lambda-rule): for l1 4 noise sds of the correlation image; with --lambda-rule peaks a first solve at max(2e-2 of the correlation's 90th percentile, 4 noise sds), then max(0.28 of the median emitter peak, 4 noise sds)"),
	ENUM(lambda_rule, "peaks|cv|noise", "lambda-rule",
	     "automatic l1 lambda: the rule from a first solve's peaks, cross-validation of the interleaved frame halves (a warm-started path from 4x the rule's first step; the largest lambda within one standard error of the least prediction error, over sqrt 2 for all frames; measured worse on the simulated grid), or the noise floor: lambda = 4 noise sds of the correlation image, and with a label radius that plus the correlation the tubes' width leaves beside their axis; no first solve (docs/defaults.md#lambda_rule)", "noise"),
	ENUM(fwhm_rule, "stated|data", "fwhm-rule",
	     "PSF width of the support, intensity and depth solves: the stated one (--fwhm, --psf, --emission/--na), or the one the stacks' covariance says (lag 2 over lag 1) where it differs from the stated one by more than 5 % (measured within 2 % on Gaussian PSFs; an Airy disk reads 8 % narrower; see docs/defaults.md#fwhm_rule). Measured on the first support stack before its solve", "data"),
	ENUM(support_solver, "fista|pruned", "support-solver",
	     "l1 support solver, both FISTA on a working set re-made every 100 iterations (momentum kept): with the whole grid's step, or with the set's own step (converges, see the guide)", "fista"),
	NUM(iterations, C0_P_INT, "iterations", "N", "maximum FISTA iterations (per reweighting for cel0; -1: the default)", "2000, or 10000 with pruned"),
	NUM(tol, C0_P_DOUBLE, "tol", "F", "stop when the relative change of the iterate falls below this (-1: the default)",
	    "0 with fista on l1 (every iteration: the capped iterate is the estimator), 1e-5 with pruned and cel0"),
	NUM(reweightings, C0_P_INT, "reweightings", "N", "CEL0 reweighting steps", "10"),
	NUM(lag, C0_P_INT, "lag", "PX", "covariance lag radius in pixels", "ceil(6 sigma / pixel)"),
	NUM(tile, C0_P_INT, "tile", "PX", "support and intensity tile side in camera pixels (tiles overlap by two lags)", "256, or the image when smaller"),
	ROW(drift, C0_P_ENUM, 0, 0, "off|on", "drift", "on|off", "estimate lateral drift from block means and undo it before the covariance and the means", "on"),
	ROW(pixel_guard, C0_P_ENUM, 0, 0, "off|on", "pixel-guard", "on|off", "clip each pixel's variance to what its covariances with its neighbours allow (noisy sCMOS pixels)", "on"),
	NUM(frc, C0_P_FLAG, "frc", "0|1", "solve each half of the frames too, for the localisation precision and the halves' FRC curve", "1"),
	/* intensity and background */
	ENUM(background, "none|constant|smooth", "background", "background model", "smooth"),
	NUM(beta, C0_P_DOUBLE, "beta", "B", "background curvature weight: beta/2 ||L b||^2, L the camera grid's Laplacian (smoothing length beta^(1/4) pixels)", "100"),
	NUM(nu, C0_P_DOUBLE, "nu", "F", "intensity discrepancy factor: residual^2 = nu^2 HW sigma2 / T (0: sqrt(T))", "1"),
	NUM(mu, C0_P_DOUBLE, "mu", "M", "fixed smoothness weight instead of the discrepancy principle", "0 (discrepancy)"),
	ENUM(discrepancy, "relative|plain", "discrepancy",
	     "intensity mu: residual = the model's floor (at mu = 1e-3) plus the noise level, or the noise level alone", "relative"),
	NUM(cg_tol, C0_P_DOUBLE, "tol", "F", "CG stopping tolerance, relative to the residual at intensity 0 and the background at the data's mean", "1e-3"),
	NUM(cg_iterations, C0_P_INT, "cg-iterations", "N", "CG steps per active-set round", "500"),
	NUM(graph_radius, C0_P_DOUBLE, "graph-radius", "PX", "intensity smoothness couples support pixels up to this far apart (fine pixels)", "6"),
	NUM(graph_orient, C0_P_DOUBLE, "graph-orient", "P", "intensity smoothness along the structure: an edge weighs (1 - cos^2)^(P/2), cos to the support's normal (0: every direction alike)", "20"),
	LIST(noise_variance, C0_P_DOUBLES, "noise-variance", "V,...", "per-stack noise variance (camera units^2)", "estimated on the support"),
	/* MA-TIRF */
	LIST(angles, C0_P_DOUBLES, "angles", "DEG,...", "incidence angle in the glass of each stack/image, same order", "none (2D)"),
	NUM(n_glass, C0_P_DOUBLE, "n-glass", "N", "refractive index of the coverslip and immersion", "1.518"),
	NUM(n_sample, C0_P_DOUBLE, "n-sample", "N", "refractive index of the sample", "1.33"),
	NUM(wavelength_nm, C0_P_DOUBLE, "wavelength", "NM", "excitation wavelength in vacuum", "488"),
	NUM(s_fraction, C0_P_DOUBLE, "s-fraction", "F", "share of s-polarised excitation in I0", "0.75"),
	LIST(gains, C0_P_DOUBLES, "gains", "G,...", "per-angle gain calibration (multiplies I0)", "1 for every angle"),
	ROW(z_range_nm, C0_P_DOUBLES, 0, 3, NULL, "z-range", "MIN,MAX,STEP", "depth bins in nm", "0,400,20"),
	ENUM(reg, "tv|hessian", "reg", "regulariser: total variation or Hessian-Schatten", "tv"),
	NUM(kappa, C0_P_DOUBLE, "kappa", "K", "regularisation weight (images scaled to a maximum of 1; -1: the default)",
	    "0.03, or 1e-3 with psf-fwhm"),
	NUM(sparsity, C0_P_DOUBLE, "sparsity", "S", "weight of the l1 term that keeps few depths per pixel", "0.03"),
	NUM(axial_weight, C0_P_DOUBLE, "axial-weight", "W", "axial weight of the regulariser relative to lateral", "0"),
	NUM(matirf_iterations, C0_P_INT, "matirf-iterations", "N", "maximum primal-dual iterations", "3000"),
	NUM(matirf_tol, C0_P_DOUBLE, "matirf-tol", "F", "primal-dual stopping tolerance (0: the solver's)", "1e-3 exact, 1e-4 diag, apg 5e-4 (TV) 1e-3 (Hessian)"),
	ENUM(matirf_solver, "exact|diag|auto|apg", "matirf-solver",
	     "exact per-pixel data steps, diagonal steps, or apg: the per-pixel steps by projected gradient (auto: apg)", "auto"),
	NUM(matirf_coarse, C0_P_INT, "matirf-coarse", "N", "levels of the warm start from 2x2-binned images (apg and exact with TV; -1: the default)", "2 with apg, else 0"),
	/* the standard MA-TIRF path on raw images */
	NUM(offset, C0_P_DOUBLE, "offset", "ADU", "camera offset subtracted from every image (refused at or above an image's mean)", "0"),
	NUM(matirf_background, C0_P_DOUBLE, "background", "V", "constant background subtracted after the offset", "0"),
	NUM(estimate_background, C0_P_FLAG, "estimate-background", NULL, "estimate a smooth background common to all angles jointly (background.tif)", "off"),
	NUM(background_smooth, C0_P_DOUBLE, "background-smooth", "PX2", "smoothness weight of the estimated background", "100"),
	NUM(psf_fwhm_nm, C0_P_DOUBLE, "psf-fwhm", "NM", "joint deconvolution: the images are the volume's projections blurred by a Gaussian PSF of this FWHM", "none"),
	/* depth pooling */
	NUM(depth_pool_nm, C0_P_DOUBLE, "depth-pool", "NM", "window over which intensities are summed for each pixel's depth: its length along the structure when guided (0: off; -1: the default)", "1.75 FWHM"),
	NUM(depth_pool_range_nm, C0_P_DOUBLE, "depth-pool-range", "NM", "only window pixels whose first depth guess is within NM of the centre's are summed (0: all; -1: the default)", "50"),
	NUM(depth_noise_block, C0_P_INT, "depth-noise-block", "N", "the depth fit weighs the angles by the intensities' noise, from two halves of each stack's frames in blocks of N frames (0: equal weights)", "20"),
	/* photobleaching */
	ENUM(bleach, "estimate|off|repeat", "bleach",
	     "photobleaching across the stacks: estimate the fade from the stacks' frame sums and divide each stack's intensity by its factor before MA-TIRF; "
	     "repeat: the last stack is a repeat of the first angle recorded at the end, the fade from its intensity relative to the first's "
	     "(it only measures the fade, not used in the MA-TIRF); or off", "estimate"),
	LIST(bleach_factors, C0_P_DOUBLES, "bleach-factors", "F,...", "known bleaching factors: each stack's mean population relative to the start of the acquisition", "estimated"),
	ENUM(acquisition, "sequential|interleaved", "acquisition", "how the stacks were recorded: one after another, or frame by frame in turn", "sequential"),
	LIST(acquisition_order, C0_P_INTS, "acquisition-order", "I,J,...", "the stack numbers (1-based, as given) in the order they were recorded", "as given"),
	LIST(gaps_frames, C0_P_DOUBLES, "gaps", "FRAMES,...", "illuminated but unrecorded time between consecutive recorded stacks, in frames (one value: all)", "none"),
	NUM(baseline, C0_P_FLAG, "baseline", NULL, "also reconstruct the standard MA-TIRF volume from the background-corrected means (baseline_*)", "off"),
	/* the camera's calibration (sCMOS; docs/guide.md: making the maps from dark frames) */
	NUM(offset_map, C0_P_STRING, "offset-map", "FILE.tif", "per-pixel dark level (ADU, one plane of the stacks' size): subtracted from every frame", "none"),
	NUM(variance_map, C0_P_STRING, "variance-map", "FILE.tif", "per-pixel read-noise variance (ADU^2): taken out of each pixel's variance in the covariance", "none"),
	NUM(gain_map, C0_P_STRING, "gain-map", "FILE.tif", "per-pixel gain (ADU per photon): frames are evened to the map's mean gain", "none"),
	ROW(common_pattern, C0_P_ENUM, 0, 0, "off|on", "common-pattern", "on|off", "without --offset-map: estimate the pixels' fixed pattern the angles' intensity fits share (sCMOS dark levels) and take it out of their means where it shows", "on"),
};
enum { NPARAMS = sizeof table / sizeof *table };
_Static_assert(NPARAMS <= 32 * sizeof ((struct c0_run_conf *)0)->given / sizeof(uint32_t), "c0_run_conf.given: too few bits");

void c0_param_mark_given(struct c0_run_conf *c, const struct c0_param *p)
{
	const int i = (int)(p - table);
	c->given[i / 32] |= 1u << (i % 32);
}

int c0_param_assumed(const struct c0_run_conf *c, const char *name)
{
	const struct c0_param *p = c0_param_find(name);
	const struct c0_run_conf d = C0_RUN_CONF_DEFAULTS;
	if (!p || p->type != C0_P_DOUBLE)
		return 0;
	const int i = (int)(p - table);
	return !(c->given[i / 32] >> (i % 32) & 1) && *(const double *)((const char *)c + p->off) ==
	       *(const double *)((const char *)&d + p->off);
}

const struct c0_param *c0_params(int *n)
{
	*n = NPARAMS;
	return table;
}

const struct c0_param *c0_param_find(const char *name)
{
	for (int i = 0; name && i < NPARAMS; i++)
		if (!strcmp(table[i].name, name))
			return &table[i];
	return NULL;
}

static int number(const char *s, double *v)
{
	char *end;
	errno = 0;
	*v = strtod(s, &end);
	return end != s && !errno && *v == *v && (*end == '\0' || *end == ',') ? (int)(end - s) : -1;
}

int c0_param_set(const struct c0_param *p, struct c0_run_conf *c, const char *name, const char *value)
{
	if (!value)
		return c0_fail(C0_EINVAL, "%s: missing value", name);
	char *f = (char *)c + p->off;
	if (p->type == C0_P_STRING) {   /* a file, kept by reference: the caller's string must outlive c */
		FILE *fp = *value ? fopen(value, "rb") : NULL;
		if (*value && !fp)
			return c0_fail(C0_EINVAL, "%s %s: %s", name, value, strerror(errno));
		if (fp)
			fclose(fp);
		*(const char **)f = *value ? value : NULL;
		return C0_OK;
	}
	double v;
	int k = number(value, &v);
	switch (p->type) {
	case C0_P_DOUBLE:
		if (k < 0 || value[k])
			return c0_fail(C0_EINVAL, "%s %s: expected a number", name, value);
		*(double *)f = v;
		return C0_OK;
	case C0_P_INT:
	case C0_P_FLAG:
		if (k < 0 || value[k] || v != (int)v || (p->type == C0_P_FLAG && v != 0 && v != 1))
			return c0_fail(C0_EINVAL, "%s %s: expected %s", name, value, p->type == C0_P_FLAG ? "0 or 1" : "an integer");
		*(int *)f = (int)v;
		return C0_OK;
	case C0_P_DOUBLES:
	case C0_P_INTS: {
		double tmp[C0_MAX_STACKS];
		int n = 0;
		for (const char *s = value; *s; n++) {
			if (n == p->max || (k = number(s, &tmp[n])) < 0)
				return c0_fail(C0_EINVAL, "%s %s: expected %s%d numbers, comma-separated", name, value,
					       p->count ? "up to " : "", p->max);
			if (p->type == C0_P_INTS && tmp[n] != (int)tmp[n])
				return c0_fail(C0_EINVAL, "%s %s: expected integers", name, value);
			s += k + (s[k] == ',');
		}
		if (p->count ? n == 0 : n != p->max)
			return c0_fail(C0_EINVAL, "%s %s: expected %s%d numbers, comma-separated", name, value,
				       p->count ? "up to " : "", p->max);
		for (int i = 0; i < n; i++)
			if (p->type == C0_P_INTS)
				((int *)f)[i] = (int)tmp[i];
			else
				((double *)f)[i] = tmp[i];
		if (p->count)
			*(int *)((char *)c + p->count) = n;
		return C0_OK;
	}
	case C0_P_STRING:
		break;
	case C0_P_ENUM: {
		const char *s = p->choices;
		for (int i = 0; s; i++) {
			const char *bar = strchr(s, '|');
			size_t l = bar ? (size_t)(bar - s) : strlen(s);
			if (strlen(value) == l && !strncmp(s, value, l)) {
				*(int *)f = i;   /* the enums are int-sized, valued in this order */
				return C0_OK;
			}
			s = bar ? bar + 1 : NULL;
		}
		return c0_fail(C0_EINVAL, "%s %s: expected one of %s", name, value, p->choices);
	}
	}
	return C0_EINVAL;
}
