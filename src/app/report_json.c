/* The other steps' parts of report.json: drift, render, intensity,
 * bleaching, MA-TIRF and the run's parameters. */
#include "app/report_json.h"
#include "stages/depthfit.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>

int c0_report_drift(cJSON *rep, const struct c0_drift *d, double px)
{
	struct c0_drift_info in;
	c0_drift_get_info(d, &in);
	cJSON *j = cJSON_AddObjectToObject(rep, "drift");
	cJSON_AddStringToObject(j, "method", "block means filtered by the PSF and cross-correlated (chained, then against the mean of all blocks), "
				"sub-pixel peak; frames shifted back by a mirrored Fourier shift");
	cJSON_AddNumberToObject(j, "block_frames", in.block);
	cJSON_AddNumberToObject(j, "blocks", in.blocks);
	cJSON_AddNumberToObject(j, "max_nm", in.max_px * px);
	double nz[2] = { in.noise_px[0] * px, in.noise_px[1] * px }, cr[2] = { in.corrected[0], in.corrected[1] };
	c0_report_add_array(j, "block_noise_nm", nz, 2);
	c0_report_add_array(j, "corrected_xy", cr, 2);
	double *b = c0_alloc(3 * (size_t)in.blocks + 1, sizeof *b);
	if (!b)
		return C0_ENOMEM;
	for (int k = 0; k < in.blocks; k++)
		b[k] = in.bt[k] + 1, b[in.blocks + k] = in.bx[k] * px, b[2 * in.blocks + k] = in.by[k] * px;
	c0_report_add_array(j, "block_centre_frame", b, in.blocks);
	c0_report_add_array(j, "block_dx_nm", b + in.blocks, in.blocks);
	c0_report_add_array(j, "block_dy_nm", b + 2 * in.blocks, in.blocks);
	free(b);
	cJSON_AddStringToObject(j, "trajectory", "drift.csv (nm per frame), drift.png");
	cJSON_AddNumberToObject(j, "seconds", in.seconds);
	return C0_OK;
}

void c0_report_render(cJSON *rep, double sd, double prec, double fine)
{
	cJSON *j = cJSON_AddObjectToObject(rep, "render");
	cJSON_AddStringToObject(j, "file", "render.tif");
	cJSON_AddStringToObject(j, "content", "each stack's intensity (one plane each) splatted with a normalised Gaussian "
				"of sd max(localisation precision, half a fine pixel)");
	cJSON_AddNumberToObject(j, "gaussian_sd_nm", sd);
	cJSON_AddNumberToObject(j, "localisation_precision_nm", prec);
	cJSON_AddNumberToObject(j, "pixel_nm", fine);
}

static cJSON *intensity_stack(const char *name, const struct c0_intensity_result *s, const struct c0_intensity_conf *ic,
			      int64_t frames, double tc)
{
	static const char *dp[] = {
		"met",
		"below: even the smallest mu leaves a residual above the target, so the intensity is as little smoothed as allowed (give mu to smooth more)",
		"above: even the largest mu leaves a residual below the target, so the intensity is as smooth as allowed (lower nu or give mu for more detail)",
		"not converged: mu is the last one tried (give mu to fix it)" };
	cJSON *j = cJSON_CreateObject();
	cJSON_AddStringToObject(j, "stack", name);
	cJSON_AddNumberToObject(j, "frames", (double)frames);
	cJSON_AddNumberToObject(j, "noise_variance", s->sigma2);
	cJSON_AddNumberToObject(j, "mu", s->mu);
	cJSON_AddNumberToObject(j, "residual2", s->residual2);
	cJSON_AddNumberToObject(j, "discrepancy_target2", s->target2);
	if (ic->relative && s->dp_status >= 0)
		cJSON_AddNumberToObject(j, "residual_floor2", s->floor2);
	cJSON_AddStringToObject(j, "discrepancy", s->dp_status < 0 ? "fixed mu" : dp[s->dp_status]);
	cJSON_AddNumberToObject(j, "tiles", s->tiles);
	cJSON_AddNumberToObject(j, "tiles_discrepancy_met", s->tiles_met);
	cJSON_AddNumberToObject(j, "solves", s->solves);
	cJSON_AddNumberToObject(j, "cg_iterations", s->cg_iters);
	cJSON_AddNumberToObject(j, "seconds", s->seconds + tc);
	return j;
}

