/* Glue shared by the subcommands that run pipeline stages: input checks,
 * stage runs that fill the JSON report, and writing their outputs. */
#pragma once
#include "stages/support.h"
#include "io/outdir.h"
#include "io/report.h"

/* Every stack opens as a TIFF, and OUTDIR is not where an input lives. */
int c0_check_inputs(char **stacks, int n, const char *outdir);
/* Support of each stack (pixel size from the first stack's calibration when
 * c->pixel_nm is 0); fills rep["support"]. */
int c0_run_support(struct c0_support_conf *c, char **stacks, int n, struct c0_support_result *res, cJSON *rep);
/* support.tif (union of the masks) and rx.tif (one plane per stack). */
int c0_write_support(struct c0_outdir *out, const struct c0_support_conf *c, const struct c0_support_result *res,
		     int n, cJSON *rep);

#include "stages/intensity.h"

/* Intensity and background of each stack on the support mask (Ly x Lx).
 * known (n pointers, or NULL): the support result of a stack when the
 * support step ran on it, whose mean and noise variance are used as they
 * are; otherwise one pass over the stack, for its mean when sigma2[i] > 0
 * gives the noise variance, else for its covariance, from which the noise
 * variance is estimated on the mask.
 * Writes intensity_qNN.tif and background_qNN.tif, fills rep["intensity"].
 * corrected (n pointers, or NULL): receives each temporal mean minus its
 * background (coarse grid, allocated), the standard MA-TIRF input. */
int c0_run_intensity(struct c0_outdir *out, const struct c0_intensity_conf *ic, const struct c0_support_conf *sc,
		     char **stacks, int n, const uint8_t *mask, const double *sigma2,
		     const struct c0_support_result *const *known, struct c0_intensity_result *res, float **corrected,
		     cJSON *rep);

#include "stages/matirf.h"
#include "cli/opts.h"

/* The MA-TIRF options shared by 'matirf' and 'run'. */
struct c0_matirf_cli {
	struct c0_matirf_conf c;
	double angles[64], gains[64], zr[3];
	int nangles, ngains, nzr;
	const char *reg;
};
#define C0_MATIRF_CLI_OPTS 12
/* Fills C0_MATIRF_CLI_OPTS rows of o from m (which holds the defaults). */
void c0_matirf_cli_opts(struct c0_matirf_cli *m, struct c0_opt *o);
/* Turns the parsed strings and lists into m->c; nimages: expected angles. */
int c0_matirf_cli_finish(struct c0_matirf_cli *m, int nimages);
/* Reconstructs the volume from nq images (ny x nx, pixel pixel_nm) and writes
 * PREFIXvolume.tif, PREFIXdepth.tif (mean depth) and PREFIXdepth.png; fills
 * rep[key]. own (or NULL): when img are pooled (stages/depthpool.h), the
 * pixels' own images, to which the volume is rescaled. */
int c0_run_matirf(struct c0_outdir *out, const struct c0_matirf_cli *m, const float *const *img,
		  const float *const *own, int ny, int nx, double pixel_nm, const char *prefix, const char *key,
		  struct c0_matirf_result *res, cJSON *rep);

#include "stages/bleach.h"

/* run's bleaching options into c: mode ("estimate", "off" or factors; NULL:
 * estimate when three_d), acquisition ("sequential" or "interleaved") and
 * the 1-based recording order; checks them against the n stacks. */
int c0_bleach_cli(const char *mode, const char *acq, const int *order, int norder, int three_d, int n,
		  struct c0_bleach_conf *c);
/* Estimates the fade (stages/bleach.h) with each stack's background from
 * res, divides each intensity res[q].x (and corrected[q], when given) by its
 * factor, and fills rep["bleaching"]. The intensity files are written
 * before: they are the stacks' own means. */
int c0_run_bleach(const struct c0_bleach_conf *c, char **stacks, int n, struct c0_intensity_result *res,
		  float **corrected, const int *support_only, cJSON *rep);
