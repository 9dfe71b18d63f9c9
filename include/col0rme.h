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
};

enum c0_penalty { C0_PENALTY_L1, C0_PENALTY_CEL0 };                /* "l1", "cel0" */
enum c0_support_solver { C0_SUPPORT_FISTA, C0_SUPPORT_PRUNED };    /* "fista", "pruned" */
enum c0_background { C0_BG_NONE, C0_BG_CONSTANT, C0_BG_SMOOTH };   /* "none", "constant", "smooth" */
enum c0_reg { C0_REG_TV, C0_REG_HESSIAN };                         /* "tv", "hessian" */
enum c0_matirf_solver { C0_MATIRF_EXACT, C0_MATIRF_DIAG, C0_MATIRF_AUTO, C0_MATIRF_APG }; /* "exact", "diag", "auto", "apg" */
enum c0_discrepancy { C0_DISCREPANCY_RELATIVE, C0_DISCREPANCY_PLAIN };  /* "relative", "plain" */
enum c0_bleaching { C0_BLEACHING_ESTIMATE, C0_BLEACHING_OFF };       /* "estimate", "off" */
enum c0_acquisition { C0_ACQ_SEQUENTIAL, C0_ACQ_INTERLEAVED };       /* "sequential", "interleaved" */

#define C0_MAX_STACKS 64

/* Every parameter of the method. Each field's name is its parameter name
 * (c0_run_conf_set, messages); the comment gives its default. */