void c0_report_intensity(cJSON *rep, const struct c0_result *r, const struct c0_intensity_conf *ic,
			 const int64_t *frames, const double *tc, const double *mu_own)
{
	cJSON *arr = cJSON_AddArrayToObject(rep, "intensity");
	for (int i = 0; i < r->n; i++) {
		cJSON *j = intensity_stack(r->names[i], &r->ires[i], ic, frames[i], tc[i]);
		if (mu_own)
			cJSON_AddNumberToObject(j, "mu_own", mu_own[i]);
		cJSON_AddItemToArray(arr, j);
	}
	cJSON *p = cJSON_AddObjectToObject(rep, "intensity_parameters");
	cJSON_AddNumberToObject(p, "pixel_size_nm", ic->grid.pixel_nm);   /* the forward model, for report.html's error map */
	cJSON_AddNumberToObject(p, "fwhm_nm", ic->grid.fwhm_nm);
	cJSON_AddNumberToObject(p, "srf", ic->grid.srf);
	static const char *bg[] = { "none", "constant", "smooth" };
	cJSON_AddStringToObject(p, "background", bg[ic->background]);
	cJSON_AddNumberToObject(p, "beta", ic->beta);
	cJSON_AddNumberToObject(p, "nu", ic->nu);
	cJSON_AddNumberToObject(p, "fixed_mu", ic->mu);
	cJSON_AddStringToObject(p, "mu_rule", ic->mu > 0 ? "fixed" : ic->relative ? "relative discrepancy" : "plain discrepancy");
	cJSON_AddStringToObject(p, "mu_rule_meaning",
		ic->mu > 0 ? "mu as given"
		: ic->relative ? "mu is the largest smoothness whose residual exceeds the model's floor (the residual at mu = 1e-3) by no more than the noise explains (nu^2 H W sigma2 / T): smoothing that costs less than the noise is kept. The floor is the model error (continuous positions on the fine grid, background shape), larger than the noise on real data, which is why the plain principle is never met there. Larger nu smooths more; mu fixes it."
		: "mu makes the residual equal to the noise level nu^2 H W sigma2 / T; on data whose model error exceeds the noise this is never met and mu stays at its smallest value");
	cJSON_AddNumberToObject(p, "graph_radius_px", ic->graph_radius);
	cJSON_AddNumberToObject(p, "graph_orient", ic->graph_orient);
	if (mu_own)
		cJSON_AddStringToObject(p, "mu_shared", "the MA-TIRF stacks share one mu, the geometric mean of their own (mu_own), or the largest where the camera's fixed pattern is in the means (an offset map given, or the stacks' common pattern found): the depth reads the ratios between angles, so each angle is smoothed alike");
}

