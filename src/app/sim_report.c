/* sim.json: the simulator's parameters and estimates, and the run that
 * writes it beside the stacks */
#include "app/sim_report.h"
#include "io/outdir.h"

/* the camera when it is not the plain ccd */
static void report_camera(const struct c0_sim_conf *c, cJSON *p)
{
	cJSON_AddStringToObject(p, "camera", c0_sim_camera_name(c->camera));
	if (c->camera == C0_CAM_EMCCD) {
		cJSON_AddNumberToObject(p, "em_gain", c->em_gain);
		cJSON_AddStringToObject(p, "camera_model", "ADU = gain Gamma(Poisson(photons), 1) + offset + Normal(0, (read_noise / em_gain)^2): "
					"excess noise factor sqrt 2, gain ADU per photon");
		return;
	}
	cJSON_AddNumberToObject(p, "offset_sd_adu", c->offset_sd);
	cJSON_AddNumberToObject(p, "gain_cv", c->gain_cv);
	cJSON_AddNumberToObject(p, "read_noise_median_e", c->read_e);
	cJSON_AddNumberToObject(p, "read_noise_lognormal_sigma", c->read_spread);
	cJSON_AddNumberToObject(p, "dark_frames", c->dark_frames);
	cJSON_AddStringToObject(p, "camera_model", "per pixel i: ADU = gain_i Poisson(photons) + offset_i + Normal(0, sd_i^2) (+ Normal(0, hot_sd^2) "
				"on the noisy pixels); gain_i = gain (1 + gain_cv N), offset_i = offset + offset_sd N, sd_i = gain_i read_e "
				"exp(read_noise_lognormal_sigma N); truth in calib_offset.tif (ADU), calib_variance.tif (sd_i^2 + hot + 1/12, "
				"ADU^2), calib_gain.tif (ADU/photon); dark.tif: dark frames of the same camera; snr_db_target not used");
}

/* "parameters": the configuration as simulated */
static void report_parameters(const struct c0_sim_conf *c, cJSON *rep)
{
	cJSON *p = cJSON_AddObjectToObject(rep, "parameters");
	cJSON_AddNumberToObject(p, "seed", (double)c->seed);
	cJSON_AddNumberToObject(p, "width", c->width);
	cJSON_AddNumberToObject(p, "height", c->height);
	cJSON_AddNumberToObject(p, "frames", c->frames);
	cJSON_AddNumberToObject(p, "pixel_size_nm", c->pixel_nm);
	cJSON_AddNumberToObject(p, "fwhm_nm", c->fwhm_nm);
	if (c->psf != C0_SIM_PSF_GAUSS)   /* the Gaussian's sim.json as it always was */
		cJSON_AddStringToObject(p, "psf", c0_sim_psf_name(c->psf));
	cJSON_AddNumberToObject(p, "srf", c->srf);
	c0_report_add_array(p, "angles_deg", c->angles, c->nangles);
	cJSON_AddNumberToObject(p, "n_glass", c->tirf.n_glass);
	cJSON_AddNumberToObject(p, "n_sample", c->tirf.n_sample);
	cJSON_AddNumberToObject(p, "wavelength_nm", c->tirf.wavelength_nm);
	cJSON_AddNumberToObject(p, "s_polarisation_fraction", c->tirf.s_fraction);
	if (c->emitters_csv)
		cJSON_AddStringToObject(p, "emitters_csv", c->emitters_csv);
	else {
		cJSON_AddNumberToObject(p, "filaments", c->filaments);
		cJSON_AddNumberToObject(p, "persistence_nm", c->persistence_nm);
		cJSON_AddNumberToObject(p, "density_per_um", c->density_per_um);
		cJSON_AddBoolToObject(p, "pairs", c->pairs);
		if (c->pairs) {
			cJSON_AddNumberToObject(p, "pair_sep_nm", c->pair_sep_nm);
			cJSON_AddNumberToObject(p, "pair_dz_nm", c->pair_dz_nm);
		}
		cJSON_AddNumberToObject(p, "label_radius_nm", c->label_radius_nm);
	}
	cJSON_AddNumberToObject(p, "z_min_nm", c->z_min_nm);
	cJSON_AddNumberToObject(p, "z_max_nm", c->z_max_nm);
	cJSON_AddNumberToObject(p, "tau_on_ms", c->tau_on_ms);
	cJSON_AddNumberToObject(p, "tau_off_ms", c->tau_off_ms);
	cJSON_AddNumberToObject(p, "tau_bleach_s", c->tau_bleach_s);
	cJSON_AddStringToObject(p, "tau_bleach_definition", "mean cumulative ON time before bleaching");
	cJSON_AddStringToObject(p, "bleach_order", c0_sim_order_name(c->order));
	cJSON_AddBoolToObject(p, "repeat_first", c->repeat_first);
	if (c->ngaps)
		c0_report_add_array(p, "gaps_s", c->gap_s, c->ngaps);
	cJSON_AddNumberToObject(p, "fps", c->fps);
	c0_report_add_array(p, "drift_nm", c->drift_nm, 2);
	cJSON_AddStringToObject(p, "drift", c->drift_walk ? "random walk" : "linear");
	cJSON_AddNumberToObject(p, "brightness_photons", c->brightness);
	cJSON_AddNumberToObject(p, "brightness_cv", c->brightness_cv);
	cJSON_AddNumberToObject(p, "background_photons", c->background);
	cJSON_AddNumberToObject(p, "offset_adu", c->offset);
	cJSON_AddNumberToObject(p, "gain_adu_per_photon", c->gain);
	cJSON_AddNumberToObject(p, "snr_db_target", c->snr_db);
	cJSON_AddNumberToObject(p, "hot_pixel_fraction", c->hot_fraction);
	cJSON_AddNumberToObject(p, "hot_pixel_sd_adu", c->hot_sd);
	if (c->camera != C0_CAM_CCD)   /* the ccd's sim.json as it always was */
		report_camera(c, p);
	cJSON_AddStringToObject(p, "snr_definition", "10 log10(var(noise-free ADU over pixels and frames) / read_noise^2), per angle");
}

