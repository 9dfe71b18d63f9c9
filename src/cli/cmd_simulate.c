/* col0rme simulate: MA-TIRF blinking stacks with ground truth. */
#include "cli/commands.h"
#include "cli/opts.h"
#include "cli/confopts.h"
#include "sim/sim.h"
#include "io/outdir.h"
#include "io/report.h"
#include "core/err.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void report(const struct c0_sim_conf *c, const struct c0_sim_result *r, cJSON *rep)
{
	cJSON *p = cJSON_AddObjectToObject(rep, "parameters");
	cJSON_AddNumberToObject(p, "seed", (double)c->seed);
	cJSON_AddNumberToObject(p, "width", c->width);
	cJSON_AddNumberToObject(p, "height", c->height);
	cJSON_AddNumberToObject(p, "frames", c->frames);
	cJSON_AddNumberToObject(p, "pixel_size_nm", c->pixel_nm);
	cJSON_AddNumberToObject(p, "fwhm_nm", c->fwhm_nm);
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
	}
	cJSON_AddNumberToObject(p, "z_min_nm", c->z_min_nm);
	cJSON_AddNumberToObject(p, "z_max_nm", c->z_max_nm);
	cJSON_AddNumberToObject(p, "tau_on_ms", c->tau_on_ms);
	cJSON_AddNumberToObject(p, "tau_off_ms", c->tau_off_ms);
	cJSON_AddNumberToObject(p, "tau_bleach_s", c->tau_bleach_s);
	cJSON_AddStringToObject(p, "tau_bleach_definition", "mean cumulative ON time before bleaching");
	static const char *orders[] = { "sequential", "interleaved", "restart" };
	cJSON_AddStringToObject(p, "bleach_order", orders[c->order]);
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
	cJSON_AddStringToObject(p, "snr_definition", "10 log10(var(noise-free ADU over pixels and frames) / read_noise^2), per angle");
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
	cJSON *t = cJSON_AddObjectToObject(rep, "timings_s");
	cJSON_AddNumberToObject(t, "simulate", r->seconds);
}

/* The simulator's parameter names (as in sim.json) that its messages cite,
 * and their flags here. */
static const struct c0_cli_name NAMES[] = {
	{ "width", "--width" }, { "height", "--height" }, { "frames", "--frames" }, { "angles", "--angles" },
	{ "bleach_order", "--bleach-order" }, { "gaps_s", "--gaps" }, { "pair_sep_nm", "--pair-sep" },
	{ "pair_dz_nm", "--pair-dz" }, { "tau_on_ms", "--tau-on" }, { "tau_off_ms", "--tau-off" }, { "fps", "--fps" },
	{ "tau_bleach_s", "--tau-bleach" }, { "brightness", "--brightness" }, { "brightness_cv", "--brightness-cv" },
	{ "background", "--background" }, { "gain", "--gain" }, { "read_noise", "--read-noise" }, { "offset", "--offset" },
	{ "z_min_nm", "--z-range min" }, { "z_max_nm", "--z-range max" }, { "filaments", "--filaments" },
	{ "density_per_um", "--density" }, { "persistence_nm", "--persistence" }, { "emitters_csv", "--emitters" },
	{ "drift_nm", "--drift-nm" }, { "hot_pixels", "--hot-pixels" }, { "srf", "--srf" }, { NULL, NULL },
};

static int fail(void)
{
	return c0_cli_error_names("simulate", NAMES);
}

