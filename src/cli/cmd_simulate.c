/* col0rme simulate: MA-TIRF blinking stacks with ground truth. */
#include "cli/commands.h"
#include "cli/opts.h"
#include "cli/confopts.h"
#include "cli/cmdkit.h"
#include "app/sim_report.h"
#include "io/outdir.h"
#include "core/err.h"
#include "core/progress.h"

#include <stdio.h>
#include <stdlib.h>

/* The simulator's parameter names (as in sim.json) that its messages cite,
 * and their flags here. */
static const struct c0_cli_name NAMES[] = {
	{ "width", "--width" }, { "height", "--height" }, { "frames", "--frames" }, { "angles", "--angles" },
	{ "bleach_order", "--bleach-order" }, { "gaps_s", "--gaps" }, { "pair_sep_nm", "--pair-sep" },
	{ "pair_dz_nm", "--pair-dz" }, { "label_radius_nm", "--label-radius" }, { "tau_on_ms", "--tau-on" }, { "tau_off_ms", "--tau-off" }, { "fps", "--fps" },
	{ "tau_bleach_s", "--tau-bleach" }, { "brightness", "--brightness" }, { "brightness_cv", "--brightness-cv" },
	{ "background", "--background" }, { "gain", "--gain" }, { "read_noise", "--read-noise" }, { "offset", "--offset" },
	{ "z_min_nm", "--z-range min" }, { "z_max_nm", "--z-range max" }, { "filaments", "--filaments" },
	{ "density_per_um", "--density" }, { "persistence_nm", "--persistence" }, { "emitters_csv", "--emitters" },
	{ "drift_nm", "--drift-nm" }, { "hot_pixels", "--hot-pixels" }, { "srf", "--srf" },
	{ "camera", "--camera" }, { "em_gain", "--em-gain" }, { "offset_sd", "--offset-sd" }, { "gain_cv", "--gain-cv" },
	{ "read_e", "--read-e" }, { "read_spread", "--read-spread" }, { "dark_frames", "--dark-frames" }, { "psf", "--psf" },
	{ NULL, NULL },
};

static int fail(void)
{
	return c0_cli_error_names("simulate", NAMES);
}

