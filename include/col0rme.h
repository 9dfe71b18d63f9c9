/* col0rme public API: 3D-COL0RME on multi-angle TIRF stacks in one call.
 * Plain structs in, plain arrays out, status codes; self-contained (C11).
 *
 *   struct c0_run_conf c;
 *   c0_run_conf_init(&c);                          documented defaults
 *   c0_run_conf_set(&c, "angles", "62,64,66");     or set the fields
 *   struct c0_stack s[3] = { { .path = "q1.tif" }, ... };  or .data = T x H x W floats
 *   struct c0_result *r;
 *   if (c0_run(&c, s, 3, &r)) fprintf(stderr, "%s\n", c0_last_error());
 *   const float *vol = c0_result_volume(r, &nz, &h, &w);
 *   c0_result_write(r, "out", 0);                   the files `col0rme run` writes
 *   c0_result_free(r);
 *
 * Images are row-major, x fastest: image[y*W + x], stack[t][y][x],
 * volume[z][y][x]. Lengths in nm. Errors leave one line in c0_last_error()
 * that names the parameter (as in c0_run_conf_set) or the file at fault. */
#ifndef COL0RME_H
#define COL0RME_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

enum c0_status {
	C0_OK = 0,
	C0_EINVAL,       /* bad parameter or argument */
	C0_EIO,          /* cannot open, read, write or rename a file */
	C0_EFORMAT,      /* a file is not what it claims or is damaged */
	C0_EUNSUPPORTED, /* a valid file we do not handle (RGB, complex, ...) */
	C0_ENOMEM,
	C0_ECANCELED,    /* the progress callback asked the run to stop; nothing was kept */
};

/* A run's progress (c0_run_conf_set_progress): called on the calling
 * thread with the stage now working ("drift", "support", "intensity",
 * "render", "bleaching", "matirf"; "matirf" alone in c0_run_matirf) and
 * its fraction done: 0 when it starts, 1 when it ends, and in between at
 * most ten times a second where the stage can tell (never decreasing
 * within a stage). Return 0 to go on; nonzero asks the run to stop: it
 * ends at its next stage with C0_ECANCELED and returns no result. */
typedef int (*c0_progress_fn)(const char *stage, double fraction, void *user);

enum c0_penalty { C0_PENALTY_L1, C0_PENALTY_CEL0 };                /* "l1", "cel0" */
enum c0_support_solver { C0_SUPPORT_FISTA, C0_SUPPORT_PRUNED };    /* "fista", "pruned" */
enum c0_lambda_rule { C0_LAMBDA_PEAKS, C0_LAMBDA_CV, C0_LAMBDA_NOISE };    /* "peaks", "cv", "noise" */
enum c0_fwhm_rule { C0_FWHM_STATED, C0_FWHM_DATA };     /* "stated", "data" */
enum c0_background { C0_BG_NONE, C0_BG_CONSTANT, C0_BG_SMOOTH };   /* "none", "constant", "smooth" */
enum c0_reg { C0_REG_TV, C0_REG_HESSIAN };                         /* "tv", "hessian" */
enum c0_matirf_solver { C0_MATIRF_EXACT, C0_MATIRF_DIAG, C0_MATIRF_AUTO, C0_MATIRF_APG }; /* "exact", "diag", "auto", "apg" */
enum c0_discrepancy { C0_DISCREPANCY_RELATIVE, C0_DISCREPANCY_PLAIN };  /* "relative", "plain" */
enum c0_bleaching { C0_BLEACHING_ESTIMATE, C0_BLEACHING_OFF, C0_BLEACHING_REPEAT }; /* "estimate", "off", "repeat" */
enum c0_acquisition { C0_ACQ_SEQUENTIAL, C0_ACQ_INTERLEAVED };       /* "sequential", "interleaved" */

#define C0_MAX_STACKS 64

/* Every parameter of the method. Each field's name is its parameter name
 * (c0_run_conf_set, messages, Python keywords). What each does, its default
 * and its command-line option are in one table, listed by
 * c0_run_conf_param() and in docs/params.md (`col0rme params`); the
 * defaults' values are C0_RUN_CONF_DEFAULTS. A list field x has its length
 * in nx. */
