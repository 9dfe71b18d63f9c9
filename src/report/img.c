/* The image figures: colour maps, the page's binning, panels with a scale
 * bar, and the mean, render, depth and error-map sections. */
#include "report/html.h"
#include "core/mem.h"
#include "core/order.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PANEL_CSS 184   /* a panel's width on the page, CSS pixels */

int c0_page_bin(const float *img, int ny, int nx, float **out, int *oy, int *ox)
{
	int f = 1;
	while ((ny + f - 1) / f > C0_PAGE_MAX || (nx + f - 1) / f > C0_PAGE_MAX)
		f++;
	*oy = ny / f > 0 ? ny / f : 1, *ox = nx / f > 0 ? nx / f : 1;
	float *o = c0_alloc((size_t)*oy * *ox, sizeof *o);
	if (!o)
		return 0;
	for (int y = 0; y < *oy; y++)
		for (int x = 0; x < *ox; x++) {
			double s = 0;
			int c = 0;
			for (int i = y * f; i < (y + 1) * f && i < ny; i++)
				for (int j = x * f; j < (x + 1) * f && j < nx; j++)
					s += img[(size_t)i * nx + j], c++;
			o[(size_t)y * *ox + x] = (float)(s / c);
		}
	*out = o;
	return f;
}

static uint8_t byte(double v)
{
	return (uint8_t)(v <= 0 ? 0 : v >= 1 ? 255 : lround(v * 255));
}

void c0_cmap_grey(const float *img, size_t n, double lo, double hi, uint8_t *rgb)
{
	double s = hi > lo ? 1 / (hi - lo) : 0;
	for (size_t i = 0; i < n; i++)
		rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = byte((img[i] - lo) * s);
}

void c0_cmap_diverging(const float *img, size_t n, double s, uint8_t *rgb)
{
	static const double red[3] = { 0.70, 0.09, 0.17 }, blue[3] = { 0.13, 0.40, 0.67 };
	for (size_t i = 0; i < n; i++) {
		double t = s > 0 ? round(16 * fmax(-1, fmin(1, img[i] / s))) / 16 : 0;   /* 33 levels */
		const double *c = t > 0 ? red : blue;
		for (int k = 0; k < 3; k++)   /* white at 0, full colour at |t| = 1 */
			rgb[3 * i + k] = byte(1 + fabs(t) * (c[k] - 1));
	}
}

/* near the glass red, then yellow, green, cyan, deep blue (as depth.png) */
static const double depth_stops[5][3] = { { 1, 0, 0 }, { 1, 1, 0 }, { 0, 1, 0 }, { 0, 1, 1 }, { 0, 0, 1 } };

void c0_cmap_depth(double t, double v, uint8_t *rgb)
{
	t = fmax(0, fmin(1, t)) * 4;
	int k = t >= 4 ? 3 : (int)t;
	double u = t - k;
	for (int c = 0; c < 3; c++)
		rgb[c] = byte(v * (depth_stops[k][c] * (1 - u) + depth_stops[k + 1][c] * u));
}

/* a round length near a fifth of the field (nm) */
static double bar_nm(double field_nm)
{
	static const double nice[] = { 50, 100, 200, 500, 1000, 2000, 5000, 10000, 20000, 50000, 100000 };
	double want = field_nm / 5, best = nice[0];
	for (size_t i = 0; i < sizeof nice / sizeof *nice; i++)
		if (nice[i] <= want)
			best = nice[i];
	return best;
}

void c0_img_panel(struct c0_html *h, const uint8_t *rgb, int w, int ht, double pixel_nm, const char *caption)
{
	const double s = (double)PANEL_CSS / w, W = PANEL_CSS, H = ht * s;
	c0_html_printf(h, "<figure class=\"panel\"><svg width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 %.0f %.0f\" role=\"img\">"
		       "<image width=\"%.0f\" height=\"%.0f\" preserveAspectRatio=\"none\" href=\"", W, H, W, H, W, H);
	c0_html_png(h, w, ht, rgb);
	c0_html_add(h, "\"/>");
	if (pixel_nm > 0) {
		double nm = bar_nm(w * pixel_nm), len = nm / pixel_nm * s;
		c0_html_printf(h, "<rect class=\"bar\" x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"4\"/>"
			       "<text class=\"barlabel\" x=\"%.1f\" y=\"%.1f\">%g %s</text>", 10.0, H - 12, len, 10 + len / 2, H - 17,
			       nm >= 1000 ? nm / 1000 : nm, nm >= 1000 ? "\u00b5m" : "nm");
	}
	c0_html_add(h, "</svg><figcaption>");
	c0_html_escape(h, caption);
	c0_html_add(h, "</figcaption></figure>");
}