struct c0_run_conf {
	/* optics and grid */
	double pixel_nm;       /* 0: camera pixel size in the sample; 0: the first stack's (c0_stack.pixel_nm, else its TIFF calibration) */
	double fwhm_nm;        /* 0: PSF full width at half maximum; 0: from psf_image, else 0.51 emission_nm / na */
	const char *psf_image; /* NULL: a measured PSF image (TIFF, planes averaged) whose fitted Gaussian FWHM is used */
	double emission_nm;    /* 0: emission wavelength (with na, when fwhm_nm is 0) */
	double na;             /* 0: numerical aperture of the objective (with emission_nm) */
	int srf;               /* 4: super-resolution factor, fine pixel = pixel_nm / srf */
	/* support (sparse covariance) */
	int support_stacks[C0_MAX_STACKS]; /* 1-based numbers of the stacks whose supports are joined */
	int nsupport_stacks;   /* 0: the stack with the smallest angle (the first in 2D mode) */
	enum c0_penalty penalty; /* l1 */
	double lambda;         /* 0: regularisation relative to lambda_max; 0: automatic, from the noise of the
			        * interleaved frame halves (max(2e-2 q90, 4 noise sds) for l1, q90 the correlation
			        * image's 90th percentile above the noise: docs/guide.md) */
	int lag;               /* 0: covariance lag radius in pixels; 0: ceil(6 sigma / pixel) */
	int iterations;        /* -1: maximum FISTA iterations (per reweighting for cel0); -1: the solver's,
				* 2000 for fista and cel0 (part of the estimator: docs/parameters.md), 10000
				* for pruned (a safety cap: it stops on converging) */
	enum c0_support_solver support_solver; /* fista: l1 by FISTA on a working set re-made every 100
				* iterations (the momentum kept), the whole grid's step; pruned: the same with
				* the set's own step (converges; see docs/parameters.md) */
	double tol;            /* -1: FISTA stops when the iterate's relative change is below this; -1: the
				* solver's, 0 for fista on l1 (every iteration up to the cap, part of the
				* estimator), 1e-5 for pruned and cel0 */
	int reweightings;      /* 10: CEL0 reweighting steps */
	int drift;             /* 1: estimate lateral drift from block means of all stacks (in order) and undo
			        * it before the covariance and the means ("on"); 0: "off" */
	int pixel_guard;       /* 1: clip each pixel's variance to what its neighbours' covariances allow
			        * (noisy sCMOS pixels, docs/parameters.md) ("on"); 0: "off" */
	int frc;               /* 1: solve each half of the frames too, for the FRC resolution and the
			        * localisation precision (render.tif) */
	int tile;              /* 0: support tile side in camera pixels (tiles overlap by two lags); 0: 256, or the image when smaller */
	/* intensity and background per stack */
	enum c0_background background; /* smooth */
	double beta;           /* 20: background smoothness weight (coarse grid) */
	double nu;             /* 1: discrepancy factor, residual^2 = nu^2 H W sigma2 / T; 0: sqrt(T) */
	double mu;             /* 0: smoothness weight by the discrepancy principle; > 0: fixed */
	enum c0_discrepancy discrepancy; /* relative: residual^2 = floor^2 + nu^2 H W sigma2 / T, floor = the residual at mu = 1e-3; plain: without the floor */
	double cg_tol;         /* 1e-3: CG relative residual */
	int cg_iterations;     /* 500: CG steps per active-set round */
	double graph_radius;   /* 2.25: smoothness couples support pixels up to this far apart (fine pixels, 1..4) */
	double noise_variance[C0_MAX_STACKS]; /* per-stack noise variance (camera units^2) */
	int nnoise_variance;   /* 0: estimated on the support */
	/* MA-TIRF axial reconstruction (3D mode when angles are given) */
	double angles[C0_MAX_STACKS]; /* incidence angle in the glass of each stack (deg), same order */
	int nangles;           /* 0: 2D COL0RME (support and intensities only) */
	double gains[C0_MAX_STACKS]; /* per-angle gain calibration (multiplies I0) */
	int ngains;            /* 0: 1 for every angle */
	double n_glass;        /* 1.518: refractive index of the coverslip and immersion */
	double n_sample;       /* 1.33: refractive index of the sample */
	double wavelength_nm;  /* 488: excitation wavelength in vacuum */
	double s_fraction;     /* 0.75: share of s-polarised excitation in I0 */
	double z_range_nm[3];  /* 0, 400, 20: depth bins min, max, step */
	enum c0_reg reg;       /* tv: regulariser, total variation or Hessian-Schatten */
	double kappa;          /* 3e-2: regularisation weight (images scaled to a maximum of 1) */
	double sparsity;       /* 3e-2: weight of the l1 term that keeps few depths per pixel */
	double axial_weight;   /* 0: axial weight of the regulariser relative to lateral */
	int matirf_iterations; /* 3000: maximum primal-dual iterations */
	double matirf_tol;     /* 0: primal-dual stopping tolerance; 0: the solver's, 1e-3 exact, 1e-4 diag, apg 5e-4 (TV) 1e-3 (Hessian) */
	enum c0_matirf_solver matirf_solver; /* (auto: apg) exact: per-pixel exact data steps; diag: diagonal steps; apg: exact's steps, the per-pixel prox by projected gradient */
	int matirf_coarse;     /* -1: levels of the warm start from 2x2-binned images (apg and exact with TV); -1: 2 with apg, else 0 */
	/* the standard MA-TIRF path on raw images (c0_run_matirf, `col0rme matirf`) */
	double offset;         /* 0: camera offset subtracted from every image */
	double matirf_background; /* 0: constant background subtracted after the offset */
	int estimate_background; /* 0: 1 estimates a smooth background common to all angles jointly with the volume */
	double background_smooth; /* 100: its smoothness weight, px^2 */
	double psf_fwhm_nm;    /* 0: joint deconvolution by a Gaussian PSF of this FWHM; 0: none */
	double depth_pool_nm;  /* -1: window over which intensities are summed for each pixel's depth; -1: 0.75 fwhm_nm, 0: off */
	double depth_pool_range_nm; /* -1: only pixels whose first depth guess is this close to the centre's are summed; -1: 50, 0: all */
	/* photobleaching across the stacks (3D mode) */
	enum c0_bleaching bleach; /* estimate: the fade from the stacks' frame sums, each intensity divided by its factor; off */
	double bleach_factors[C0_MAX_STACKS]; /* known factors (each stack's mean population relative to the start) */
	int nbleach_factors;   /* 0: estimated (or off) */
	enum c0_acquisition acquisition; /* sequential: stacks recorded one after another; interleaved: frame by frame in turn */
	int acquisition_order[C0_MAX_STACKS]; /* 1-based stack numbers in the order they were recorded */
	int nacquisition_order; /* 0: the order given */
	double gaps_frames[C0_MAX_STACKS]; /* illuminated, unrecorded frames between consecutive recorded stacks */
	int ngaps_frames;      /* 0: none; 1: the same everywhere; else one per pair */
	int baseline;          /* 0: 1 also reconstructs the standard MA-TIRF volume from the background-corrected means */
};