struct c0_run_conf {
	/* optics and grid */
	double pixel_nm;
	double fwhm_nm;
	const char *psf_image;
	double emission_nm;
	double na;
	int srf;
	/* support (sparse covariance) */
	int support_stacks[C0_MAX_STACKS];
	int nsupport_stacks;
	int support_pool;
	double label_radius_nm;
	enum c0_penalty penalty;
	double lambda;
	int lag;
	int iterations;
	enum c0_support_solver support_solver;
	double tol;
	int reweightings;
	int drift;
	int pixel_guard;
	int frc;
	int tile;
	/* intensity and background per stack */
	enum c0_background background;
	double beta;
	double nu;
	double mu;
	enum c0_discrepancy discrepancy;
	double cg_tol;
	int cg_iterations;
	double graph_radius;
	double noise_variance[C0_MAX_STACKS];
	int nnoise_variance;
	/* MA-TIRF axial reconstruction (3D mode when angles are given) */
	double angles[C0_MAX_STACKS];
	int nangles;
	double gains[C0_MAX_STACKS];
	int ngains;
	double n_glass;
	double n_sample;
	double wavelength_nm;
	double s_fraction;
	double z_range_nm[3];
	enum c0_reg reg;
	double kappa;
	double sparsity;
	double axial_weight;
	int matirf_iterations;
	double matirf_tol;
	enum c0_matirf_solver matirf_solver;
	int matirf_coarse;
	/* the standard MA-TIRF path on raw images (c0_run_matirf, `col0rme matirf`) */
	double offset;
	double matirf_background;
	int estimate_background;
	double background_smooth;
	double psf_fwhm_nm;
	double depth_pool_nm;
	double depth_pool_range_nm;
	/* photobleaching across the stacks (3D mode) */
	enum c0_bleaching bleach;
	double bleach_factors[C0_MAX_STACKS];
	int nbleach_factors;
	enum c0_acquisition acquisition;
	int acquisition_order[C0_MAX_STACKS];
	int nacquisition_order;
	double gaps_frames[C0_MAX_STACKS];
	int ngaps_frames;
	int baseline;
	/* the camera's calibration maps (sCMOS), TIFF files of the stacks' frame size */
	const char *offset_map;
	const char *variance_map;
	const char *gain_map;
	/* the automatic support lambda's rule (l1) */
	enum c0_lambda_rule lambda_rule;
	/* the PSF width the solves use: the stated one, or the covariance's where it differs by more than 5 % */
	enum c0_fwhm_rule fwhm_rule;
	/* without an offset map: the MA-TIRF stacks' common fixed pattern (an sCMOS camera's dark levels)
	 * estimated from their intensity fits and taken out of their means where it shows (1, the default) */
	int common_pattern;
	/* the intensity smoothness's direction: each graph edge weighs (1 - cos^2)^(graph_orient/2),
	 * cos between the edge and the support's normal at its ends (20; 0: every direction alike) */
	double graph_orient;
	/* the depth fit weighs the angles by the intensities' noise, measured on two halves of each
	 * stack's frames in blocks of this many frames (20, longer than a blink; 0: equal weights) */
	int depth_noise_block;
	/* not parameters: the run's progress callback and its argument (NULL: none); */
	c0_progress_fn progress;
	void *progress_user;
	/* which parameters c0_run_conf_set set (bit i: the i-th of c0_run_conf_param), so that a
	 * run can say which physical values it assumed (a field set directly counts as given
	 * when it differs from its default) */
	uint32_t given[4];
};

#define C0_RUN_CONF_DEFAULTS { .srf = 4, .support_pool = 1, .label_radius_nm = 15, .penalty = C0_PENALTY_L1, .iterations = -1, .tol = -1, \
	.reweightings = 10, .drift = 1, .pixel_guard = 1, .frc = 1, .background = C0_BG_SMOOTH, .beta = 100, .nu = 1, .cg_tol = 1e-3, .cg_iterations = 500, \
	.graph_radius = 6, .n_glass = 1.518, .n_sample = 1.33, .wavelength_nm = 488, .s_fraction = 0.75, \
	.z_range_nm = { 0, 400, 20 }, .reg = C0_REG_TV, .kappa = -1, .sparsity = 3e-2, \
	.matirf_iterations = 3000, .matirf_solver = C0_MATIRF_AUTO, .matirf_coarse = -1, .background_smooth = 100, .depth_pool_nm = -1, \
	.depth_pool_range_nm = -1, .fwhm_rule = C0_FWHM_DATA, .common_pattern = 1, .graph_orient = 20, \
	.depth_noise_block = 20, .lambda_rule = C0_LAMBDA_NOISE }

void c0_run_conf_init(struct c0_run_conf *c);
/* Sets one parameter from text: numbers ("1e-3"), comma lists ("62,64,66"),
 * names ("cel0"), flags ("1", "0"). Unknown name or bad value: C0_EINVAL and
 * a message naming the parameter. */
int c0_run_conf_set(struct c0_run_conf *c, const char *name, const char *value);
/* The parameters in order (i = 0, 1, ... until NULL): name, and its help
 * line with the default. */
const char *c0_run_conf_param(int i, const char **doc);
/* Parameter i's name (NULL past the last), the kind of its value ("number",
 * "integer", "flag" (0 or 1), "numbers", "integers" (comma lists),
 * "choice", "file"), its choices for a choice ("l1|cel0", else NULL), its
 * help line and its default as text: what a language binding needs for
 * its keywords and their documentation. */
