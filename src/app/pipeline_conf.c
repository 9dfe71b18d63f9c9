/* The run configuration: one table gives each parameter's name, type, field
 * and help; setting by name, and turning it into the stages' configs. */
#include "app/pipeline.h"
#include "stages/depthpool.h"
#include "stages/psfimage.h"
#include "core/err.h"
#include "c0_version.h"

#include "optics/psf.h"

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum ptype { P_DOUBLE, P_INT, P_FLAG, P_DOUBLES, P_INTS, P_ENUM, P_STRING };

struct param {
	const char *name;
	enum ptype type;
	size_t off;          /* the field */
	size_t count;        /* lists: the count field, 0 for a fixed length */
	int max;             /* lists: capacity (fixed length when count is 0) */
	const char *choices; /* enums: names in value order, '|'-separated */
	const char *doc;
};

#define F(f) offsetof(struct c0_run_conf, f)
#define NUM(n, t, doc) { #n, t, F(n), 0, 0, NULL, doc }
#define LIST(x, t, doc) { #x, t, F(x), F(n##x), C0_MAX_STACKS, NULL, doc }
static const struct param params[] = {
	NUM(pixel_nm, P_DOUBLE, "camera pixel size in the sample, nm (0: the first stack's calibration)"),
	NUM(fwhm_nm, P_DOUBLE, "PSF full width at half maximum, nm (0: 0.51 emission_nm / na)"),
	NUM(psf_image, P_STRING, "measured PSF image (TIFF): its fitted Gaussian FWHM instead of fwhm_nm (none)"),
	NUM(emission_nm, P_DOUBLE, "emission wavelength, nm, with na instead of fwhm_nm (0)"),
	NUM(na, P_DOUBLE, "numerical aperture of the objective, with emission_nm (0)"),
	NUM(srf, P_INT, "super-resolution factor: fine pixel = pixel_nm / srf (4)"),
	{ "support_stacks", P_INTS, F(support_stacks), F(nsupport_stacks), C0_MAX_STACKS, NULL,
	  "1-based stack numbers whose supports are joined (none: the smallest angle)" },
	{ "penalty", P_ENUM, F(penalty), 0, 0, "l1|cel0", "support sparsity penalty (l1)" },
	NUM(lambda, P_DOUBLE, "support regularisation relative to lambda_max (0: automatic, from the noise of the frame halves)"),
	NUM(lag, P_INT, "covariance lag radius in pixels (0: ceil(6 sigma / pixel))"),
	NUM(iterations, P_INT, "maximum FISTA iterations, per reweighting for cel0 (-1: 2000, or 10000 for pruned)"),
	{ "support_solver", P_ENUM, F(support_solver), 0, 0, "fista|pruned",
	  "l1 support solver: FISTA on a working set re-made every 100 iterations, with the whole grid's step (fista) or the set's own (pruned)" },
	NUM(tol, P_DOUBLE, "FISTA stops when the iterate's relative change falls below this (-1: 0 for fista on l1, every iteration; 1e-5 for pruned and cel0)"),
	NUM(reweightings, P_INT, "CEL0 reweighting steps (10)"),
	{ "drift", P_ENUM, F(drift), 0, 0, "off|on", "estimate lateral drift from block means and undo it before the covariance and the means (on)" },
	{ "pixel_guard", P_ENUM, F(pixel_guard), 0, 0, "off|on", "clip each pixel's temporal variance to what its covariances with its neighbours allow, against pixels with noise of their own (on)" },
	NUM(frc, P_FLAG, "1: also solve each half of the frames for the FRC resolution and the localisation precision (1)"),
	NUM(tile, P_INT, "support and intensity tile side in camera pixels, tiles overlap by two lags (0: 256, or the image when smaller)"),
	{ "background", P_ENUM, F(background), 0, 0, "none|constant|smooth", "background model (smooth)" },
	NUM(beta, P_DOUBLE, "background smoothness weight (20)"),
	NUM(nu, P_DOUBLE, "intensity discrepancy factor: residual^2 = nu^2 HW sigma2 / T (1; 0: sqrt(T))"),
	NUM(mu, P_DOUBLE, "fixed intensity smoothness weight (0: discrepancy principle)"),
	{ "discrepancy", P_ENUM, F(discrepancy), 0, 0, "relative|plain",
	  "intensity mu: residual = the model's floor (at mu = 1e-3) plus the noise level, or the noise level alone (relative)" },
	NUM(cg_tol, P_DOUBLE, "CG stopping tolerance, relative residual (1e-3)"),
	NUM(cg_iterations, P_INT, "CG steps per active-set round (500)"),
	NUM(graph_radius, P_DOUBLE, "intensity smoothness couples support pixels up to this far apart, fine pixels (2.25)"),
	LIST(noise_variance, P_DOUBLES, "per-stack noise variance, camera units^2 (none: estimated on the support)"),
	LIST(angles, P_DOUBLES, "incidence angle in the glass of each stack, deg, same order (none: 2D)"),
	LIST(gains, P_DOUBLES, "per-angle gain calibration, multiplies I0 (none: 1 for every angle)"),
	NUM(n_glass, P_DOUBLE, "refractive index of the coverslip and immersion (1.518)"),
	NUM(n_sample, P_DOUBLE, "refractive index of the sample (1.33)"),
	NUM(wavelength_nm, P_DOUBLE, "excitation wavelength in vacuum, nm (488)"),
	NUM(s_fraction, P_DOUBLE, "share of s-polarised excitation in I0 (0.75)"),
	{ "z_range_nm", P_DOUBLES, F(z_range_nm), 0, 3, NULL, "depth bins MIN,MAX,STEP in nm (0,400,20)" },
	{ "reg", P_ENUM, F(reg), 0, 0, "tv|hessian", "MA-TIRF regulariser: total variation or Hessian-Schatten (tv)" },
	NUM(kappa, P_DOUBLE, "MA-TIRF regularisation weight, images scaled to a maximum of 1 (3e-2)"),
	NUM(sparsity, P_DOUBLE, "weight of the l1 term that keeps few depths per pixel (3e-2)"),
	NUM(axial_weight, P_DOUBLE, "axial weight of the regulariser relative to lateral (0)"),
	NUM(matirf_iterations, P_INT, "maximum primal-dual iterations (3000)"),
	NUM(matirf_tol, P_DOUBLE, "primal-dual stopping tolerance (0: 1e-3 exact, 1e-4 diag)"),
	{ "matirf_solver", P_ENUM, F(matirf_solver), 0, 0, "exact|diag|auto|apg", "MA-TIRF solver: exact per-pixel data steps, diagonal steps, or apg (the exact per-pixel steps by a few projected gradient steps; auto: apg, docs/parameters.md)" },
	NUM(matirf_coarse, P_INT, "levels of the warm start from 2x2-binned images, apg and exact with TV (-1: 2 with apg, else 0)"),
	NUM(offset, P_DOUBLE, "camera offset subtracted from every image, standard MA-TIRF path (0)"),
	NUM(matirf_background, P_DOUBLE, "constant background subtracted after the offset, standard MA-TIRF path (0)"),
	NUM(estimate_background, P_FLAG, "1: estimate a smooth background common to all angles jointly, standard MA-TIRF path (0)"),
	NUM(background_smooth, P_DOUBLE, "smoothness weight of the estimated background, px^2 (100)"),
	NUM(psf_fwhm_nm, P_DOUBLE, "joint deconvolution by a Gaussian PSF of this FWHM, nm, standard MA-TIRF path (0: none)"),
	NUM(depth_pool_nm, P_DOUBLE, "window over which intensities are summed for each pixel's depth, nm (-1: 0.75 fwhm_nm, 0: off)"),
	NUM(depth_pool_range_nm, P_DOUBLE, "only window pixels whose first depth guess is this close to the centre's are summed, nm (-1: 50, 0: all)"),
	{ "bleach", P_ENUM, F(bleach), 0, 0, "estimate|off", "photobleaching across the stacks: estimate and correct the fade, or off (estimate; 3D mode)" },
	LIST(bleach_factors, P_DOUBLES, "known bleaching factors, each stack's mean population relative to the start (none: estimated)"),
	{ "acquisition", P_ENUM, F(acquisition), 0, 0, "sequential|interleaved",
	  "stacks recorded one after another, or frame by frame in turn (sequential)" },
	LIST(acquisition_order, P_INTS, "1-based stack numbers in the order they were recorded (none: as given)"),
	LIST(gaps_frames, P_DOUBLES, "illuminated, unrecorded frames between consecutive recorded stacks (none)"),
	NUM(baseline, P_FLAG, "1: also reconstruct the standard MA-TIRF volume from the background-corrected means (0)"),
};
enum { NPARAMS = sizeof params / sizeof *params };

