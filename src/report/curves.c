/* The plotted sections, each from its part of report.json: the lambda
 * criterion, the drift trajectory, the bleaching fit and the FRC. */
#include "report/html.h"
#include "core/mem.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* a report.json array of numbers (allocated; *n 0 when absent) */
static double *array(const cJSON *rep, const char *path, int *n)
{
	const cJSON *a = c0_json_at(rep, path);
	*n = cJSON_IsArray(a) ? cJSON_GetArraySize(a) : 0;
	double *v = *n ? c0_alloc((size_t)*n, sizeof *v) : NULL;
	if (!v)
		*n = 0;
	for (int i = 0; i < *n; i++) {
		const cJSON *e = cJSON_GetArrayItem(a, i);
		v[i] = cJSON_IsNumber(e) ? e->valuedouble : NAN;
	}
	return v;
}

static void range(const double *v, int n, double *lo, double *hi)
{
	for (int i = 0; i < n; i++)
		if (isfinite(v[i]))
			*lo = fmin(*lo, v[i]), *hi = fmax(*hi, v[i]);
}

static void open_section(struct c0_html *h, const char *id, const char *title, const char *what)
{
	c0_html_printf(h, "<section id=\"%s\"><h2>%s</h2><p class=\"what\">%s</p><div class=\"panels\">", id, title, what);
}

/* y at x on a curve by linear interpolation in log x */
static double at(const double *x, const double *y, int n, double v)
{
	for (int i = 0; i + 1 < n; i++)
		if ((x[i] - v) * (x[i + 1] - v) <= 0) {
			double t = x[i + 1] != x[i] ? (log(v) - log(x[i])) / (log(x[i + 1]) - log(x[i])) : 0;
			return y[i] + t * (y[i + 1] - y[i]);
		}
	return NAN;
}

/* The cross-validation path (stages/lambda.h, c0_lambda_cv): its error over
 * the least, so that the flat bottom shows (log scale, floor 1e-5) */
static void cv_one(struct c0_html *h, const cJSON *rep, int k, double chosen)
{
	char p[128];
	int n, ne;
	snprintf(p, sizeof p, "support.%d.lambda_auto.cross_validation.lambda_relative", k);
	double *x = array(rep, p, &n);
	snprintf(p, sizeof p, "support.%d.lambda_auto.cross_validation.error", k);
	double *e = array(rep, p, &ne);
	if (n > 1 && ne == n) {
		double least = INFINITY, lo = INFINITY, hi = 0, xl = NAN, top = 1e-4;
		for (int i = 0; i < n; i++)
			if (e[i] < least)
				least = e[i], xl = x[i];
		for (int i = 0; i < n; i++) {
			e[i] = fmax(e[i] / least - 1, 1e-5);
			lo = fmin(lo, x[i]), hi = fmax(hi, x[i]), top = fmax(top, e[i]);
		}
		struct c0_plot pl = { lo / 1.5, hi * 1.5, 1e-5, top * 2, 1, 1, 0, 0, 1 };
		c0_plot_begin(h, &pl, "\u03bb / \u03bb_max", "cross-validation error / least \u2212 1");
		c0_plot_line(h, &pl, x, e, n, "#1f4e8c", 0);
		c0_plot_mark(h, &pl, xl, 1e-5, "#888", "least");
		c0_plot_mark(h, &pl, chosen, 1e-5, "#c0392b", "chosen");
		c0_plot_end(h);
	}
	free(x), free(e);
}