/* "estimates": what the simulation's angles and bleaching came to */
static void report_estimates(const struct c0_sim_conf *c, const struct c0_sim_result *r, cJSON *rep)
{
	cJSON *e = cJSON_AddObjectToObject(rep, "estimates");
	cJSON_AddNumberToObject(e, "emitters", r->nemitters);
	cJSON *angles = cJSON_AddArrayToObject(e, "angles");
	for (int q = 0; q < c->nangles; q++) {
		const struct c0_sim_angle *a = &r->angle[q];
		cJSON *o = cJSON_CreateObject();
		cJSON_AddNumberToObject(o, "angle_deg", c->angles[q]);
		if (a->p_per_nm > 0)
			cJSON_AddNumberToObject(o, "penetration_depth_nm", a->depth_nm);
		else
			cJSON_AddStringToObject(o, "excitation", "epi (below the critical angle: no evanescent decay)");
		cJSON_AddNumberToObject(o, "i0_relative", a->i0_rel);
		cJSON_AddNumberToObject(o, "read_noise_adu", a->read_noise);
		cJSON_AddNumberToObject(o, "snr_db", a->snr_db);
		cJSON_AddNumberToObject(o, "start_s", a->t_start_s);
		cJSON_AddNumberToObject(o, "bleach_factor", a->bleach_factor);
		cJSON_AddItemToArray(angles, o);
	}
	/* the truth for run's bleaching estimate: rate per second and per frame,
	 * and each stack's mean population relative to the unbleached one */
	cJSON *b = cJSON_AddObjectToObject(e, "bleaching");
	cJSON_AddNumberToObject(b, "rate_per_s", r->bleach_rate);
	cJSON_AddNumberToObject(b, "rate_per_frame", r->bleach_rate / c->fps);
	double f[C0_MAX_ANGLES];
	for (int q = 0; q < c->nangles; q++)
		f[q] = r->angle[q].bleach_factor;
	c0_report_add_array(b, "stack_factors", f, c->nangles);
	cJSON_AddNumberToObject(b, "fade_last_vs_first", c->nangles > 1 ? 1 - f[c->nangles - 1] / f[0] : 0);
}

void c0_sim_report(const struct c0_sim_conf *c, const struct c0_sim_result *r, cJSON *rep)
{
	report_parameters(c, rep);
	report_estimates(c, r, rep);
	cJSON *t = cJSON_AddObjectToObject(rep, "timings_s");
	cJSON_AddNumberToObject(t, "simulate", r->seconds);
}

int c0_sim_write(const struct c0_sim_conf *c, struct c0_outdir *out, int argc, char **argv, struct c0_sim_result *res)
{
	cJSON *rep = c0_report_new("simulate", argc, argv);
	int st = c0_simulate(c, out, res);
	if (!st) {
		c0_sim_report(c, res, rep);
		st = c0_report_write(rep, c0_outdir_file(out, "sim.json"));
	}
	cJSON_Delete(rep);
	return st;
}
