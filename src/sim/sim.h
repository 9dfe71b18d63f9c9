/* Simulated MA-TIRF acquisitions of blinking emitters, with ground truth.
 *
 * Model, per angle q (a separate acquisition with its own blinking):
 *   photons(pixel, t) = sum_e B_e * E_q(z_e) * on_e,q(t) * PSF_e(pixel) + bg_q(pixel)
 *   E_q(z) = I0(alpha_q)/I0(alpha_1) * exp(-p(alpha_q) z)       (tirf.h physics)
 *   ADU = gain * Poisson(photons) + offset + Normal(0, read_noise^2), rounded to uint16
 * plus, on a fixed random share hot_fraction of the pixels (sCMOS pixels with
 * random-telegraph or high read noise), Normal(0, hot_sd^2) more.
 * on_e,q(t) is the fraction of frame t the emitter spends on (two-state
 * telegraph process integrated within the frame) and zero once bleached.
 * Bleaching follows the cumulative ON time. The angles are acquired one
 * after another on the same fluorophores (order "sequential", optional
 * illuminated gaps between stacks), frame by frame in turn ("interleaved"),
 * or each on a fresh population ("restart", no fade across angles): in the
 * first two, each emitter runs one process over the whole acquisition, so
 * later stacks see a faded population. An angle below the critical one is an
 * epifluorescence stack (E_q(z) = 1, no evanescent decay).
 *
 * SNR (the paper's 14.75 dB, as in the COL0RME reference code):
 *   SNR_dB = 10 log10( var(noise-free ADU over all pixels and frames) / read_noise^2 )
 * per angle; with snr_db > 0 the read noise is set from it. */
#pragma once
#include "optics/tirf.h"

#include <stddef.h>
#include <stdint.h>

#define C0_MAX_ANGLES 32

enum c0_sim_order { C0_ORDER_SEQUENTIAL, C0_ORDER_INTERLEAVED, C0_ORDER_RESTART };

struct c0_emitter {
	double x, y, z;          /* nm; x, y from the image's top-left corner */
	double brightness;       /* photons per frame when fully on at z = 0 under angle 1 */
};

struct c0_sim_conf {
	uint64_t seed;             /* 1 */
	int width, height;         /* 64 x 64 camera pixels */
	int frames;                /* 500 per angle */
	double pixel_nm;           /* 100 */
	double fwhm_nm;            /* 229 */
	int srf;                   /* 4: truth grid factor */
	int nangles;               /* 5 */
	double angles[C0_MAX_ANGLES]; /* deg; default: 5 equally spaced in n_g sin(alpha) from alpha_c + 0.3 to 70 deg */
	struct c0_tirf tirf;       /* 1.518 / 1.33 / 488 nm / 0.75 s */
	/* structure */
	int filaments;             /* 5 worm-like chains crossing the field */
	double persistence_nm;     /* 4000 */
	double density_per_um;     /* 250 emitters per um of filament (a labelled microtubule's fluorophores
				    * hold every fine pixel of the tube: docs/defaults.md#label_radius_nm) */
	double z_min_nm, z_max_nm; /* 0, 400: depth varies smoothly inside */
	int pairs;                 /* 0; 1 adds a parallel partner pair_sep_nm away, pair_dz_nm deeper */
	double pair_sep_nm;        /* 120: lateral distance of the partner */
	double pair_dz_nm;         /* 100: how much deeper the partner runs */
	double label_radius_nm;    /* 15: on a tube of this radius around the filament's axis (a labelled
				    * microtubule: 12.5 nm plus the label's reach); 0: on the axis */
	const char *emitters_csv;  /* x_nm,y_nm,z_nm[,brightness] instead of filaments */
	/* photophysics */
	double tau_on_ms, tau_off_ms;  /* 20, 40 */
	double tau_bleach_s;       /* 35: mean cumulative ON time before bleaching (s); 0: none */
	int order;                 /* enum c0_sim_order: sequential */
	double gap_s[C0_MAX_ANGLES]; /* illuminated, unrecorded seconds before stack q+1 (sequential order) */
	int ngaps;                 /* 0: none; 1: the same gap everywhere; nangles - 1 */
	double fps;                /* 100; each frame integrates its whole period */
	double brightness;         /* 300 photons per frame, fully on, z = 0, angle 1 */
	double brightness_cv;      /* 0.3: log-normal spread (coefficient of variation) */
	/* background and camera */
	double background;         /* 40 photons/pixel/frame at angle 1, smooth pattern per angle */
	double offset;             /* 100 ADU */
	double gain;               /* 1 ADU per photon */
	double read_noise;         /* ADU sd; used when snr_db <= 0 */
	double snr_db;             /* 14.75 */
	double hot_fraction;       /* 0: share of pixels with extra read noise */
	double hot_sd;             /* 30 ADU: that noise's sd */
	/* stage drift over the whole acquisition (the angles one after another) */
	double drift_nm[2];        /* 0,0: x, y displacement of the sample at the last frame */
	int drift_walk;            /* 0: linear; 1: Gaussian random walk (per-axis step sd |drift|/sqrt(frames)) */
	/* the camera (camera.c): enum c0_sim_camera_kind */
	int camera;                /* ccd: the model above */
	double em_gain;            /* 100 (emccd): the read noise is divided by it (added after the multiplication) */
	double offset_sd;          /* 2 ADU (scmos): spread of the per-pixel offset around offset */
	double gain_cv;            /* 0.03 (scmos): spread of the per-pixel gain around gain */
	double read_e;             /* 1.5 (scmos): median read-noise sd, electrons (photons) */
	double read_spread;        /* 0.45 (scmos): log-normal sigma of the per-pixel read-noise sd */
	int dark_frames;           /* 200 (scmos): frames of dark.tif */
	/* 0; 1: one more stack at the end at the first angle (its fade measures
	 * the bleaching over the acquisition: run's bleach repeat) */
	int repeat_first;
	/* the PSF the stacks are rendered with (enum c0_sim_psf_kind): gauss (the
	 * methods' model) or airy (same fwhm_nm; airy.c) */
	int psf;
};