void c0_run_conf_init(struct c0_run_conf *c)
{
	*c = (struct c0_run_conf)C0_RUN_CONF_DEFAULTS;
}

const char *c0_run_conf_param(int i, const char **doc)
{
	if (i < 0 || i >= NPARAMS)
		return NULL;
	if (doc)
		*doc = params[i].doc;
	return params[i].name;
}

const char *c0_version(void)
{
	return C0_VERSION;
}

static int number(const char *s, double *v)
{
	char *end;
	errno = 0;
	*v = strtod(s, &end);
	return end != s && !errno && *v == *v && (*end == '\0' || *end == ',') ? (int)(end - s) : -1;
}

int c0_run_conf_set(struct c0_run_conf *c, const char *name, const char *value)
{
	const struct param *p = NULL;
	for (int i = 0; name && i < NPARAMS; i++)
		if (!strcmp(params[i].name, name))
			p = &params[i];
	if (!p)
		return c0_fail(C0_EINVAL, "%s: unknown parameter", name ? name : "(null)");
	if (!value)
		return c0_fail(C0_EINVAL, "%s: missing value", name);
	char *f = (char *)c + p->off;
	if (p->type == P_STRING) {   /* a file, kept by reference: the caller's string must outlive c */
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
	case P_DOUBLE:
		if (k < 0 || value[k])
			return c0_fail(C0_EINVAL, "%s %s: expected a number", name, value);
		*(double *)f = v;
		return C0_OK;
	case P_INT:
	case P_FLAG:
		if (k < 0 || value[k] || v != (int)v || (p->type == P_FLAG && v != 0 && v != 1))
			return c0_fail(C0_EINVAL, "%s %s: expected %s", name, value, p->type == P_FLAG ? "0 or 1" : "an integer");
		*(int *)f = (int)v;
		return C0_OK;
	case P_DOUBLES:
	case P_INTS: {
		double tmp[C0_MAX_STACKS];
		int n = 0;
		for (const char *s = value; *s; n++) {
			if (n == p->max || (k = number(s, &tmp[n])) < 0)
				return c0_fail(C0_EINVAL, "%s %s: expected %s%d numbers, comma-separated", name, value,
					       p->count ? "up to " : "", p->max);
			if (p->type == P_INTS && tmp[n] != (int)tmp[n])
				return c0_fail(C0_EINVAL, "%s %s: expected integers", name, value);
			s += k + (s[k] == ',');
		}
		if (p->count ? n == 0 : n != p->max)
			return c0_fail(C0_EINVAL, "%s %s: expected %s%d numbers, comma-separated", name, value,
				       p->count ? "up to " : "", p->max);
		for (int i = 0; i < n; i++)
			if (p->type == P_INTS)
				((int *)f)[i] = (int)tmp[i];
			else
				((double *)f)[i] = tmp[i];
		if (p->count)
			*(int *)((char *)c + p->count) = n;
		return C0_OK;
	}
	case P_STRING:
		break;
	case P_ENUM: {
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

void c0_run_conf_matirf(const struct c0_run_conf *c, struct c0_matirf_conf *m)
{
	*m = (struct c0_matirf_conf)C0_MATIRF_DEFAULTS;
	m->tirf = (struct c0_tirf){ c->n_glass, c->n_sample, c->wavelength_nm, c->s_fraction };
	m->z0_nm = c->z_range_nm[0], m->z1_nm = c->z_range_nm[1], m->dz_nm = c->z_range_nm[2];
	m->reg = c->reg, m->kappa = c->kappa, m->wz = c->axial_weight, m->sparsity = c->sparsity;
	m->pdhg.maxit = c->matirf_iterations, m->pdhg.tol = c->matirf_tol;
	/* measured: apg takes half the CPU of exact and diag on the 350x350 phantom
	 * and less in the pipeline, with the same depths (docs/parameters.md) */
	m->solver = c->matirf_solver != C0_MATIRF_AUTO ? c->matirf_solver : C0_MATIRF_APG;
	/* measured: 2 levels take apg from 343 to 71 full-grid iterations on the
	 * 350x350 phantom (2.3x less CPU), depths 0.45 nm from the cold start's
	 * (docs/parameters.md) */
	m->coarse = c->matirf_coarse >= 0 ? c->matirf_coarse : m->solver == C0_MATIRF_APG ? 2 : 0;
}

int c0_run_conf_stages(const struct c0_run_conf *c, double pixel_nm, struct c0_stage_confs *s)
{
	double fwhm = c->fwhm_nm;
	s->psf_fitted = 0;
	if (c->psf_image) {
		if (fwhm > 0 || c->emission_nm > 0)
			return c0_fail(C0_EINVAL, "psf_image %s: give the PSF width once (psf_image, fwhm_nm or emission_nm with na)", c->psf_image);
		int st = c0_psf_fit_file(c->psf_image, &s->psf, &s->psf_pixel_nm);
		if (st)
			return st;
		s->psf_fitted = 1;
		fwhm = s->psf.fwhm_px * (s->psf_pixel_nm > 0 ? s->psf_pixel_nm : pixel_nm);   /* uncalibrated: the camera's pixels */
	}
	if (fwhm == 0) {
		if (!c->emission_nm && !c->na)
			return c0_fail(C0_EINVAL, "fwhm_nm %g: give the PSF FWHM, or the emission wavelength (emission_nm) and numerical aperture (na)", fwhm);
		int st = c0_fwhm_from_na(c->emission_nm, c->na, c->n_glass, &fwhm);
		if (st)
			return st;
	}
	if (!(c->depth_pool_nm >= -1 && c->depth_pool_nm <= 100 * fwhm))
		return c0_fail(C0_EINVAL, "depth_pool_nm %g: must be a window in nm (0: off, -1: the default, %g FWHM)", c->depth_pool_nm, C0_DEPTH_POOL_FWHM);
	if (!(c->depth_pool_range_nm >= -1 && isfinite(c->depth_pool_range_nm)))
		return c0_fail(C0_EINVAL, "depth_pool_range_nm %g: must be a depth difference in nm (0: every pixel of the window, -1: the default, %d)",
			       c->depth_pool_range_nm, C0_DEPTH_POOL_RANGE_NM);
	s->support = (struct c0_support_conf){ .pixel_nm = pixel_nm, .fwhm_nm = fwhm, .srf = c->srf, .penalty = c->penalty,
					       .lambda_rel = c->lambda, .lag = c->lag,
					       .fista = { c->iterations != -1 ? c->iterations
							  : c->support_solver == C0_SUPPORT_PRUNED ? C0_PRUNED_MAXIT : C0_FISTA_MAXIT,
							  c->tol },
					       .cel0_outer = c->reweightings,
					       .solver = c->support_solver,
					       .frc = c->frc, .tile = c->tile, .guard = c->pixel_guard };
	s->intensity = (struct c0_intensity_conf){ .pixel_nm = pixel_nm, .fwhm_nm = fwhm, .srf = c->srf,
						   .background = c->background, .beta = c->beta, .nu = c->nu, .mu = c->mu,
						   .tol = c->cg_tol, .maxit = c->cg_iterations,
						   .graph_radius = c->graph_radius, .relative = c->discrepancy == C0_DISCREPANCY_RELATIVE,
						   .tile = c->tile > 0 ? c->tile : C0_SUPPORT_TILE };
	c0_run_conf_matirf(c, &s->matirf);
	s->pool_nm = c->depth_pool_nm < 0 ? C0_DEPTH_POOL_FWHM * fwhm : c->depth_pool_nm;
	s->pool_range_nm = c->depth_pool_range_nm < 0 ? C0_DEPTH_POOL_RANGE_NM : c->depth_pool_range_nm;
	if ((unsigned)c->discrepancy > C0_DISCREPANCY_PLAIN || (unsigned)c->bleach > C0_BLEACHING_OFF ||
	    (unsigned)c->acquisition > C0_ACQ_INTERLEAVED)
		return c0_fail(C0_EINVAL, "discrepancy %d / bleach %d / acquisition %d: out of range", (int)c->discrepancy,
			       (int)c->bleach, (int)c->acquisition);
	if ((unsigned)c->penalty > C0_PENALTY_CEL0 || (unsigned)c->support_solver > C0_SUPPORT_PRUNED ||
	    (unsigned)c->background > C0_BG_SMOOTH || (unsigned)c->reg > C0_REG_HESSIAN || (unsigned)c->matirf_solver > C0_MATIRF_APG)
		return c0_fail(C0_EINVAL, "penalty %d / support_solver %d / background %d / reg %d / matirf_solver %d: out of range",
			       (int)c->penalty, (int)c->support_solver, (int)c->background, (int)c->reg, (int)c->matirf_solver);
	if (c->matirf_coarse < -1 || c->matirf_coarse > 8)
		return c0_fail(C0_EINVAL, "matirf_coarse %d: must be -1 (the solver's default) or 0..8", c->matirf_coarse);
	if (c->nangles < 0 || c->nangles > C0_MAX_STACKS || c->ngains < 0 || c->ngains > C0_MAX_STACKS ||
	    c->nsupport_stacks < 0 || c->nsupport_stacks > C0_MAX_STACKS || c->nnoise_variance < 0 ||
	    c->nnoise_variance > C0_MAX_STACKS)
		return c0_fail(C0_EINVAL, "nangles %d / ngains %d / nsupport_stacks %d / nnoise_variance %d: must be 0..%d",
			       c->nangles, c->ngains, c->nsupport_stacks, c->nnoise_variance, C0_MAX_STACKS);
	int st = c0_psf_check(pixel_nm, fwhm, c->srf);
	return st ? st : c0_intensity_check(&s->intensity);
}

int c0_run_conf_matirf_check(const struct c0_run_conf *c, const struct c0_matirf_conf *m, int nimages)
{
	if (c->nangles != nimages)
		return c0_fail(C0_EINVAL, "angles: %d angles for %d stacks (one per stack, same order)", c->nangles, nimages);
	if (c->ngains && c->ngains != nimages)
		return c0_fail(C0_EINVAL, "gains: %d gains for %d stacks", c->ngains, nimages);
	for (int q = 0; q < c->ngains; q++)
		if (!(c->gains[q] > 0 && isfinite(c->gains[q])))
			return c0_fail(C0_EINVAL, "gains: gain %d is %g, must be > 0", q + 1, c->gains[q]);
	return c0_matirf_check(m, c->nangles, c->angles);
}