cJSON *c0_report_matirf(cJSON *rep, const char *key, const struct c0_angles *a, const struct c0_matirf_conf *m,
			const struct c0_matirf_result *res)
{
	const int nq = a->n;
	cJSON *j = cJSON_AddObjectToObject(rep, key);
	c0_report_add_array(j, "angles_deg", a->deg, nq);
	if (a->ngains)
		c0_report_add_array(j, "gains", a->gain, a->ngains);
	double pen[C0_MAX_STACKS];
	for (int q = 0; q < nq; q++)
		c0_tirf_p(&m->tirf, a->deg[q], &pen[q]), pen[q] = 1 / pen[q];
	c0_report_add_array(j, "penetration_depth_nm", pen, nq);
	cJSON_AddNumberToObject(j, "critical_angle_deg", c0_tirf_critical_deg(&m->tirf));
	cJSON_AddNumberToObject(j, "n_glass", m->tirf.n_glass);
	cJSON_AddNumberToObject(j, "n_sample", m->tirf.n_sample);
	cJSON_AddNumberToObject(j, "wavelength_nm", m->tirf.wavelength_nm);
	cJSON_AddNumberToObject(j, "s_fraction", m->tirf.s_fraction);
	c0_report_add_array(j, "z_nm", res->z_nm, res->nz);
	if (!cJSON_GetObjectItem(rep, "z_nm"))
		c0_report_add_array(rep, "z_nm", res->z_nm, res->nz);
	cJSON_AddStringToObject(j, "regulariser", m->reg == C0_REG_TV ? "tv" : "hessian");
	cJSON_AddNumberToObject(j, "kappa", m->kappa);
	cJSON_AddNumberToObject(j, "axial_weight", m->wz);
	cJSON_AddNumberToObject(j, "sparsity", m->sparsity);
	cJSON_AddNumberToObject(j, "data_scale", res->scale);
	cJSON_AddNumberToObject(j, "iterations", res->iters);
	cJSON_AddNumberToObject(j, "coarse_iterations", res->coarse_iters);   /* on the binned grids */
	cJSON_AddBoolToObject(j, "converged", res->converged);
	cJSON_AddStringToObject(j, "solver", res->apg ? "apg" : res->exact ? "exact" : "diag");
	cJSON_AddNumberToObject(j, "final_relative_change", res->rel_change);
	cJSON_AddNumberToObject(j, "objective", res->objective);
	cJSON_AddNumberToObject(j, "seconds", res->seconds);
	return j;
}

void c0_report_depth_readout(cJSON *j, int mean, double seconds)
{
	cJSON_AddStringToObject(j, "depth_readout", mean ? "intensity-weighted mean of each column" : "single-depth fit of each column's projections");
	cJSON_AddNumberToObject(j, "depth_readout_s", seconds);
}

void c0_report_pattern(cJSON *rep, const struct c0_pattern_stats *ps)
{
	if (ps->stacks < 2)
		return;   /* not evaluated */
	cJSON *o = cJSON_AddObjectToObject(rep, "common_pattern");
	cJSON_AddBoolToObject(o, "applied", ps->applied);
	cJSON_AddNumberToObject(o, "stacks", ps->stacks);
	cJSON_AddNumberToObject(o, "shared_variance_adu2", ps->common_var);
	cJSON_AddNumberToObject(o, "far_pixels", ps->far_pixels);
	cJSON_AddNumberToObject(o, "shrink_support", ps->k_on);
	cJSON_AddNumberToObject(o, "shrink_near", ps->k_near);
	cJSON_AddNumberToObject(o, "shrink_far", ps->k_far);
	if (ps->common_var_other > 0) {   /* a drift correction moved the frames */
		cJSON_AddStringToObject(o, "frame", ps->camera_frame ? "camera" : "sample");
		cJSON_AddNumberToObject(o, "shared_variance_other_frame_adu2", ps->common_var_other);
	}
}

void c0_report_matirf_raw(cJSON *j, const struct c0_matirf_raw *raw, const struct c0_matirf_result *res)
{
	cJSON_AddNumberToObject(j, "offset", raw->offset);
	if (res->background) {
		cJSON_AddStringToObject(j, "background", "estimated");
		cJSON_AddNumberToObject(j, "background_mean", res->background_mean);
		cJSON_AddNumberToObject(j, "background_smooth_px2", raw->background_smooth);
	} else
		cJSON_AddNumberToObject(j, "background", raw->background);
	cJSON_AddNumberToObject(j, "psf_fwhm_nm", raw->psf_fwhm_nm);
}