int cmd_simulate(int argc, char **argv)
{
	struct c0_sim_conf c;
	c0_sim_defaults(&c);
	const char *outdir = NULL;
	int force = 0, verbose = 0, nangles = c.nangles, nz = 2, ndrift = 0;
	const char *order = "sequential";
	long long seed = (long long)c.seed;
	double zr[2] = { c.z_min_nm, c.z_max_nm }, hot[2] = { c.hot_fraction, c.hot_sd };
	int nhot = 0;
	const struct c0_opt opts[] = {
		{ "output", 'o', C0_OPT_STRING, &outdir, "DIR", "output directory (created; must be empty unless --force)", NULL, 0, NULL },
		{ "seed", 0, C0_OPT_LONG, &seed, "N", "random seed (same seed, same bytes)", NULL, 0, NULL },
		{ "width", 0, C0_OPT_INT, &c.width, "PX", "camera pixels across", NULL, 0, NULL },
		{ "height", 0, C0_OPT_INT, &c.height, "PX", "camera pixels down", NULL, 0, NULL },
		{ "frames", 0, C0_OPT_INT, &c.frames, "T", "frames per angle", NULL, 0, NULL },
		{ "pixel-size", 0, C0_OPT_DOUBLE, &c.pixel_nm, "NM", "camera pixel size in the sample", NULL, 0, NULL },
		{ "fwhm", 0, C0_OPT_DOUBLE, &c.fwhm_nm, "NM", "PSF full width at half maximum", NULL, 0, NULL },
		{ "srf", 0, C0_OPT_INT, &c.srf, "R", "ground-truth grid refinement factor", NULL, 0, NULL },
		{ "angles", 0, C0_OPT_DOUBLES, c.angles, "DEG,...", "incidence angles in the glass, one acquisition each",
		  "5 equally spaced in NA, critical+0.3 to 70", C0_MAX_ANGLES, &nangles },
		{ "n-glass", 0, C0_OPT_DOUBLE, &c.tirf.n_glass, "N", "refractive index of the coverslip", NULL, 0, NULL },
		{ "n-sample", 0, C0_OPT_DOUBLE, &c.tirf.n_sample, "N", "refractive index of the sample", NULL, 0, NULL },
		{ "wavelength", 0, C0_OPT_DOUBLE, &c.tirf.wavelength_nm, "NM", "excitation wavelength (vacuum)", NULL, 0, NULL },
		{ "s-fraction", 0, C0_OPT_DOUBLE, &c.tirf.s_fraction, "F", "s-polarised fraction of the excitation", NULL, 0, NULL },
		{ "filaments", 0, C0_OPT_INT, &c.filaments, "N", "worm-like-chain filaments crossing the field", NULL, 0, NULL },
		{ "persistence", 0, C0_OPT_DOUBLE, &c.persistence_nm, "NM", "filament persistence length", NULL, 0, NULL },
		{ "density", 0, C0_OPT_DOUBLE, &c.density_per_um, "N", "emitters per um of filament", NULL, 0, NULL },
		{ "z-range", 0, C0_OPT_DOUBLES, zr, "MIN,MAX", "depth range of the filaments (nm)", NULL, 2, &nz },
		{ "pairs", 0, C0_OPT_FLAG, &c.pairs, NULL, "add a parallel partner to each filament, --pair-sep away and --pair-dz deeper", NULL, 0, NULL },
		{ "pair-sep", 0, C0_OPT_DOUBLE, &c.pair_sep_nm, "NM", "lateral distance of a filament's partner", NULL, 0, NULL },
		{ "pair-dz", 0, C0_OPT_DOUBLE, &c.pair_dz_nm, "NM", "how much deeper the partner runs", NULL, 0, NULL },
		{ "emitters", 0, C0_OPT_STRING, &c.emitters_csv, "CSV", "emitters x_nm,y_nm,z_nm[,brightness] instead of filaments", NULL, 0, NULL },
		{ "tau-on", 0, C0_OPT_DOUBLE, &c.tau_on_ms, "MS", "mean on-state lifetime", NULL, 0, NULL },
		{ "tau-off", 0, C0_OPT_DOUBLE, &c.tau_off_ms, "MS", "mean off-state lifetime", NULL, 0, NULL },
		{ "tau-bleach", 0, C0_OPT_DOUBLE, &c.tau_bleach_s, "S", "mean cumulative ON time before an emitter bleaches (0: none)", NULL, 0, NULL },
		{ "bleach-order", 0, C0_OPT_STRING, &order, "sequential|interleaved|restart",
		  "angles acquired one after another on the same fluorophores, frame by frame in turn, or each on a fresh population", NULL, 0, NULL },
		{ "gaps", 0, C0_OPT_DOUBLES, c.gap_s, "S,...", "illuminated, unrecorded seconds between consecutive stacks (one value: all; sequential order)",
		  "none", C0_MAX_ANGLES, &c.ngaps },
		{ "fps", 0, C0_OPT_DOUBLE, &c.fps, "HZ", "frame rate (each frame integrates its whole period)", NULL, 0, NULL },
		{ "brightness", 0, C0_OPT_DOUBLE, &c.brightness, "PH", "photons per frame of an emitter fully on at z=0, angle 1", NULL, 0, NULL },
		{ "brightness-cv", 0, C0_OPT_DOUBLE, &c.brightness_cv, "F", "log-normal spread of brightness (coefficient of variation)", NULL, 0, NULL },
		{ "background", 0, C0_OPT_DOUBLE, &c.background, "PH", "background photons/pixel/frame at angle 1 (smooth pattern)", NULL, 0, NULL },
		{ "offset", 0, C0_OPT_DOUBLE, &c.offset, "ADU", "camera offset", NULL, 0, NULL },
		{ "gain", 0, C0_OPT_DOUBLE, &c.gain, "G", "ADU per photon", NULL, 0, NULL },
		{ "read-noise", 0, C0_OPT_DOUBLE, &c.read_noise, "ADU", "Gaussian read noise sd (used with --snr 0)", NULL, 0, NULL },
		{ "snr", 0, C0_OPT_DOUBLE, &c.snr_db, "DB", "set the read noise to reach this SNR (0: use --read-noise)", NULL, 0, NULL },
		{ "hot-pixels", 0, C0_OPT_DOUBLES, hot, "SHARE[,SD]", "a fixed share of pixels (sCMOS) with extra Gaussian read noise of sd SD ADU (30 unless given)", "0", 2, &nhot },
		{ "drift-nm", 0, C0_OPT_DOUBLES, c.drift_nm, "X,Y", "stage drift over the whole acquisition (all angles in order): displacement at the last frame", "0,0", 2, &ndrift },
		{ "drift-walk", 0, C0_OPT_FLAG, &c.drift_walk, NULL, "drift as a Gaussian random walk (per-axis step sd |X|/sqrt(frames), |Y|/...) instead of linear", NULL, 0, NULL },
		{ "force", 0, C0_OPT_FLAG, &force, NULL, "write into a non-empty output directory", NULL, 0, NULL },
		{ "verbose", 0, C0_OPT_FLAG, &verbose, NULL, "show progress even when not on a terminal", NULL, 0, NULL },
	};
	const struct c0_cmd_spec spec = { "simulate", "[options] -o OUTDIR",
		"Simulate one blinking TIRF stack per angle (uint16, calibrated) with ground truth:\n"
		"stack_qNN.tif, truth_intensity_qNN.tif (ADU/frame, fine grid), truth_background_qNN.tif,\n"
		"truth_depth.tif (nm), truth_support.tif (positions at the first frame), emitters.csv,\n"
		"drift_truth.csv (with --drift-nm) and sim.json.",
		opts, C0_NOPTS(opts), 0, 0, 1 };
	char **pos = malloc(sizeof(char *) * (size_t)argc);
	int np, rc = c0_opts_parse(&spec, argc, argv, &np, pos);
	free(pos);
	if (rc)
		return rc == 1 ? 0 : 2;
	c.seed = (uint64_t)seed;
	c.z_min_nm = zr[0];
	c.z_max_nm = nz > 1 ? zr[1] : zr[0];
	c.nangles = nangles;
	c.hot_fraction = hot[0], c.hot_sd = hot[1];
	if (ndrift == 1)
		return c0_fail(C0_EINVAL, "--drift-nm: expected X,Y in nm"), fail();
	static const char *orders[] = { "sequential", "interleaved", "restart" };
	c.order = -1;
	for (int k = 0; k < 3; k++)
		if (!strcmp(order, orders[k]))
			c.order = k;
	if (c.order < 0) {
		c0_fail(C0_EINVAL, "--bleach-order %s: expected sequential, interleaved or restart", order);
		return fail();
	}
	struct c0_outdir out;
	if (c0_sim_check(&c) || c0_outdir_open(&out, outdir, force))
		return fail();
	struct c0_sim_result res;
	cJSON *rep = c0_report_new("simulate", argc, argv);
	int st = c0_simulate(&c, &out, &res);
	if (!st) {
		report(&c, &res, rep);
		st = c0_report_write(rep, c0_outdir_file(&out, "sim.json"));
	}
	cJSON_Delete(rep);
	if ((st = c0_outdir_finish(&out, st))) {
		c0_sim_result_free(&res);
		return fail();
	}
	fprintf(stderr, "simulate: %d emitters, %d angles x %d frames of %dx%d in %.2fs -> %s\n", res.nemitters,
		c.nangles, c.frames, c.width, c.height, res.seconds, outdir);
	c0_sim_result_free(&res);
	return 0;
}
