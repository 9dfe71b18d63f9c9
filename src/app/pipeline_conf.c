/* The run configuration: setting a parameter by name (app/params.h holds
 * the table), and turning the whole into the stages' configs. */
#include "app/pipeline_conf.h"
#include "app/params.h"
#include "stages/depthpool.h"
#include "app/psfimage.h"
#include "core/err.h"
#include "c0_version.h"

#include "optics/psf.h"

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void c0_run_conf_init(struct c0_run_conf *c)
{
	*c = (struct c0_run_conf)C0_RUN_CONF_DEFAULTS;
}

const char *c0_run_conf_param(int i, const char **doc)
{
	int n;
	const struct c0_param *t = c0_params(&n);
	if (i < 0 || i >= n)
		return NULL;
	if (doc)
		*doc = t[i].doc;
	return t[i].name;
}

const char *c0_run_conf_param_info(int i, const char **kind, const char **choices, const char **help, const char **def)
{
	static const char *const kinds[] = { [C0_P_DOUBLE] = "number", [C0_P_INT] = "integer", [C0_P_FLAG] = "flag",
		[C0_P_DOUBLES] = "numbers", [C0_P_INTS] = "integers", [C0_P_ENUM] = "choice", [C0_P_STRING] = "file" };
	int n;
	const struct c0_param *t = c0_params(&n);
	if (i < 0 || i >= n)
		return NULL;
	if (kind)
		*kind = kinds[t[i].type];
	if (choices)
		*choices = t[i].choices;
	if (help)
		*help = t[i].help;
	if (def)
		*def = t[i].def;
	return t[i].name;
}

const char *c0_version(void)
{
	return C0_VERSION;
}

int c0_run_conf_set(struct c0_run_conf *c, const char *name, const char *value)
{
	const struct c0_param *p = c0_param_find(name);
	if (!p)
		return c0_fail(C0_EINVAL, "%s: unknown parameter", name ? name : "(null)");
	int st = c0_param_set(p, c, name, value);
	if (!st)
		c0_param_mark_given(c, p);
	return st;
}

void c0_run_conf_matirf(const struct c0_run_conf *c, struct c0_matirf_conf *m)
{
	*m = (struct c0_matirf_conf)C0_MATIRF_DEFAULTS;
	m->tirf = (struct c0_tirf){ c->n_glass, c->n_sample, c->wavelength_nm, c->s_fraction };
	m->z0_nm = c->z_range_nm[0], m->z1_nm = c->z_range_nm[1], m->dz_nm = c->z_range_nm[2];
	m->reg = c->reg, m->wz = c->axial_weight, m->sparsity = c->sparsity;
	/* -1: the default of the mode, measured per mode (docs/defaults.md#kappa);
	 * any other negative value is refused by c0_run_conf_matirf_check */
	m->kappa = c->kappa != -1 ? c->kappa : c->psf_fwhm_nm > 0 ? C0_MATIRF_KAPPA_DECONV : m->kappa;
	m->pdhg.maxit = c->matirf_iterations, m->pdhg.tol = c->matirf_tol;
	/* measured: apg takes half the CPU of exact and diag on the 350x350 phantom
	 * and less in the pipeline, with the same depths (docs/defaults.md#matirf_solver) */
	m->solver = c->matirf_solver != C0_MATIRF_AUTO ? c->matirf_solver : C0_MATIRF_APG;
	/* measured: 2 levels take apg from 343 to 71 full-grid iterations on the
	 * 350x350 phantom (2.3x less CPU), depths 0.45 nm from the cold start's
	 * (docs/defaults.md#matirf_coarse) */
	m->coarse = c->matirf_coarse >= 0 ? c->matirf_coarse : m->solver == C0_MATIRF_APG ? 2 : 0;
}