void c0_report_bleach(cJSON *rep, const struct c0_bleach_conf *bc, const struct c0_bleach_result *br, int n)
{
	static const char *modes[] = { "estimated", "given", "off", "estimated" };
	cJSON *o = cJSON_AddObjectToObject(rep, "bleaching");
	cJSON_AddStringToObject(o, "correction", modes[bc->mode]);
	cJSON_AddStringToObject(o, "acquisition", bc->interleaved ? "interleaved" : "sequential");
	double v[C0_MAX_STACKS];
	for (int i = 0; i < n; i++)
		v[i] = bc->norder ? bc->order[i] + 1 : i + 1;
	c0_report_add_array(o, "acquisition_order", v, n);
	if (bc->ngaps)
		c0_report_add_array(o, "gaps_frames", bc->gap_frames, bc->ngaps);
	if (bc->mode == C0_BLEACH_ESTIMATE) {
		cJSON_AddNumberToObject(o, "rate_per_frame", br->k);
		cJSON_AddNumberToObject(o, "rate_sd_per_frame", br->k_sd);
		cJSON_AddNumberToObject(o, "rate_fit_per_frame", br->k_fit);   /* before k >= 0 */
		cJSON_AddNumberToObject(o, "residual_autocorrelation", br->rho);
		for (int q = 0; q < n; q++)
			v[q] = br->k_stack[q] == br->k_stack[q] ? br->k_stack[q] : 0;
		c0_report_add_array(o, "rate_per_frame_by_stack", v, n);
		cJSON_AddBoolToObject(o, "first_stack_transient", br->first_left_out);
		if (br->first_left_out)
			cJSON_AddStringToObject(o, "first_stack_transient_meaning",
						"the first stack recorded faded faster in its first half than in its second (a start-up "
						"transient: the blinking not yet in its steady state); its rate is its second half's");
		c0_report_add_array(o, "start_frame", br->start, n);
		c0_report_add_array(o, "signal_per_frame", br->signal, n);
	}
	if (bc->mode == C0_BLEACH_REPEAT) {
		cJSON_AddStringToObject(o, "source", "repeat");
		cJSON_AddStringToObject(o, "source_meaning", "the rate from the last stack, a repeat of the first angle recorded at the end: "
					"its intensity total on the support over the first stack's, e^{-k dt}, dt between their midpoints");
		cJSON_AddNumberToObject(o, "repeat_ratio", bc->repeat_ratio);
		cJSON_AddNumberToObject(o, "rate_per_frame", br->k);
		cJSON_AddNumberToObject(o, "rate_fit_per_frame", br->k_fit);   /* before k >= 0 */
		c0_report_add_array(o, "start_frame", br->start, n);
	} else if (bc->mode == C0_BLEACH_ESTIMATE)
		cJSON_AddStringToObject(o, "source", "slope");
	c0_report_add_array(o, "factors", br->factor, n);
	cJSON_AddBoolToObject(o, "rate_significant", br->significant);
	const int first = bc->norder ? bc->order[0] : 0, last = bc->norder ? bc->order[n - 1] : n - 1;
	cJSON_AddNumberToObject(o, "fade_last_vs_first", 1 - br->factor[last] / br->factor[first]);
	cJSON_AddStringToObject(o, "meaning",
		bc->mode == C0_BLEACH_OFF ? "no correction: a fade across the stacks would read as depth"
		: "each stack's intensity was divided by its factor (its mean population relative to the start of the acquisition) before the MA-TIRF fit; intensity_qNN.tif are the stacks' own means");
}

static void psf_image(cJSON *p, const struct c0_run_conf *c, const struct c0_stage_confs *s)
{
	cJSON *o = cJSON_AddObjectToObject(p, "psf_image");
	cJSON_AddStringToObject(o, "file", c->psf_image);
	cJSON_AddNumberToObject(o, "pixel_size_nm", s->psf_pixel_nm > 0 ? s->psf_pixel_nm : s->support.grid.pixel_nm);
	cJSON_AddStringToObject(o, "pixel_size_from", s->psf_pixel_nm > 0 ? "its calibration" : "the stacks (the image has none)");
	cJSON_AddNumberToObject(o, "fwhm_px", s->psf.fwhm_px);
	cJSON_AddNumberToObject(o, "centre_x_px", s->psf.cx);
	cJSON_AddNumberToObject(o, "centre_y_px", s->psf.cy);
	cJSON_AddNumberToObject(o, "background", s->psf.background);
	cJSON_AddNumberToObject(o, "rms_residual_relative", s->psf.rel_rms);
	cJSON_AddStringToObject(o, "method", "least-squares fit of a pixel-integrated Gaussian plus a constant to the mean of its planes");
}