/* one plane through a colour map, binned to the page's size */
enum cmap { GREY, DIVERGING };
static void panel(struct c0_html *h, const float *img, int ny, int nx, double pixel_nm, enum cmap cm, double lo, double hi,
		  const char *caption)
{
	float *b;
	int by, bx, f = c0_page_bin(img, ny, nx, &b, &by, &bx);
	uint8_t *rgb = f ? c0_alloc((size_t)by * bx, 3) : NULL;
	if (!rgb) {
		free(f ? b : NULL);
		h->st = h->st ? h->st : -1;
		return;
	}
	if (cm == GREY)
		c0_cmap_grey(b, (size_t)by * bx, lo, hi, rgb);
	else
		c0_cmap_diverging(b, (size_t)by * bx, hi, rgb);
	c0_img_panel(h, rgb, bx, by, pixel_nm * f, caption);
	free(rgb), free(b);
}

/* "q1, 61.48 deg: stack_q01.tif" */
static void stack_caption(const struct c0_rundir *d, int q, char *out, size_t n)
{
	char k[64];
	snprintf(k, sizeof k, "intensity.%d.stack", q);
	const cJSON *s = c0_json_at(d->rep, k);
	if (!cJSON_IsString(s)) {
		snprintf(k, sizeof k, "support.%d.stack", q);
		s = c0_json_at(d->rep, k);
	}
	const char *name = cJSON_IsString(s) ? s->valuestring : "", *slash = strrchr(name, '/');
	snprintf(k, sizeof k, "matirf.angles_deg.%d", q);
	double a = c0_json_num(d->rep, k, NAN);
	if (isnan(a))
		snprintf(out, n, "q%d: %s", q + 1, slash ? slash + 1 : name);
	else
		snprintf(out, n, "q%d, %.2f\u00b0: %s", q + 1, a, slash ? slash + 1 : name);
}

static void section(struct c0_html *h, const char *id, const char *title, const char *what)
{
	c0_html_printf(h, "<section id=\"%s\"><h2>%s</h2><p class=\"what\">", id, title);
	c0_html_add(h, what);
	c0_html_add(h, "</p><div class=\"panels\">");
}

static void absent(struct c0_html *h, const char *id, const char *title, const char *why)
{
	c0_html_printf(h, "<section id=\"%s\"><h2>%s</h2><p class=\"absent\">%s</p></section>\n", id, title, why);
}

void c0_fig_mean(struct c0_html *h, const struct c0_rundir *d)
{
	if (!d->n || !d->mean[0]) {
		absent(h, "mean", "Mean images", c0_json_at(d->rep, "support.0.stacks_pooled")
			? "No mean_qNN.tif here: the support pooled the stacks' covariances, which keeps no stack's own mean (run writes them)."
			: "No mean_qNN.tif here: the command read no stacks (matirf), or the run is older than these files.");
		return;
	}
	section(h, "mean", "Mean images", "The temporal mean of each stack on the camera grid (after drift correction), "
		"grey from its 0.5th to its 99.5th percentile.");
	const size_t L = (size_t)d->ny * d->nx;
	for (int q = 0; q < d->n; q++) {
		char cap[512];
		stack_caption(d, q, cap, sizeof cap);
		panel(h, d->mean[q], d->ny, d->nx, d->grid.pixel_nm, GREY, c0_quantile(d->mean[q], L, 0.005),
		      c0_quantile(d->mean[q], L, 0.995), cap);
	}
	c0_html_add(h, "</div></section>\n");
}

void c0_fig_render(struct c0_html *h, const struct c0_rundir *d)
{
	if (!d->render) {
		absent(h, "render", "Super-resolved render", "This run made no render (render.tif: the run command only).");
		return;
	}
	section(h, "render", "Super-resolved render", "Each stack's intensity splatted with a Gaussian of the localisation "
		"precision (render.tif), grey from 0 to its 99.9th percentile.");
	const int Ly = d->ny * d->grid.srf, Lx = d->nx * d->grid.srf;
	const size_t L = (size_t)Ly * Lx;
	for (int q = 0; q < d->n; q++) {
		char cap[512];
		stack_caption(d, q, cap, sizeof cap);
		float *img;
		int st = c0_rundir_plane(d, "render.tif", q, &img);
		if (st) {
			h->st = h->st ? h->st : st;
			return;
		}
		panel(h, img, Ly, Lx, c0_grid_fine_nm(&d->grid), GREY, 0, c0_quantile(img, L, 0.999), cap);
		free(img);
	}
	c0_html_add(h, "</div></section>\n");
}