static void lambda_one(struct c0_html *h, const cJSON *rep, int k)
{
	char p[128], q[128], cap[160];
	int n, ns, nn;
	snprintf(p, sizeof p, "support.%d.lambda_auto.curve.lambda_relative", k);
	double *x = array(rep, p, &n);
	snprintf(p, sizeof p, "support.%d.lambda_auto.curve.signal_above", k);
	double *s = array(rep, p, &ns);
	snprintf(p, sizeof p, "support.%d.lambda_auto.curve.noise_above", k);
	double *z = array(rep, p, &nn);
	snprintf(p, sizeof p, "support.%d.lambda_relative", k);
	double chosen = c0_json_num(rep, p, NAN);
	c0_html_add(h, "<figure class=\"plotfig\">");
	if (n > 1 && ns == n && nn == n) {
		struct c0_plot pl = { x[0], x[n - 1], 1e-4, 1, 1, 1, 0, 0, 1 };
		c0_plot_begin(h, &pl, "\u03bb / \u03bb_max", "share of fine pixels above \u03bb");
		c0_plot_line(h, &pl, x, s, n, "#1f4e8c", 0);
		c0_plot_line(h, &pl, x, z, n, "#888", 1);
		c0_plot_mark(h, &pl, chosen, at(x, s, n, chosen), "#c0392b", "chosen");
		c0_plot_legend(h, &pl, 0, "#1f4e8c", 0, "correlation image");
		c0_plot_legend(h, &pl, 1, "#888", 1, "noise of the halves");
		c0_plot_end(h);
		cv_one(h, rep, k, chosen);
	} else
		c0_html_add(h, "<p class=\"absent\">No criterion curve: \u03bb was given.</p>");
	snprintf(q, sizeof q, "support.%d.stack", k);
	const cJSON *st = c0_json_at(rep, q);
	const char *name = cJSON_IsString(st) ? st->valuestring : "", *sl = strrchr(name, '/');
	snprintf(cap, sizeof cap, "%s: \u03bb/\u03bb_max = ", sl ? sl + 1 : name);
	c0_html_add(h, "<figcaption>");
	c0_html_escape(h, cap);
	c0_html_num(h, p, chosen);
	snprintf(q, sizeof q, "support.%d.lambda_auto.bound_by", k);
	const cJSON *b = c0_json_at(rep, q);
	if (cJSON_IsString(b))
		c0_html_printf(h, ", bound by the %s", b->valuestring);
	snprintf(q, sizeof q, "support.%d.support_pixels", k);
	c0_html_add(h, "; support pixels ");
	c0_html_num(h, q, c0_json_num(rep, q, NAN));
	c0_html_add(h, "</figcaption></figure>");
	free(x), free(s), free(z);
}

void c0_fig_lambda(struct c0_html *h, const struct c0_rundir *d)
{
	const cJSON *su = c0_json_at(d->rep, "support");
	if (!cJSON_IsArray(su) || !cJSON_GetArraySize(su)) {
		c0_html_add(h, "<section id=\"lambda\"><h2>\u03bb criterion</h2><p class=\"absent\">No support step in this run.</p></section>\n");
		return;
	}
	const cJSON *rule = c0_json_at(d->rep, "support.0.lambda_auto.rule");
	open_section(h, "lambda", "\u03bb criterion", "The support's regularisation: the share of fine pixels whose "
		     "correlation exceeds \u03bb (solid) and the same for the noise image of the frame halves (dashed), "
		     "against \u03bb relative to \u03bb_max; below it, where \u03bb was cross-validated, how much worse "
		     "each \u03bb's solutions on one half of the frames predict the other half's covariance than the "
		     "best of the path. The red point is the \u03bb the run used.");
	for (int k = 0; k < cJSON_GetArraySize(su); k++)
		lambda_one(h, d->rep, k);
	c0_html_add(h, "</div>");
	if (cJSON_IsString(rule)) {
		c0_html_add(h, "<p class=\"what\">Rule: ");
		c0_html_escape(h, rule->valuestring);
		c0_html_add(h, ".</p>");
	}
	c0_html_add(h, "</section>\n");
}