/* Cameras (camera.c). ccd: ADU = gain Poisson + offset + read noise (above).
 * emccd: gain * Gamma(Poisson, 1) + offset + Normal(0, (read_noise / em_gain)^2):
 * the multiplication's excess noise factor sqrt 2, the readout noise referred
 * to photons divided by the EM gain, --gain ADU per photon as before.
 * scmos: per pixel i, gain_i = gain (1 + gain_cv N), offset_i = offset +
 * offset_sd N, read sd_i = gain_i read_e exp(read_spread N) (log-normal: a
 * median of read_e electrons, a tail to 4x at 0.1 %), plus the noisy pixels
 * (hot_fraction, hot_sd) as for the ccd; snr_db and read_noise are not used.
 * ADU = gain_i Poisson + offset_i + Normal(0, sd_i^2) (+ the noisy pixels'). */
enum c0_sim_camera_kind { C0_CAM_CCD, C0_CAM_EMCCD, C0_CAM_SCMOS };
int c0_sim_camera_parse(const char *name, int *camera);
const char *c0_sim_camera_name(int camera);
int c0_sim_camera_check(const struct c0_sim_conf *c);
/* The sCMOS pixels' maps (all NULL for the other cameras). */
struct c0_sim_cam {
	float *offset, *gain, *sd;   /* ADU, ADU per photon, ADU */
	uint8_t *hot;                /* 1: a noisy pixel */
};
int c0_sim_cam_new(const struct c0_sim_conf *c, struct c0_sim_cam *m);
void c0_sim_cam_free(struct c0_sim_cam *m);
/* Pixel i's dark variance (ADU^2): read noise, noisy pixel, rounding (1/12). */
double c0_sim_cam_variance(const struct c0_sim_conf *c, const struct c0_sim_cam *m, size_t i);
double c0_sim_cam_median_sd(const struct c0_sim_conf *c, const struct c0_sim_cam *m);
/* One frame through c's camera (ccd: c0_sim_camera, the same numbers). */
void c0_sim_expose(const struct c0_sim_conf *c, const struct c0_sim_cam *m, int q, int t, double read_noise,
		   const double *photons, float *adu);
/* scmos: calib_offset.tif, calib_variance.tif, calib_gain.tif (float32) and
 * dark.tif (dark_frames, uint16); nothing for the other cameras. */
struct c0_outdir;
int c0_sim_write_camera(const struct c0_sim_conf *c, const struct c0_sim_cam *m, struct c0_outdir *out);

/* PSFs (airy.c). The Airy disk's kernels: C0_AIRY_BANK^2 sub-pixel
 * positions, each K x K camera pixels (K = 2 c0_sim_airy_half + 2), the
 * emitter at (half + (i + 1/2)/C0_AIRY_BANK, half + (j + 1/2)/C0_AIRY_BANK)
 * of kernel j C0_AIRY_BANK + i; each sums to the share of the light inside. */
enum c0_sim_psf_kind { C0_SIM_PSF_GAUSS, C0_SIM_PSF_AIRY };
#define C0_AIRY_BANK 32
int c0_sim_psf_parse(const char *name, int *psf);
const char *c0_sim_psf_name(int psf);
int c0_sim_airy_half(double fwhm_px);
int c0_sim_airy_bank(double fwhm_px, int K, double **bank);