/* matirf_coarse's range, for every run and for the matirf command */
static int coarse_check(const struct c0_run_conf *c)
{
	if (c->matirf_coarse < -1 || c->matirf_coarse > 8)
		return c0_fail(C0_EINVAL, "matirf_coarse %d: must be -1 (the solver's default) or 0..8", c->matirf_coarse);
	return C0_OK;
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
	if (!(c->label_radius_nm >= 0 && c->label_radius_nm <= fwhm))
		return c0_fail(C0_EINVAL, "label_radius_nm %g: must be a radius in nm, 0 to the PSF's FWHM (%g)", c->label_radius_nm, fwhm);
	if (!(c->depth_pool_nm >= -1 && c->depth_pool_nm <= 100 * fwhm))
		return c0_fail(C0_EINVAL, "depth_pool_nm %g: must be a window in nm (0: off, -1: the default, %g FWHM)", c->depth_pool_nm, C0_DEPTH_POOL_FWHM);
	if (!(c->depth_pool_range_nm >= -1 && isfinite(c->depth_pool_range_nm)))
		return c0_fail(C0_EINVAL, "depth_pool_range_nm %g: must be a depth difference in nm (0: every pixel of the window, -1: the default, %d)",
			       c->depth_pool_range_nm, C0_DEPTH_POOL_RANGE_NM);
	if (c->depth_noise_block < 0)
		return c0_fail(C0_EINVAL, "depth_noise_block %d: must be a number of frames (0: equal weights)", c->depth_noise_block);
	const struct c0_grid grid = { pixel_nm, fwhm, c->srf };
	s->support = (struct c0_support_conf){ .grid = grid, .penalty = c->penalty,
					       .lambda_rel = c->lambda, .lag = c->lag,
					       .fista = { c->iterations != -1 ? c->iterations
							  : c->support_solver == C0_SUPPORT_PRUNED ? C0_PRUNED_MAXIT : C0_FISTA_MAXIT,
							  c->tol },
					       .cel0_outer = c->reweightings,
					       .solver = c->support_solver,
					       .frc = c->frc, .tile = c->tile, .guard = c->pixel_guard,
					       .lambda_cv = c->lambda_rule == C0_LAMBDA_CV,
					       .lambda_noise = c->lambda_rule == C0_LAMBDA_NOISE,
					       .fwhm_data = c->fwhm_rule == C0_FWHM_DATA,
					       .label_radius_nm = c->label_radius_nm };
	s->intensity = (struct c0_intensity_conf){ .grid = grid,
						   .background = c->background, .beta = c->beta, .nu = c->nu, .mu = c->mu,
						   .tol = c->cg_tol, .maxit = c->cg_iterations,
						   .graph_radius = c->graph_radius, .graph_orient = c->graph_orient, .relative = c->discrepancy == C0_DISCREPANCY_RELATIVE,
						   .tile = c->tile > 0 ? c->tile : C0_SUPPORT_TILE,
						   .common_pattern = c->common_pattern };
	c0_run_conf_matirf(c, &s->matirf);
	if (c->kappa == -1)   /* run's MA-TIRF step does not deconvolve (docs/defaults.md#psf_fwhm_nm): the plain default */
		s->matirf.kappa = ((struct c0_matirf_conf)C0_MATIRF_DEFAULTS).kappa;
	s->pool_per_fwhm = c->depth_pool_nm < 0;
	s->pool_nm = s->pool_per_fwhm ? C0_DEPTH_POOL_FWHM * fwhm : c->depth_pool_nm;
	s->pool_range_nm = c->depth_pool_range_nm < 0 ? C0_DEPTH_POOL_RANGE_NM : c->depth_pool_range_nm;
	/* the halves serve the guided pool's depth fit alone */
	s->intensity.noise_block = c->nangles > 0 && s->pool_nm > 0 && s->pool_range_nm > 0 ? c->depth_noise_block : 0;
	if ((unsigned)c->discrepancy > C0_DISCREPANCY_PLAIN || (unsigned)c->bleach > C0_BLEACHING_REPEAT ||
	    (unsigned)c->acquisition > C0_ACQ_INTERLEAVED)
		return c0_fail(C0_EINVAL, "discrepancy %d / bleach %d / acquisition %d: out of range", (int)c->discrepancy,
			       (int)c->bleach, (int)c->acquisition);
	if ((unsigned)c->lambda_rule > C0_LAMBDA_NOISE)
		return c0_fail(C0_EINVAL, "lambda_rule %d: out of range", (int)c->lambda_rule);
	if ((unsigned)c->fwhm_rule > C0_FWHM_DATA)
		return c0_fail(C0_EINVAL, "fwhm_rule %d: out of range", (int)c->fwhm_rule);
	if ((unsigned)c->penalty > C0_PENALTY_CEL0 || (unsigned)c->support_solver > C0_SUPPORT_PRUNED ||
	    (unsigned)c->background > C0_BG_SMOOTH || (unsigned)c->reg > C0_REG_HESSIAN || (unsigned)c->matirf_solver > C0_MATIRF_APG)
		return c0_fail(C0_EINVAL, "penalty %d / support_solver %d / background %d / reg %d / matirf_solver %d: out of range",
			       (int)c->penalty, (int)c->support_solver, (int)c->background, (int)c->reg, (int)c->matirf_solver);
	int st = coarse_check(c);
	if (st)
		return st;
	if (c->nangles < 0 || c->nangles > C0_MAX_STACKS || c->ngains < 0 || c->ngains > C0_MAX_STACKS ||
	    c->nsupport_stacks < 0 || c->nsupport_stacks > C0_MAX_STACKS || c->nnoise_variance < 0 ||
	    c->nnoise_variance > C0_MAX_STACKS)
		return c0_fail(C0_EINVAL, "nangles %d / ngains %d / nsupport_stacks %d / nnoise_variance %d: must be 0..%d",
			       c->nangles, c->ngains, c->nsupport_stacks, c->nnoise_variance, C0_MAX_STACKS);
	st = c0_grid_check(&grid);
	if (!st)
		st = c0_intensity_check(&s->intensity);
	c0_run_conf_bleach(c, &s->bleach);
	s->drift = (struct c0_drift_conf)C0_DRIFT_DEFAULTS;
	if (!st)
		s->drift.psf_sigma_px = c0_grid_sigma_px(&grid);
	return st;
}