#define C0_RUN_CONF_DEFAULTS { .srf = 4, .penalty = C0_PENALTY_L1, .iterations = -1, .tol = -1, \
	.reweightings = 10, .drift = 1, .pixel_guard = 1, .frc = 1, .background = C0_BG_SMOOTH, .beta = 20, .nu = 1, .cg_tol = 1e-3, .cg_iterations = 500, \
	.graph_radius = 2.25, .n_glass = 1.518, .n_sample = 1.33, .wavelength_nm = 488, .s_fraction = 0.75, \
	.z_range_nm = { 0, 400, 20 }, .reg = C0_REG_TV, .kappa = 3e-2, .sparsity = 3e-2, \
	.matirf_iterations = 3000, .matirf_solver = C0_MATIRF_AUTO, .matirf_coarse = -1, .background_smooth = 100, .depth_pool_nm = -1, \
	.depth_pool_range_nm = -1 }

void c0_run_conf_init(struct c0_run_conf *c);
/* Sets one parameter from text: numbers ("1e-3"), comma lists ("62,64,66"),
 * names ("cel0"), flags ("1", "0"). Unknown name or bad value: C0_EINVAL and
 * a message naming the parameter. */
int c0_run_conf_set(struct c0_run_conf *c, const char *name, const char *value);
/* The parameters in order (i = 0, 1, ... until NULL): name, and its help
 * line with the default. */
const char *c0_run_conf_param(int i, const char **doc);
/* A conf on the heap with the defaults (NULL: out of memory), for callers
 * that cannot hold the struct itself (language bindings). */
struct c0_run_conf *c0_run_conf_new(void);
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
 * each stack, joined (support and report). */
int c0_run_support(const struct c0_run_conf *c, const struct c0_stack *stacks, int n, struct c0_result **out);
/* The MA-TIRF volume from n images of h x w (one per angle of c, row-major;
 * pixel size c->pixel_nm, for the outputs' calibration): volume, depth, z_nm. */
int c0_run_matirf(const struct c0_run_conf *c, const float *const *images, int n, int h, int w, struct c0_result **out);

/* Arrays owned by the result (NULL when absent or q out of range). */
int c0_result_nstacks(const struct c0_result *r);
const uint8_t *c0_result_support(const struct c0_result *r, int *h, int *w);          /* union of the masks, fine grid */
const float *c0_result_intensity(const struct c0_result *r, int q, int *h, int *w);   /* stack q (0-based), fine grid */
const float *c0_result_background(const struct c0_result *r, int q, int *h, int *w);  /* stack q, camera grid */
const float *c0_result_volume(const struct c0_result *r, int *nz, int *h, int *w);    /* NULL in 2D mode */
const float *c0_result_depth(const struct c0_result *r, int *h, int *w);              /* mean depth (nm), 0 where empty */
const float *c0_result_baseline_volume(const struct c0_result *r, int *nz, int *h, int *w); /* camera grid; with baseline */
const double *c0_result_z_nm(const struct c0_result *r, int *nz);                     /* depth bin centres */
/* stack q's intensity splatted with a Gaussian of the localisation precision, fine grid (render.tif) */
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