void c0_fig_drift(struct c0_html *h, const struct c0_rundir *d)
{
	int n, nx, ny;
	double *t = array(d->rep, "drift.block_centre_frame", &n), *x = array(d->rep, "drift.block_dx_nm", &nx),
	       *y = array(d->rep, "drift.block_dy_nm", &ny);
	if (n < 1 || nx != n || ny != n) {
		c0_html_add(h, "<section id=\"drift\"><h2>Drift</h2><p class=\"absent\">No drift estimate in this run "
			       "(--drift off, or a command without it).</p></section>\n");
		free(t), free(x), free(y);
		return;
	}
	open_section(h, "drift", "Drift", "The lateral drift of the sample against the frames of the whole acquisition "
		     "(PSF-filtered block means cross-correlated; drift.csv has every frame). It was undone frame by frame before the "
		     "covariance and the means; an axis within 6 noise sds of zero is left uncorrected.");
	double lo = -10, hi = 10;
	range(x, n, &lo, &hi), range(y, n, &lo, &hi);
	struct c0_plot pl = { 0, t[n - 1] + t[0], lo - 2, hi + 2, 0, 0, 0, 0, 0 };
	c0_html_add(h, "<figure class=\"plotfig\">");
	c0_plot_begin(h, &pl, "frame (whole acquisition)", "shift (nm)");
	c0_plot_line(h, &pl, t, x, n, "#c0392b", 0);
	c0_plot_line(h, &pl, t, y, n, "#1f4e8c", 0);
	c0_plot_legend(h, &pl, 0, "#c0392b", 0, "x");
	c0_plot_legend(h, &pl, 1, "#1f4e8c", 0, "y");
	c0_plot_end(h);
	c0_html_add(h, "<figcaption>largest shift ");
	c0_html_num(h, "drift.max_nm", c0_json_num(d->rep, "drift.max_nm", NAN));
	c0_html_add(h, " nm; noise of one block x ");
	c0_html_num(h, "drift.block_noise_nm.0", c0_json_num(d->rep, "drift.block_noise_nm.0", NAN));
	c0_html_add(h, " nm, y ");
	c0_html_num(h, "drift.block_noise_nm.1", c0_json_num(d->rep, "drift.block_noise_nm.1", NAN));
	c0_html_add(h, " nm</figcaption></figure></div></section>\n");
	free(t), free(x), free(y);
}

void c0_fig_bleach(struct c0_html *h, const struct c0_rundir *d)
{
	int n, nf, nk;
	double *start = array(d->rep, "bleaching.start_frame", &n), *F = array(d->rep, "bleaching.factors", &nf),
	       *ks = array(d->rep, "bleaching.rate_per_frame_by_stack", &nk), k = c0_json_num(d->rep, "bleaching.rate_per_frame", NAN);
	if (n < 1 || nf != n) {
		c0_html_add(h, "<section id=\"bleach\"><h2>Bleaching</h2><p class=\"absent\">No bleaching step in this run "
			       "(it runs with --angles).</p></section>\n");
		free(start), free(F), free(ks);
		return;
	}
	open_section(h, "bleach", "Bleaching", "The fade of the fluorophore population over the acquisition clock: the "
		     "fitted model e<sup>\u2212k u</sup> (grey) and, for each stack, its own measured rate from the slope of "
		     "its frame sums, drawn over its frames through the model at their middle (colour); the dot is the factor "
		     "its intensity was divided by.");
	const double T = n && d->n ? c0_json_num(d->rep, "intensity.0.frames", 0) : 0;
	double end = 0;
	for (int q = 0; q < n; q++)
		end = fmax(end, start[q] + T);
	struct c0_plot pl = { 0, end > 0 ? end : 1, 0, 1.05, 0, 0, 0, 0, 0 };
	double lo = 1;
	for (int q = 0; q < n; q++)
		lo = fmin(lo, F[q]);
	if (isfinite(k))
		lo = fmin(lo, exp(-k * end));
	pl.y0 = fmax(0, floor((lo - 0.05) * 20) / 20);
	c0_html_add(h, "<figure class=\"plotfig\">");
	c0_plot_begin(h, &pl, "acquisition clock (frames)", "population / start");
	static const char *col[] = { "#c0392b", "#d68910", "#1e8449", "#17a589", "#1f4e8c", "#7d3c98" };
	if (isfinite(k)) {
		double u[64], m[64];
		for (int i = 0; i < 64; i++)
			u[i] = end * i / 63, m[i] = exp(-k * u[i]);
		c0_plot_line(h, &pl, u, m, 64, "#999", 0);
	}
	for (int q = 0; q < n; q++) {
		double mid = start[q] + T / 2, u[2] = { start[q], start[q] + T }, m[2];
		if (T > 0 && q < nk && isfinite(ks[q]) && isfinite(k)) {
			for (int i = 0; i < 2; i++)
				m[i] = exp(-k * mid) * exp(-ks[q] * (u[i] - mid));
			c0_plot_line(h, &pl, u, m, 2, col[q % 6], 0);
		}
		char lab[16];
		snprintf(lab, sizeof lab, "q%d", q + 1);
		c0_plot_mark(h, &pl, mid, F[q], col[q % 6], lab);
	}
	c0_plot_end(h);
	c0_html_add(h, "<figcaption>rate ");
	c0_html_num(h, "bleaching.rate_per_frame", k);
	const double ksd = c0_json_num(d->rep, "bleaching.rate_sd_per_frame", NAN);
	if (isfinite(ksd)) {
		c0_html_add(h, " \u00b1 ");
		c0_html_num(h, "bleaching.rate_sd_per_frame", ksd);
		const double kfit = c0_json_num(d->rep, "bleaching.rate_fit_per_frame", NAN);
		if (kfit < 0) {   /* clamped: a fade cannot reverse */
			c0_html_add(h, " (the slopes' fit, ");
			c0_html_num(h, "bleaching.rate_fit_per_frame", kfit);
			c0_html_add(h, ", is below 0: a fade cannot reverse)");
		}
	} else if (isfinite(c0_json_num(d->rep, "bleaching.repeat_ratio", NAN)))   /* bleach repeat: one ratio, no sd */
		c0_html_add(h, " (from the repeat of the first angle, the last stack)");
	c0_html_add(h, " per frame; factors");
	for (int q = 0; q < n; q++) {
		char p[64];
		snprintf(p, sizeof p, "bleaching.factors.%d", q);
		c0_html_add(h, " ");
		c0_html_num(h, p, F[q]);
	}
	const double dsd = c0_json_num(d->rep, "bleaching.depth_offset_sd_nm", NAN);
	if (isfinite(dsd)) {   /* the rate's sd as depth: every depth shares it */
		c0_html_add(h, ". One sd of the rate moves every depth alike by ");
		c0_html_num(h, "bleaching.depth_offset_sd_nm", dsd);
		c0_html_add(h, " nm");
	}
	c0_html_add(h, "</figcaption></figure></div></section>\n");
	free(start), free(F), free(ks);
}