void c0_sim_defaults(struct c0_sim_conf *c);
/* With repeat_first: appends the first angle to the angles (once; refused
 * when there is no room). */
int c0_sim_add_repeat(struct c0_sim_conf *c);
/* enum c0_sim_order by its name in sim.json (sequential, interleaved, restart)
 * and back; an unknown name is refused naming bleach_order. */
int c0_sim_order_parse(const char *name, int *order);
const char *c0_sim_order_name(int order);
int c0_sim_check(const struct c0_sim_conf *c);
/* Sets the default angle set for c->tirf (nangles equally spaced in NA). */
void c0_sim_default_angles(struct c0_sim_conf *c, int n);

/* Emitters: from the CSV if given, else filaments. *out is malloc'ed. */
int c0_sim_structure(const struct c0_sim_conf *c, struct c0_emitter **out, int *n);
int c0_sim_read_csv(const char *path, double default_brightness, struct c0_emitter **out, int *n);

/* Fraction of each frame spent on: on[t] for t < frames, one emitter, one
 * acquisition. Stationary start; bleaching at an exponential time. */
void c0_sim_blink(const struct c0_sim_conf *c, uint64_t stream, int frames, float *on);
/* The same on the acquisition's time line: on[f] is the fraction of frame
 * period slot[f] (increasing; NULL: slot f) spent on. */
void c0_sim_blink_slots(const struct c0_sim_conf *c, uint64_t stream, const int64_t *slot, int frames, float *on);
/* Variance of the per-frame on-fraction of the unbleached telegraph process. */
double c0_sim_onfrac_variance(const struct c0_sim_conf *c);
/* Decay rate (1/s) of the expected signal: the slowest eigenvalue of the
 * on/off/bleached chain (about p_on / tau_bleach). */
double c0_sim_bleach_rate(const struct c0_sim_conf *c);
/* Frame period (slot) of stack q's frame t on the acquisition's time line. */
int64_t c0_sim_slot(const struct c0_sim_conf *c, int q, int t);
/* Excitation of angle q: inverse penetration depth (0 for an epi stack below
 * the critical angle) and I0 relative to the first TIRF angle's. Returns 1
 * for an epi stack. */
int c0_sim_excitation(const struct c0_sim_conf *c, int q, double *p, double *i0_rel);

struct c0_sim_angle {
	double p_per_nm, depth_nm, i0_rel;  /* physics of this angle (p = 0, depth inf: epi) */
	double bleach_factor;               /* mean over its frames of the population's on-fraction / p_on (1: unfaded) */
	double t_start_s;                   /* when its first frame starts on the time line */
	double read_noise, snr_db;          /* what was used / achieved */
	double *mean_on;                    /* per emitter, over the acquisition */
};

struct c0_sim_result {
	int nemitters;
	struct c0_emitter *em;
	struct c0_sim_angle angle[C0_MAX_ANGLES];
	double bleach_rate;                 /* 1/s, c0_sim_bleach_rate */
	float *stack[C0_MAX_ANGLES];        /* without an outdir: frames x height x width ADU per angle */
	double seconds;
};

/* Writes OUTDIR/stack_qNN.tif (uint16) and the ground truth; with out NULL,
 * keeps the stacks in res->stack instead (the same values) and writes nothing. */
struct c0_outdir;
int c0_simulate(const struct c0_sim_conf *c, struct c0_outdir *out, struct c0_sim_result *res);
void c0_sim_result_free(struct c0_sim_result *r);

/* One angle's frames t0..t0+n-1 as expected photons (noise-free) or ADU with
 * noise; used by c0_simulate and by the tests. */
struct c0_sim_scene;
int c0_sim_scene_new(const struct c0_sim_conf *c, const struct c0_emitter *em, int nem, int q,
		     struct c0_sim_scene **out);
void c0_sim_scene_free(struct c0_sim_scene *s);
const float *c0_sim_scene_onfrac(const struct c0_sim_scene *s);   /* frames x nem: on[t nem + e] */
const double *c0_sim_scene_background(const struct c0_sim_scene *s); /* photons, H x W */
void c0_sim_render(const struct c0_sim_scene *s, int t, double *photons);
/* Drift of the sample at frame t of angle q (nm), for every frame of that
 * angle: dx[t], dy[t] (t < frames). Time runs over the acquisition's slots:
 * interleaved stacks drift together, gaps between stacks drift too. */
void c0_sim_drift(const struct c0_sim_conf *c, int q, double *dx, double *dy);
void c0_sim_camera(const struct c0_sim_conf *c, int q, int t, double read_noise, const double *photons, float *adu);