void c0_report_run_params(cJSON *rep, const struct c0_run_conf *c, const struct c0_stage_confs *s,
			  const struct c0_result *r, const int *only, int three_d)
{
	cJSON *p = cJSON_AddObjectToObject(rep, "parameters");
	cJSON_AddStringToObject(p, "mode", three_d ? "3D" : "2D");
	cJSON_AddNumberToObject(p, "pixel_size_nm", s->support.grid.pixel_nm);
	cJSON_AddNumberToObject(p, "fine_pixel_nm", c0_grid_fine_nm(&s->support.grid));
	cJSON_AddNumberToObject(p, "fwhm_nm", s->support.grid.fwhm_nm);
	cJSON_AddNumberToObject(p, "srf", s->support.grid.srf);
	if (three_d) {
		cJSON_AddNumberToObject(p, "depth_pool_nm", s->pool_nm);
		cJSON_AddNumberToObject(p, "depth_pool_range_nm", s->pool_range_nm);
	}
	double s1[C0_MAX_STACKS];
	const int ns = r->npool ? r->npool : r->nsup;
	for (int k = 0; k < ns; k++)
		s1[k] = (r->npool ? r->pool[k] : r->sup[k]) + 1;
	c0_report_add_array(p, "support_stacks", s1, ns);
	cJSON_AddBoolToObject(p, "support_pooled", r->npool > 0);
	int k = 0;
	for (int q = 0; q < r->n; q++)
		if (only[q])
			s1[k++] = q + 1;
	if (k) {
		c0_report_add_array(p, "support_only_stacks", s1, k);
		cJSON_AddStringToObject(p, "support_only_note",
					"stacks at or below the critical angle have no evanescent field: their supports join the union, and they are left out of the MA-TIRF fit");
	}
	if (s->psf_fitted)
		psf_image(p, c, s);
}

void c0_report_pool(cJSON *j, int window_px, double range_nm, double strip_px, int guide_window_px)
{
	cJSON_AddNumberToObject(j, "depth_pool_window_px", window_px);
	cJSON_AddNumberToObject(j, "depth_pool_range_nm", range_nm);
	cJSON_AddNumberToObject(j, "depth_pool_strip_px", strip_px);
	cJSON_AddNumberToObject(j, "depth_guide_window_px", guide_window_px);
}

void c0_report_depth_noise(cJSON *j, const struct c0_depth_noise *ns, int used, int block)
{
	cJSON *w = cJSON_AddObjectToObject(j, "depth_weights");
	cJSON_AddStringToObject(w, "rule", used ? "noise" : "equal");
	cJSON_AddStringToObject(w, "what", "noise: each pixel's depth fitted to its pooled intensities, each angle weighed by "
				"1 / (s_q m_q^2 + c_q + systematic), the random part from the intensity of the difference of "
				"two halves of the frames (blocks of block_frames frames), the systematic part from the fit's residuals "
				"beyond it; used where the residuals are at most max_ratio times the random part's "
				"expectation. equal: the volume's projections fitted with equal weights (docs/defaults.md#depth_noise_block)");
	cJSON_AddNumberToObject(w, "block_frames", block);
	cJSON_AddNumberToObject(w, "max_ratio", C0_DEPTH_NOISE_RATIO);
	if (!ns)
		return;
	cJSON_AddItemToObject(w, "relative_sd", cJSON_CreateDoubleArray(ns->rel_sd, ns->nq));
	cJSON *a = cJSON_AddArrayToObject(w, "absolute_share");
	for (int q = 0; q < ns->nq; q++)   /* JSON has no infinity: null where the relative part is 0 */
		cJSON_AddItemToArray(a, isfinite(ns->abs_share[q]) ? cJSON_CreateNumber(ns->abs_share[q]) : cJSON_CreateNull());
	cJSON_AddNumberToObject(w, "systematic_variance", ns->sys_var);
	cJSON_AddNumberToObject(w, "residuals_over_noise", ns->resid_ratio);
	cJSON_AddNumberToObject(w, "pixels", (double)ns->pixels);
}