static void depth_panel(struct c0_html *h, const struct c0_depthmap *m, double z0, double z1, const char *caption)
{
	float *dep, *tot;
	int by, bx, f = c0_page_bin(m->depth, m->ny, m->nx, &dep, &by, &bx);
	int g = c0_page_bin(m->total, m->ny, m->nx, &tot, &by, &bx);
	size_t L = (size_t)by * bx;
	uint8_t *rgb = f && g ? c0_alloc(L, 3) : NULL;
	if (rgb) {
		double top = c0_quantile(tot, L, 0.995);
		for (size_t i = 0; i < L; i++)
			c0_cmap_depth((dep[i] - z0) / (z1 - z0), top > 0 ? sqrt(fmax(0, tot[i]) / top) : 0, rgb + 3 * i);
		c0_img_panel(h, rgb, bx, by, m->pixel_nm * f, caption);
	} else if (!h->st)
		h->st = -1;
	free(rgb), free(f ? dep : NULL), free(g ? tot : NULL);
}

static void depth_bar(struct c0_html *h, double z0, double z1)
{
	c0_html_add(h, "<figure class=\"panel cbar\"><svg width=\"70\" height=\"184\" role=\"img\"><defs><linearGradient id=\"zgrad\" "
		       "x1=\"0\" y1=\"0\" x2=\"0\" y2=\"1\">");
	for (int k = 0; k < 5; k++)
		c0_html_printf(h, "<stop offset=\"%d%%\" stop-color=\"rgb(%d,%d,%d)\"/>", 25 * k, (int)(255 * depth_stops[k][0]),
			       (int)(255 * depth_stops[k][1]), (int)(255 * depth_stops[k][2]));
	c0_html_printf(h, "</linearGradient></defs><rect x=\"4\" y=\"8\" width=\"16\" height=\"168\" fill=\"url(#zgrad)\"/>"
		       "<text x=\"24\" y=\"16\">%g nm</text><text x=\"24\" y=\"96\">%g</text><text x=\"24\" y=\"178\">%g nm</text>"
		       "</svg><figcaption>depth</figcaption></figure>", z0, (z0 + z1) / 2, z1);
}

void c0_fig_depth(struct c0_html *h, const struct c0_rundir *d)
{
	if (!d->vol.depth) {
		absent(h, "depth", "Depth", "No MA-TIRF volume in this run (give --angles for 3D).");
		return;
	}
	section(h, "depth", "Depth", "Each pixel's depth (depth.tif: in a run, the single depth that best fits its column; from "
		"col0rme matirf, the column's mean) as colour, its total intensity over depth "
		"(volume.tif) as brightness (square root, full at the 99.5th percentile); beside it the standard MA-TIRF "
		"baseline on the camera grid when --baseline was given.");
	depth_panel(h, &d->vol, d->z0, d->z1, "3D-COL0RME (fine grid)");
	if (d->base.depth)
		depth_panel(h, &d->base, d->z0, d->z1, "standard MA-TIRF baseline (camera grid)");
	depth_bar(h, d->z0, d->z1);
	c0_html_add(h, "</div></section>\n");
}

static void err_bar(struct c0_html *h, double s, int sds)
{
	c0_html_add(h, "<figure class=\"panel cbar\"><svg width=\"64\" height=\"184\" role=\"img\"><defs><linearGradient id=\"egrad\" "
		       "x1=\"0\" y1=\"0\" x2=\"0\" y2=\"1\">");
	for (int k = 0; k <= 8; k++) {
		float v = (float)(s * (1 - k / 4.0));
		uint8_t c[3];
		c0_cmap_diverging(&v, 1, s, c);
		c0_html_printf(h, "<stop offset=\"%.1f%%\" stop-color=\"rgb(%d,%d,%d)\"/>", 12.5 * k, c[0], c[1], c[2]);
	}
	c0_html_printf(h, "</linearGradient></defs><rect x=\"4\" y=\"8\" width=\"16\" height=\"168\" fill=\"url(#egrad)\"/>"
		       "<text x=\"24\" y=\"16\">+%.3g</text><text x=\"24\" y=\"96\">0</text><text x=\"24\" y=\"178\">\u2212%.3g</text>"
		       "</svg><figcaption>%s</figcaption></figure>", s, s,
		       sds ? "(data \u2212 model) / noise sd" : "data \u2212 model");
}