/* The MA-TIRF parameters by their run names (the stage's own check names
 * its fields, which a run's user never sees). */
static int matirf_params(const struct c0_run_conf *c)
{
	const double *z = c->z_range_nm;
	if (!(z[2] > 0) || !(z[1] > z[0]) || !(z[0] >= 0) || !isfinite(z[1]))
		return c0_fail(C0_EINVAL, "z_range_nm %g,%g,%g: need 0 <= min < max and a positive step (nm)", z[0], z[1], z[2]);
	if ((z[1] - z[0]) / z[2] > 512)
		return c0_fail(C0_EINVAL, "z_range_nm: more than 512 depth bins");
	if (!(c->psf_fwhm_nm >= 0 && isfinite(c->psf_fwhm_nm)))
		return c0_fail(C0_EINVAL, "psf_fwhm_nm %g: must be a positive, finite number of nm (0: no deconvolution)", c->psf_fwhm_nm);
	if (!(c->background_smooth >= 0))
		return c0_fail(C0_EINVAL, "background_smooth %g: must be >= 0", c->background_smooth);
	if (!((c->kappa >= 0 || c->kappa == -1) && isfinite(c->kappa)))
		return c0_fail(C0_EINVAL, "kappa %g: must be finite and >= 0 (-1: the default)", c->kappa);
	if (!(c->axial_weight >= 0 && isfinite(c->axial_weight)) || !(c->sparsity >= 0 && isfinite(c->sparsity)))
		return c0_fail(C0_EINVAL, "axial_weight %g, sparsity %g: must be finite and >= 0", c->axial_weight, c->sparsity);
	int st = coarse_check(c);
	if (st)
		return st;
	if (c->matirf_iterations < 1)
		return c0_fail(C0_EINVAL, "matirf_iterations %d: must be at least 1", c->matirf_iterations);
	if (!(c->matirf_tol >= 0 && isfinite(c->matirf_tol)))
		return c0_fail(C0_EINVAL, "matirf_tol %g: must be >= 0", c->matirf_tol);
	return C0_OK;
}