const char *c0_run_conf_param_info(int i, const char **kind, const char **choices, const char **help, const char **def);
/* A conf on the heap with the defaults (NULL: out of memory), for callers
 * that cannot hold the struct itself (language bindings). */
struct c0_run_conf *c0_run_conf_new(void);
/* Sets c's progress callback and its argument (fn NULL: none). */
void c0_run_conf_set_progress(struct c0_run_conf *c, c0_progress_fn fn, void *user);
void c0_run_conf_free(struct c0_run_conf *c);

/* One stack: a TIFF file (path) or float32 frames in memory (data, frames x
 * height x width, row-major, owned by the caller). pixel_nm 0: the file's
 * calibration, else the conf's. */
struct c0_stack {
	const char *path;
	const float *data;
	int frames, height, width;
	double pixel_nm;
};

struct c0_result;

/* The whole method: support, intensity and background of each stack, and
 * with angles the MA-TIRF volume (and the baseline when asked). */
int c0_run(const struct c0_run_conf *c, const struct c0_stack *stacks, int n, struct c0_result **out);
/* Writes the files `col0rme run` writes into outdir (created; must be empty
 * unless force; never the directory of an input). On failure nothing is left. */
int c0_result_write(const struct c0_result *r, const char *outdir, int force);
/* OUTDIR/report.html (and error_qNN.tif) from an output directory's files
 * alone: report.json and the TIFFs a run wrote (c0_result_write calls it
 * last). On failure nothing is written. */
int c0_report_html(const char *outdir);
/* One step alone, as `col0rme support` and `col0rme matirf` do. The support of
 * the stacks: their covariances pooled (support_pool, the default), or each
 * stack's, joined (support and report). */
int c0_run_support(const struct c0_run_conf *c, const struct c0_stack *stacks, int n, struct c0_result **out);
/* The MA-TIRF volume from n images of h x w (one per angle of c, row-major;
 * pixel size c->pixel_nm, for the outputs' calibration): volume, depth, z_nm. */
int c0_run_matirf(const struct c0_run_conf *c, const float *const *images, int n, int h, int w, struct c0_result **out);

/* Arrays owned by the result (NULL when absent or q out of range). */
int c0_result_nstacks(const struct c0_result *r);
const uint8_t *c0_result_support(const struct c0_result *r, int *h, int *w);          /* union of the masks, fine grid */
const float *c0_result_intensity(const struct c0_result *r, int q, int *h, int *w);   /* stack q (0-based), fine grid; made on the first call (NULL when out of memory) */
const float *c0_result_background(const struct c0_result *r, int q, int *h, int *w);  /* stack q, camera grid */
const float *c0_result_volume(const struct c0_result *r, int *nz, int *h, int *w);    /* NULL in 2D mode; made on the first call (NULL when out of memory) */
const float *c0_result_depth(const struct c0_result *r, int *h, int *w);              /* depth (nm), 0 where empty */
const float *c0_result_baseline_volume(const struct c0_result *r, int *nz, int *h, int *w); /* camera grid; with baseline */
const double *c0_result_z_nm(const struct c0_result *r, int *nz);                     /* depth bin centres */
/* stack q's intensity splatted with a Gaussian of the localisation precision, fine grid (render.tif);
 * every stack's made on the first call (NULL when out of memory) */
const float *c0_result_render(const struct c0_result *r, int q, int *h, int *w);
const char *c0_result_report_json(const struct c0_result *r); /* report.json: every parameter, estimate, timing */
void c0_result_free(struct c0_result *r);

/* This thread's last error line. */
const char *c0_last_error(void);
/* "MAJOR.MINOR.PATCH" */
const char *c0_version(void);

/* The simulator of `col0rme simulate` in memory: blinking emitters on
 * filaments, one acquisition per angle, camera noise. Parameters by name
 * (sim.json's "parameters": "seed", "width", "height", "frames", "pixel_nm",
 * "fwhm_nm", "angles" (comma list, deg) or "nangles" (a default set),
 * "snr_db", "background", ...); the stacks are the values the CLI writes. */
struct c0_simulation;
int c0_simulation_new(struct c0_simulation **out);
int c0_simulation_set(struct c0_simulation *s, const char *name, const char *value);
double c0_simulation_get(const struct c0_simulation *s, const char *name);   /* NAN: no such parameter */
int c0_simulation_run(struct c0_simulation *s);
const float *c0_simulation_stack(const struct c0_simulation *s, int q, int *frames, int *h, int *w);  /* ADU, after run */
const double *c0_simulation_angles(const struct c0_simulation *s, int *n);
const double *c0_simulation_emitters(const struct c0_simulation *s, int *n);  /* n x (x, y, z nm, brightness) */
void c0_simulation_free(struct c0_simulation *s);

#ifdef __cplusplus
}
#endif
#endif