static void err_table(struct c0_html *h, const struct c0_rundir *d)
{
	c0_html_add(h, "<table class=\"nums\"><tr><th>stack</th><th>RSP</th><th>RSE</th><th>noise sd of the mean</th>"
		       "<th>RSE / noise sd</th><th>mean of the data</th></tr>");
	for (int q = 0; q < d->n; q++) {
		const struct c0_errstat *e = &d->es[q];
		if (!d->err[q])
			continue;
		c0_html_printf(h, "<tr><td>q%d</td><td data-err=\"%d.rsp\">%.4f</td><td data-err=\"%d.rse\">%.4g</td>"
			       "<td data-err=\"%d.noise_sd\">%.4g</td><td>%.3g</td><td>%.4g</td></tr>", q + 1, q, e->rsp, q, e->rse, q,
			       e->noise_sd, e->noise_sd > 0 ? e->rse / e->noise_sd : NAN, e->mean_data);
	}
	c0_html_add(h, "</table>");
}

void c0_fig_errmap(struct c0_html *h, const struct c0_rundir *d)
{
	int any = 0;
	for (int q = 0; q < d->n; q++)
		any |= d->err[q] != NULL;
	if (!any) {
		absent(h, "error-map", "Error map", "Needs each stack's mean, intensity and background (the run and intensity "
		       "commands write them).");
		return;
	}
	section(h, "error-map", "Error map", "The estimate taken back to the camera by the forward model of the "
		"intensity step (the intensity blurred by the Gaussian PSF and integrated over the camera pixels, plus the "
		"estimated background) against the data's mean image, in noise sds of the mean image (\u00b15 at full colour). <b>Red</b>: the data is brighter than the model (structure "
		"the estimate misses); <b>blue</b>: the model is brighter (structure it invents). The same scale for all "
		"stacks (error_qNN.tif: the residual in camera units, calibrated, for Fiji).");
	/* shown in noise sds of the mean image when every stack has one (the
	 * same colour means the same significance at every angle), else in
	 * camera units on one scale */
	const size_t L = (size_t)d->ny * d->nx;
	int sds = 1;
	for (int q = 0; q < d->n; q++)
		sds &= !d->err[q] || d->es[q].noise_sd > 0;
	double s = sds ? 5 : 0;
	for (int q = 0; !sds && q < d->n; q++)
		if (d->err[q]) {
			float *a = c0_alloc(L, sizeof *a);
			for (size_t i = 0; a && i < L; i++)
				a[i] = fabsf(d->err[q][i]);
			s = a ? fmax(s, c0_quantile(a, L, 0.995)) : s;
			free(a);
		}
	float *z = c0_alloc(L, sizeof *z);
	for (int q = 0; z && q < d->n; q++) {
		char cap[512];
		if (!d->err[q])
			continue;
		for (size_t i = 0; i < L; i++)
			z[i] = sds ? (float)(d->err[q][i] / d->es[q].noise_sd) : d->err[q][i];
		stack_caption(d, q, cap, sizeof cap);
		panel(h, z, d->ny, d->nx, d->grid.pixel_nm, DIVERGING, 0, s > 0 ? s : 1, cap);
	}
	if (!z && !h->st)
		h->st = -1;
	free(z);
	err_bar(h, s > 0 ? s : 1, sds);
	c0_html_add(h, "</div>");
	err_table(h, d);
	c0_html_add(h, "<p class=\"what\">RSP (resolution-scaled Pearson): the correlation of the data's mean image and "
		       "the model, 1 when they agree up to noise. RSE (resolution-scaled error): the RMS of data \u2212 model in "
		       "camera units, to be read against the noise sd of a mean image, \u221a(noise variance / frames); "
		       "a ratio well above 1 is model error (structure missed or invented, PSF or background mismatch). "
		       "As SQUIRREL's, but without its fitted scale and offset: the estimate is already in camera units and "
		       "the background is part of it.</p></section>\n");
}