int c0_run_conf_angles_check(const struct c0_run_conf *c, int n)
{
	if (c->nangles != n)
		return c0_fail(C0_EINVAL, "angles: %d angles for %d stacks (one per stack, same order)", c->nangles, n);
	if (c->ngains && c->ngains != n)
		return c0_fail(C0_EINVAL, "gains: %d gains for %d stacks", c->ngains, n);
	return C0_OK;
}

int c0_run_conf_matirf_check(const struct c0_run_conf *c, const struct c0_matirf_conf *m, int nimages)
{
	int st = matirf_params(c);
	if (!st)
		st = c0_run_conf_angles_check(c, nimages);
	if (st)
		return st;
	for (int q = 0; q < c->ngains; q++)
		if (!(c->gains[q] > 0 && isfinite(c->gains[q])))
			return c0_fail(C0_EINVAL, "gains: gain %d is %g, must be > 0", q + 1, c->gains[q]);
	return c0_matirf_check(m, c->nangles, c->angles);
}

void c0_run_conf_bleach(const struct c0_run_conf *c, struct c0_bleach_conf *bc)
{
	*bc = (struct c0_bleach_conf){ .mode = c->nbleach_factors ? C0_BLEACH_KNOWN
					       : c->bleach == C0_BLEACHING_OFF ? C0_BLEACH_OFF
					       : c->bleach == C0_BLEACHING_REPEAT ? C0_BLEACH_REPEAT : C0_BLEACH_ESTIMATE,
				       .interleaved = c->acquisition == C0_ACQ_INTERLEAVED, .norder = c->nacquisition_order,
				       .ngaps = c->ngaps_frames, .nfactors = c->nbleach_factors };
	for (int i = 0; i < c->nacquisition_order && i < C0_BLEACH_MAX; i++)
		bc->order[i] = c->acquisition_order[i] - 1;
	for (int i = 0; i < c->ngaps_frames && i < C0_BLEACH_MAX; i++)
		bc->gap_frames[i] = c->gaps_frames[i];
	for (int i = 0; i < c->nbleach_factors && i < C0_BLEACH_MAX; i++)
		bc->factor[i] = c->bleach_factors[i];
}

void c0_stage_confs_width(struct c0_stage_confs *s, double fwhm_nm)
{
	c0_support_set_width(&s->support, fwhm_nm);
	if (s->pool_per_fwhm)
		s->pool_nm = C0_DEPTH_POOL_FWHM * fwhm_nm;
	s->intensity.grid.fwhm_nm = fwhm_nm;
}

void c0_run_conf_angles(const struct c0_run_conf *c, struct c0_angles *a)
{
	memset(a, 0, sizeof *a);
	a->n = c->nangles, a->ngains = c->ngains;
	for (int q = 0; q < c->nangles && q < C0_MAX_STACKS; q++)
		a->deg[q] = c->angles[q];
	for (int q = 0; q < c->ngains && q < C0_MAX_STACKS; q++)
		a->gain[q] = c->gains[q];
}

int c0_run_conf_matirf_raw(const struct c0_run_conf *c, double pixel_nm, struct c0_matirf_conf *m, struct c0_matirf_raw *raw)
{
	if (c->psf_fwhm_nm != 0) {
		if (!(c->psf_fwhm_nm > 0) || !(pixel_nm > 0))
			return c0_fail(C0_EINVAL, "psf_fwhm_nm %g: needs a positive FWHM and the pixel size (pixel_nm or the TIFF calibration)",
				       c->psf_fwhm_nm);
		m->psf_sigma_px = c0_psf_sigma_px(c->psf_fwhm_nm, pixel_nm);
	}
	if (c->estimate_background) {
		if (!(c->background_smooth > 0))
			return c0_fail(C0_EINVAL, "background_smooth %g: must be > 0", c->background_smooth);
		m->bg_smooth = c->background_smooth;
	}
	c0_run_conf_angles(c, &raw->angles);
	raw->offset = c->offset, raw->background = c->matirf_background;
	raw->psf_fwhm_nm = c->psf_fwhm_nm, raw->background_smooth = c->background_smooth;
	return C0_OK;
}