/* The options into c: -1 to go on, else the command's exit code. */
static int parse(int argc, char **argv, struct c0_sim_conf *conf, const char **outdir, int *force, int *progress_json)
{
	struct c0_sim_conf c = *conf;
	int verbose = 0, nangles = c.nangles, nz = 2, ndrift = 0;
	const char *order = "sequential", *camera = "ccd", *psf = "gauss";
	long long seed = (long long)c.seed;
	double zr[2] = { c.z_min_nm, c.z_max_nm }, hot[2] = { c.hot_fraction, c.hot_sd };
	int nhot = 0;
	const struct c0_opt opts[] = {
		{ "output", 'o', C0_OPT_STRING, outdir, "DIR", "output directory (created; must be empty unless --force)", NULL, 0, NULL },
		{ "seed", 0, C0_OPT_LONG, &seed, "N", "random seed (same seed, same bytes)", NULL, 0, NULL },
		{ "width", 0, C0_OPT_INT, &c.width, "PX", "camera pixels across", NULL, 0, NULL },
		{ "height", 0, C0_OPT_INT, &c.height, "PX", "camera pixels down", NULL, 0, NULL },
		{ "frames", 0, C0_OPT_INT, &c.frames, "T", "frames per angle", NULL, 0, NULL },
		{ "pixel-size", 0, C0_OPT_DOUBLE, &c.pixel_nm, "NM", "camera pixel size in the sample", NULL, 0, NULL },
		{ "fwhm", 0, C0_OPT_DOUBLE, &c.fwhm_nm, "NM", "PSF full width at half maximum", NULL, 0, NULL },
		{ "psf", 0, C0_OPT_STRING, &psf, "gauss|airy",
		  "PSF the frames are rendered with: gauss (the model col0rme assumes) or airy (the in-focus Bessel disk "
		  "(2 J1(v)/v)^2 of the same --fwhm: its rings and heavy tail, as real PSFs have; not with --drift-nm)", NULL, 0, NULL },
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
		{ "label-radius", 0, C0_OPT_DOUBLE, &c.label_radius_nm, "NM",
		  "emitters on a tube of this radius around each filament's axis (a labelled microtubule: 12.5 nm plus the label's reach; 0: on the axis)",
		  NULL, 0, NULL },
		{ "emitters", 0, C0_OPT_STRING, &c.emitters_csv, "CSV", "emitters x_nm,y_nm,z_nm[,brightness] instead of filaments", NULL, 0, NULL },
		{ "tau-on", 0, C0_OPT_DOUBLE, &c.tau_on_ms, "MS", "mean on-state lifetime", NULL, 0, NULL },
		{ "tau-off", 0, C0_OPT_DOUBLE, &c.tau_off_ms, "MS", "mean off-state lifetime", NULL, 0, NULL },
		{ "tau-bleach", 0, C0_OPT_DOUBLE, &c.tau_bleach_s, "S", "mean cumulative ON time before an emitter bleaches (0: none)", NULL, 0, NULL },
		{ "bleach-order", 0, C0_OPT_STRING, &order, "sequential|interleaved|restart",
		  "angles acquired one after another on the same fluorophores, frame by frame in turn, or each on a fresh population", NULL, 0, NULL },
		{ "gaps", 0, C0_OPT_DOUBLES, c.gap_s, "S,...", "illuminated, unrecorded seconds between consecutive stacks (one value: all; sequential order)",
		  "none", C0_MAX_ANGLES, &c.ngaps },
		{ "repeat-first", 0, C0_OPT_FLAG, &c.repeat_first, NULL,
		  "record one more stack at the end at the first angle (same population, the fade continues): for run --bleach repeat", NULL, 0, NULL },
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
		{ "camera", 0, C0_OPT_STRING, &camera, "ccd|emccd|scmos",
		  "ccd: one gain, offset and Gaussian read noise; emccd: electron multiplication (Gamma, excess noise sqrt 2); "
		  "scmos: per-pixel offset, gain and read noise (log-normal), 1 % noisy pixels unless --hot-pixels, and the truth "
		  "calibration calib_offset/variance/gain.tif with dark frames dark.tif", NULL, 0, NULL },
		{ "em-gain", 0, C0_OPT_DOUBLE, &c.em_gain, "G", "emccd: EM gain (the read noise from --snr or --read-noise is divided by it)", NULL, 0, NULL },
		{ "offset-sd", 0, C0_OPT_DOUBLE, &c.offset_sd, "ADU", "scmos: spread (sd) of the per-pixel offset around --offset", NULL, 0, NULL },
		{ "gain-cv", 0, C0_OPT_DOUBLE, &c.gain_cv, "F", "scmos: spread (coefficient of variation) of the per-pixel gain around --gain", NULL, 0, NULL },
		{ "read-e", 0, C0_OPT_DOUBLE, &c.read_e, "E", "scmos: median per-pixel read-noise sd in electrons (photons)", NULL, 0, NULL },
		{ "read-spread", 0, C0_OPT_DOUBLE, &c.read_spread, "S", "scmos: log-normal sigma of the per-pixel read-noise sd (its long tail)", NULL, 0, NULL },
		{ "dark-frames", 0, C0_OPT_INT, &c.dark_frames, "N", "scmos: frames of dark.tif (0: none)", NULL, 0, NULL },
		{ "force", 0, C0_OPT_FLAG, force, NULL, "write into a non-empty output directory", NULL, 0, NULL },
		{ "verbose", 0, C0_OPT_FLAG, &verbose, NULL, "show progress even when not on a terminal", NULL, 0, NULL },
		{ "progress-json", 0, C0_OPT_FLAG, progress_json, NULL, C0_PROGRESS_JSON_HELP, NULL, 0, NULL },
	};
	const struct c0_cmd_spec spec = { "simulate", "[options] -o OUTDIR",
		"Simulate one blinking TIRF stack per angle (uint16, calibrated) with ground truth:\n"
		"stack_qNN.tif, truth_intensity_qNN.tif (ADU/frame, fine grid), truth_background_qNN.tif,\n"
		"truth_depth.tif (nm), truth_support.tif (positions at the first frame), emitters.csv,\n"
		"drift_truth.csv (with --drift-nm) and sim.json; with --camera scmos also calib_offset.tif,\n"
		"calib_variance.tif, calib_gain.tif (the camera's truth calibration) and dark.tif.",
		opts, C0_NOPTS(opts), 0, 0, 1 };
	char **pos = malloc(sizeof(char *) * (size_t)argc);
	int np, rc = c0_opts_parse(&spec, argc, argv, &np, pos);
	free(pos);
	if (rc)
		return rc == 1 ? 0 : 2;
	c.seed = (uint64_t)seed;
	c.z_min_nm = zr[0], c.z_max_nm = nz > 1 ? zr[1] : zr[0];
	c.nangles = nangles;
	if (c0_sim_add_repeat(&c))
		return fail();
	c.hot_fraction = hot[0], c.hot_sd = hot[1];
	if (c0_sim_camera_parse(camera, &c.camera) || c0_sim_psf_parse(psf, &c.psf))
		return fail();
	if (c.camera == C0_CAM_SCMOS && !nhot)   /* an sCMOS has its noisy pixels */
		c.hot_fraction = 0.01;
	if (ndrift == 1)
		return c0_fail(C0_EINVAL, "--drift-nm: expected X,Y in nm"), fail();
	if (c0_sim_order_parse(order, &c.order))
		return fail();
	*conf = c;
	return -1;
}

int cmd_simulate(int argc, char **argv)
{
	struct c0_sim_conf c;
	c0_sim_defaults(&c);
	const char *outdir = NULL;
	int force = 0, json = 0, rc = parse(argc, argv, &c, &outdir, &force, &json);
	if (rc >= 0)
		return rc;
	struct c0_outdir out;
	struct c0_sim_result res;
	if (c0_sim_check(&c) || c0_outdir_open(&out, outdir, force))
		return fail();
	c0_cli_guard(&out);
	/* --progress-json: the simulator's progress through the run's callback, one stage */
	struct c0_progress_sink sink;
	double t0 = 0;
	c0_progress_attach(&sink, json ? c0_cli_progress_json : NULL, &t0);
	c0_progress_stage("simulate");
	int st = c0_progress_detach(&sink, c0_sim_write(&c, &out, argc, argv, &res));
	st = c0_outdir_finish(&out, st);
	c0_cli_unguard();
	if (st) {
		c0_sim_result_free(&res);
		return fail();
	}
	fprintf(stderr, "simulate: %d emitters, %d angles x %d frames of %dx%d in %.2fs -> %s\n", res.nemitters,
		c.nangles, c.frames, c.width, c.height, res.seconds, outdir);
	c0_sim_result_free(&res);
	return 0;
}