/* The halves' FRC as a curve, with no threshold and no resolution: its 1/7
 * crossing does not follow what is resolved (docs/guide.md, section 5). */
static void frc_one(struct c0_html *h, const cJSON *rep, int k)
{
	char p[128];
	int n, nc;
	snprintf(p, sizeof p, "support.%d.frc.frequency_per_nm", k);
	double *f = array(rep, p, &n);
	snprintf(p, sizeof p, "support.%d.frc.correlation", k);
	double *c = array(rep, p, &nc);
	c0_html_add(h, "<figure class=\"plotfig\">");
	if (n > 1 && nc == n) {
		double lo = 0, hi = 1;
		range(c, n, &lo, &hi);
		struct c0_plot pl = { 0, f[n - 1], fmin(0, lo), 1.02, 0, 0, 0, 0, 0 };
		c0_plot_begin(h, &pl, "spatial frequency (1/nm)", "Fourier ring correlation");
		c0_plot_line(h, &pl, f, c, n, "#1f4e8c", 0);
		c0_plot_legend(h, &pl, 0, "#1f4e8c", 0, "FRC of the halves");
		c0_plot_end(h);
		c0_html_add(h, "<figcaption>the halves' agreement, not a resolution");
	} else
		c0_html_add(h, "<p class=\"absent\">No FRC (--frc 0).</p><figcaption>");
	snprintf(p, sizeof p, "support.%d.precision_nm", k);
	double prec = c0_json_num(rep, p, -1);
	c0_html_add(h, "; localisation precision ");
	if (prec >= 0) {
		c0_html_num(h, p, prec);
		c0_html_add(h, " nm (sd per axis)");
	} else
		c0_html_add(h, "unknown");
	c0_html_add(h, "</figcaption></figure>");
	free(f), free(c);
}

void c0_fig_frc(struct c0_html *h, const struct c0_rundir *d)
{
	const cJSON *su = c0_json_at(d->rep, "support");
	if (!cJSON_IsArray(su) || !cJSON_GetArraySize(su)) {
		c0_html_add(h, "<section id=\"frc\"><h2>Halves (FRC, precision)</h2><p class=\"absent\">No support step "
			       "in this run.</p></section>\n");
		return;
	}
	open_section(h, "frc", "Halves (FRC, precision)", "Fourier ring correlation of the emitter variances solved "
		     "from the even and the odd frames (fine grid, Hann window): how far the halves agree per spatial "
		     "frequency. It is no resolution: the halves share the fine pixels the sparse solve picks, and on "
		     "simulated lines its 1/7 crossing does not follow which lines are resolved (guide, section 5). The "
		     "localisation precision comes from the halves' supports.");
	for (int k = 0; k < cJSON_GetArraySize(su); k++)
		frc_one(h, d->rep, k);
	c0_html_add(h, "</div></section>\n");
}
