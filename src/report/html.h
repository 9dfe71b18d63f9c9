/* report.html: one self-contained page (images inline as base64 PNG, plots
 * as inline SVG, no script, no external resource) that shows what a run did
 * and where its estimate disagrees with the data. It is built from an output
 * directory's files only (report.json and the TIFFs), so `col0rme report`
 * makes it for any earlier run; `run` and `support` call it last.
 *
 * The parts: buf.c (text, base64, PNG in memory), load.c
 * (the files), errmap.c (the error map), img.c (the image
 * figures), plot.c (the SVG plots), tables.c (warnings,
 * parameters, timings, command) and page.c (the page). */
#pragma once
#include "col0rme.h"
#include "optics/grid.h"
#include <cjson/cJSON.h>
#include <stddef.h>
#include <stdint.h>

/* A growing text; a failed allocation or encoding sets st, and every later
 * append does nothing. */
struct c0_html {
	char *s;
	size_t n, cap;
	int st;
};
void c0_html_add(struct c0_html *h, const char *text);
void c0_html_printf(struct c0_html *h, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* text with & < > " escaped */
void c0_html_escape(struct c0_html *h, const char *text);
/* "data:image/png;base64,..." of an RGB image (h rows of w pixels) */
void c0_html_png(struct c0_html *h, int w, int ht, const uint8_t *rgb);
/* A number as the page shows it (%.4g, or %.6g with digits6), tagged with
 * the report.json path it comes from so that a reader (and the tests) can
 * check it: <span data-json="PATH">VALUE</span>. */
void c0_html_num(struct c0_html *h, const char *path, double v);
/* A report.json value by dotted path ("support.0.lambda_relative"), or NULL. */
const cJSON *c0_json_at(const cJSON *root, const char *path);
/* its number, or def when absent or not a number */
double c0_json_num(const cJSON *root, const char *path, double def);

/* The error map of one angle: the data's mean image against the estimate
 * pushed through the forward model (PSF blur and camera pixels, plus the
 * estimated background), residual = data - model, on the camera grid. */
struct c0_errstat {
	double rsp;        /* resolution-scaled Pearson: correlation of data and model */
	double rse;        /* resolution-scaled error: RMS residual (camera units) */
	double noise_sd;   /* sd of the mean image's noise, sqrt(noise variance / frames), 0: unknown */
	double mean_data;  /* mean of the data image */
};

/* An output directory's files, loaded. Images are row-major floats. */
struct c0_rundir {
	const char *dir;
	cJSON *rep;
	int n;                           /* stacks (report.json's "intensity", else "support") */
	int ny, nx;                      /* camera grid (from the file grid_file) */
	const char *grid_file;
	struct c0_grid grid;             /* camera pixel, PSF, super-resolution factor */
	float *mean[C0_MAX_STACKS];      /* mean_qNN.tif, camera grid (NULL: not written) */
	float *bg[C0_MAX_STACKS];        /* background_qNN.tif, camera grid */
	float *err[C0_MAX_STACKS];       /* the residual (errmap.c), camera grid */
	struct c0_errstat es[C0_MAX_STACKS];
	int inten, render;               /* intensity_qNN.tif and render.tif (fine grid) are there, checked;
					  * read plane by plane (c0_rundir_plane) where drawn */
	struct c0_depthmap {
		float *depth, *total;    /* depth (nm), and the volume summed over depth */
		int ny, nx;
		double pixel_nm;
	} vol, base;                     /* depth.tif + volume.tif, baseline_* (NULL when absent) */
	double z0, z1;                   /* depth range of the bins (nm) */
};

/* Reads OUTDIR's report.json and the files its sections say were written;
 * an error names the missing or bad file. */
int c0_rundir_load(struct c0_rundir *d, const char *dir);
void c0_rundir_free(struct c0_rundir *d);
/* Plane `plane` of d's file name (allocated). */
int c0_rundir_plane(const struct c0_rundir *d, const char *name, int64_t plane, float **out);
/* d->err and d->es for every stack with a mean, intensity and background. */
int c0_errmap(struct c0_rundir *d);

/* The figures and tables, each appended to h as one <section id=...>. */
void c0_fig_mean(struct c0_html *h, const struct c0_rundir *d);
void c0_fig_render(struct c0_html *h, const struct c0_rundir *d);
void c0_fig_depth(struct c0_html *h, const struct c0_rundir *d);
void c0_fig_errmap(struct c0_html *h, const struct c0_rundir *d);
void c0_fig_lambda(struct c0_html *h, const struct c0_rundir *d);
void c0_fig_drift(struct c0_html *h, const struct c0_rundir *d);
void c0_fig_bleach(struct c0_html *h, const struct c0_rundir *d);
void c0_fig_frc(struct c0_html *h, const struct c0_rundir *d);
void c0_tab_warnings(struct c0_html *h, const struct c0_rundir *d);
void c0_tab_parameters(struct c0_html *h, const struct c0_rundir *d);
void c0_tab_timings(struct c0_html *h, const struct c0_rundir *d);
void c0_tab_command(struct c0_html *h, const struct c0_rundir *d);

/* A line plot in SVG: axes with ticks, then curves and marks in data units. */
struct c0_plot {
	double x0, x1, y0, y1;           /* data range */
	int logx, logy;
	int w, h;                        /* pixels */
	int legend_low;                  /* 1: the legend bottom left instead of top right */
};
void c0_plot_begin(struct c0_html *h, struct c0_plot *p, const char *xlabel, const char *ylabel);
void c0_plot_line(struct c0_html *h, const struct c0_plot *p, const double *x, const double *y, int n,
		  const char *colour, int dashed);
void c0_plot_mark(struct c0_html *h, const struct c0_plot *p, double x, double y, const char *colour, const char *label);
void c0_plot_legend(struct c0_html *h, const struct c0_plot *p, int row, const char *colour, int dashed, const char *text);
void c0_plot_end(struct c0_html *h);

/* An image figure: an RGB image shown w_css pixels wide inside an SVG with
 * a scale bar for pixel_nm per image pixel, and a caption. */
void c0_img_panel(struct c0_html *h, const uint8_t *rgb, int w, int ht, double pixel_nm, const char *caption);
/* Colour maps into rgb (3 bytes): grey from lo to hi; diverging blue (-s) -
 * white - red (+s); depth hue (0: near the glass, red; 1: deep, blue) at
 * brightness v in [0, 1]. */
void c0_cmap_grey(const float *img, size_t n, double lo, double hi, uint8_t *rgb);
void c0_cmap_diverging(const float *img, size_t n, double s, uint8_t *rgb);
void c0_cmap_depth(double t, double v, uint8_t *rgb);
/* Box-averages an image to at most C0_PAGE_MAX pixels a side (the page's
 * resolution; the TIFFs keep the full one); returns the factor (1: a copy). */
#define C0_PAGE_MAX 512
int c0_page_bin(const float *img, int ny, int nx, float **out, int *oy, int *ox);
