/* The page's text parts: the warnings box, the parameter table (given on
 * the command line, a fixed default, or chosen from the data by a rule),
 * the timings and the command that reproduces the run. */
#include "report/html.h"
#include "core/order.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- warnings ---- */

struct notes { int n; };

static void warn(struct c0_html *h, struct notes *w, int serious, const char *line)
{
	c0_html_printf(h, "<li class=\"%s\">", serious ? "warn" : "note");
	c0_html_escape(h, line);
	c0_html_add(h, "</li>");
	w->n++;
}

/* the --angles of the command line, else the MA-TIRF's */
static int angles(const cJSON *rep, double *a)
{
	const cJSON *argv = c0_json_at(rep, "argv");
	int n = 0;
	for (int i = 0; i + 1 < cJSON_GetArraySize(argv); i++) {
		const cJSON *o = cJSON_GetArrayItem(argv, i), *v = cJSON_GetArrayItem(argv, i + 1);
		if (cJSON_IsString(o) && cJSON_IsString(v) && !strcmp(o->valuestring, "--angles"))
			for (char *p = v->valuestring, *e; n < C0_MAX_STACKS && *p; p = *e ? e + 1 : e) {
				a[n] = strtod(p, &e);
				if (e == p)
					return n;
				n++;
			}
	}
	const cJSON *m = c0_json_at(rep, "matirf.angles_deg");
	for (int i = 0; !n && i < cJSON_GetArraySize(m) && i < C0_MAX_STACKS; i++)
		a[i] = cJSON_GetArrayItem(m, i)->valuedouble, n = i + 1;
	return n;
}

static void warn_angles(struct c0_html *h, const struct c0_rundir *d, struct notes *w)
{
	double a[C0_MAX_STACKS], crit = c0_json_num(d->rep, "matirf.critical_angle_deg", NAN);
	int n = angles(d->rep, a);
	char line[512];
	for (int q = 0; q < n && isfinite(crit); q++) {
		if (a[q] <= crit) {
			snprintf(line, sizeof line, "Stack q%d at %.2f\u00b0 is at or below the critical angle (%.2f\u00b0): epi "
				 "illumination, no depth information (it joins the support only).", q + 1, a[q], crit);
			warn(h, w, 1, line);
		} else if (a[q] < crit + 1) {
			snprintf(line, sizeof line, "Stack q%d at %.2f\u00b0 is within 1\u00b0 of the critical angle (%.2f\u00b0): its "
				 "penetration depth depends steeply on the angle's calibration.", q + 1, a[q], crit);
			warn(h, w, 0, line);
		}
	}
}

static void warn_solves(struct c0_html *h, const struct c0_rundir *d, struct notes *w)
{
	const cJSON *su = c0_json_at(d->rep, "support");
	double cap = c0_json_num(d->rep, "support_parameters.max_iterations", 0), tol = c0_json_num(d->rep, "support_parameters.tol", 0);
	char line[768];
	for (int k = 0; k < cJSON_GetArraySize(su); k++) {
		const cJSON *s = cJSON_GetArrayItem(su, k);
		const char *name = cJSON_GetStringValue(c0_json_at(s, "stack")), *sl = name ? strrchr(name, '/') : NULL;
		name = sl ? sl + 1 : name;
		double it = c0_json_num(s, "iterations", 0);
		if (!cJSON_IsFalse(c0_json_at(s, "converged")) || !(cap > 0 && it >= cap))
			continue;
		if (tol > 0)
			snprintf(line, sizeof line, "Support solve of %s stopped at its iteration cap (%.0f) without converging.",
				 name ? name : "?", it);
		else
			snprintf(line, sizeof line, "Support solve of %s ran to its iteration cap (%.0f): by design with FISTA on "
				 "l1 (tol 0: the capped iterate is the estimator).", name ? name : "?", it);
		warn(h, w, tol > 0, line);
	}
	const cJSON *in = c0_json_at(d->rep, "intensity");
	for (int q = 0; q < cJSON_GetArraySize(in); q++) {
		const char *dp = cJSON_GetStringValue(c0_json_at(cJSON_GetArrayItem(in, q), "discrepancy"));
		if (dp && strcmp(dp, "met") && strcmp(dp, "fixed mu")) {
			snprintf(line, sizeof line, "Intensity of q%d: discrepancy principle %s", q + 1, dp);
			warn(h, w, 1, line);
		}
	}
	static const char *const vols[] = { "matirf", "baseline_matirf" };
	for (int v = 0; v < 2; v++) {
		const cJSON *m = c0_json_at(d->rep, vols[v]);
		if (m && cJSON_IsFalse(c0_json_at(m, "converged"))) {
			snprintf(line, sizeof line, "The %s solve stopped after %.0f iterations without converging (final "
				 "relative change %.2g).", v ? "baseline MA-TIRF" : "MA-TIRF", c0_json_num(m, "iterations", 0),
				 c0_json_num(m, "final_relative_change", NAN));
			warn(h, w, 1, line);
		}
	}
}

/* pixels with signal whose depth is in the deepest bin: the z range clips them */
static void warn_pixels(struct c0_html *h, const struct c0_rundir *d, struct notes *w)
{
	char line[512];
	const cJSON *z = c0_json_at(d->rep, "z_nm");
	if (d->vol.depth && cJSON_GetArraySize(z) > 1) {
		const size_t L = (size_t)d->vol.ny * d->vol.nx;
		double top = c0_quantile(d->vol.total, L, 0.995), dz = (d->z1 - d->z0) / cJSON_GetArraySize(z);
		size_t lit = 0, deep = 0;
		for (size_t i = 0; i < L; i++)
			if (d->vol.total[i] > 0.05 * top) {
				lit++;
				deep += d->vol.depth[i] >= d->z1 - dz;
			}
		if (lit && deep > 0.05 * lit) {
			snprintf(line, sizeof line, "%.1f %% of the pixels with signal have their depth in the deepest bin "
				 "(%g nm and below): the depth range clips them (--z-range).", 100.0 * deep / lit, d->z1 - dz);
			warn(h, w, 1, line);
		}
	}
	const char *g = cJSON_GetStringValue(c0_json_at(d->rep, "support_parameters.pixel_guard"));
	if (g && !strcmp(g, "on")) {
		snprintf(line, sizeof line, "Pixel guard on: each pixel's temporal variance was clipped to %.2f of what its "
			 "neighbours' covariances allow, against pixels with noise of their own (report.json does not count the "
			 "pixels it changed).", c0_json_num(d->rep, "support_parameters.pixel_guard_ratio", NAN));
		warn(h, w, 0, line);
	}
	for (int q = 0; q < d->n; q++)
		if (d->err[q] && d->es[q].rsp < 0.9) {
			snprintf(line, sizeof line, "Error map of q%d: RSP %.3f, the model explains the data's mean image poorly.",
				 q + 1, d->es[q].rsp);
			warn(h, w, 1, line);
		}
}

static void warn_drift(struct c0_html *h, const struct c0_rundir *d, struct notes *w)
{
	double mx = c0_json_num(d->rep, "drift.max_nm", 0), px = d->grid.pixel_nm;
	int side = d->ny < d->nx ? d->ny : d->nx;
	if (!(mx > 0 && px > 0 && side > 0))
		return;
	double limit = side / 4.0 * px;   /* stages/drift.h: beyond a quarter of the field it is refused */
	char line[512];
	if (mx > 0.5 * limit) {
		snprintf(line, sizeof line, "Drift reached %.0f nm, more than half of the %.0f nm the estimate accepts (a "
			 "quarter of the field): check drift.png.", mx, limit);
		warn(h, w, 1, line);
	}
}

void c0_tab_warnings(struct c0_html *h, const struct c0_rundir *d)
{
	struct notes w = { 0 };
	c0_html_add(h, "<section id=\"warnings\"><h2>Warnings and notes</h2><ul class=\"warnings\">");
	warn_angles(h, d, &w);
	warn_solves(h, d, &w);
	warn_pixels(h, d, &w);
	warn_drift(h, d, &w);
	if (!w.n)
		c0_html_add(h, "<li class=\"ok\">Nothing to report: every solve converged or stopped by design, no angle near "
			       "the critical one, drift well within range.</li>");
	c0_html_add(h, "</ul></section>\n");
}

/* ---- parameters ---- */

/* One row: the value at path (first of "a|b" that exists; %d: each stack),
 * the flags that give it, and the rule that chose it when none was given
 * (NULL: a fixed default). */
static const struct prow {
	const char *label, *path, *flags, *rule;
} prows[] = {
	{ "camera pixel size (nm)", "parameters.pixel_size_nm|support_parameters.pixel_size_nm", "--pixel-size", "the stacks' TIFF calibration" },
	{ "PSF FWHM (nm)", "parameters.fwhm_nm|support_parameters.fwhm_nm", "--fwhm|--psf|--emission|--na", "0.51 emission / NA" },
	{ "super-resolution factor", "parameters.srf|support_parameters.srf", "--srf", NULL },
	{ "support stacks", "parameters.support_stacks", "--support-angles", "the smallest angle" },
	{ "support penalty", "support_parameters.penalty", "--penalty", NULL },
	{ "\u03bb / \u03bb_max, %s", "support.%d.lambda_relative", "--lambda", "automatic: from the correlation image and the noise of the frame halves (\u03bb criterion)" },
	{ "support iteration cap", "support_parameters.max_iterations", "--iterations", NULL },
	{ "pixel guard", "support_parameters.pixel_guard", "--pixel-guard", NULL },
	{ "background model", "intensity_parameters.background", "--background", NULL },
	{ "background smoothness \u03b2", "intensity_parameters.beta", "--beta", NULL },
	{ "discrepancy factor \u03bd", "intensity_parameters.nu", "--nu", NULL },
	{ "intensity smoothness \u03bc, %s", "intensity.%d.mu", "--mu", "discrepancy principle (relative): the largest \u03bc whose residual exceeds the model's floor by no more than the noise explains" },
	{ "smoothness graph radius (fine px)", "intensity_parameters.graph_radius_px", "--graph-radius", NULL },
	{ "smoothness along the structure (power)", "intensity_parameters.graph_orient", "--graph-orient", NULL },
	{ "depth pooling window (nm)", "parameters.depth_pool_nm", "--depth-pool", "1.75 FWHM" },
	{ "depth pooling range (nm)", "parameters.depth_pool_range_nm", "--depth-pool-range", NULL },
	{ "depth fit: frame halves' block (frames)", "matirf.depth_weights.block_frames", "--depth-noise-block", NULL },
	{ "depth fit: the angles' weights", "matirf.depth_weights.rule", "--depth-noise-block",
	  "noise of the frame halves where it explains the fit's residuals (at most 1.5 times their expectation), else equal" },
	{ "bleaching correction", "bleaching.correction", "--bleach|--bleach-factors", NULL },
	{ "bleaching rate per frame", "bleaching.rate_per_frame", "--bleach-factors", "fitted to the slopes of the stacks' frame sums, at least 0" },
	{ "acquisition", "bleaching.acquisition", "--acquisition", NULL },
	{ "incidence angles (\u00b0)", "matirf.angles_deg", "--angles", NULL },
	{ "n glass", "matirf.n_glass", "--n-glass", NULL },
	{ "n sample", "matirf.n_sample", "--n-sample", NULL },
	{ "excitation wavelength (nm)", "matirf.wavelength_nm", "--wavelength", NULL },
	{ "s-polarised share", "matirf.s_fraction", "--s-fraction", NULL },
	{ "depth bin centres (nm)", "z_nm", "--z-range", NULL },
	{ "MA-TIRF regulariser", "matirf.regulariser", "--reg", NULL },
	{ "MA-TIRF \u03ba", "matirf.kappa", "--kappa", NULL },
	{ "MA-TIRF sparsity", "matirf.sparsity", "--sparsity", NULL },
	{ "MA-TIRF axial weight", "matirf.axial_weight", "--axial-weight", NULL },
	{ "MA-TIRF solver", "matirf.solver", "--matirf-solver", NULL },
};

/* the first of flags ("--a|--b") on the command line, or NULL */
static const char *given(const cJSON *rep, const char *flags)
{
	const cJSON *argv = c0_json_at(rep, "argv");
	for (int i = 0; i < cJSON_GetArraySize(argv); i++) {
		const char *a = cJSON_GetStringValue(cJSON_GetArrayItem(argv, i));
		for (const char *f = flags; a && *f;) {
			size_t k = strcspn(f, "|");
			if (!strncmp(a, f, k) && (a[k] == 0 || a[k] == '='))
				return a;
			f += k + (f[k] == '|');
		}
	}
	return NULL;
}

/* a value: numbers and strings tagged with their path; long arrays as first ... last */
static void value(struct c0_html *h, const cJSON *v, const char *path)
{
	char p[160];
	if (cJSON_IsNumber(v))
		c0_html_num(h, path, v->valuedouble);
	else if (cJSON_IsString(v)) {
		c0_html_printf(h, "<span class=\"str\" data-json=\"%s\">", path);
		c0_html_escape(h, v->valuestring);
		c0_html_add(h, "</span>");
	} else if (cJSON_IsBool(v))
		c0_html_add(h, cJSON_IsTrue(v) ? "yes" : "no");
	else if (cJSON_IsArray(v)) {
		int n = cJSON_GetArraySize(v);
		for (int i = 0; i < n; i++) {
			if (n > 8 && i == 2) {
				c0_html_printf(h, " \u2026 (%d values) \u2026 ", n);
				i = n - 2;
			} else if (i)
				c0_html_add(h, ", ");
			snprintf(p, sizeof p, "%s.%d", path, i);
			value(h, cJSON_GetArrayItem(v, i), p);
		}
	}
}

static void prow_out(struct c0_html *h, const cJSON *rep, const struct prow *r, const char *path, const char *label)
{
	const char *g = given(rep, r->flags);
	const char *how = g ? "given" : r->rule ? "chosen" : "default";
	c0_html_printf(h, "<tr class=\"%s\"><td>", how);
	c0_html_escape(h, label);
	c0_html_add(h, "</td><td>");
	value(h, c0_json_at(rep, path), path);
	c0_html_printf(h, "</td><td>%s</td><td>", how);
	if (g) {
		char flag[64];
		snprintf(flag, sizeof flag, "%.*s", (int)strcspn(g, "="), g);
		c0_html_add(h, "on the command line (");
		c0_html_escape(h, flag);
		c0_html_add(h, ")");
	} else
		c0_html_escape(h, r->rule ? r->rule : "the documented default");
	c0_html_add(h, "</td></tr>");
}

void c0_tab_parameters(struct c0_html *h, const struct c0_rundir *d)
{
	c0_html_add(h, "<section id=\"parameters\"><h2>Parameters</h2><p class=\"what\">Each value the run used: given on "
		       "the command line, a fixed default, or chosen from the data by the rule shown.</p>"
		       "<table class=\"params\"><tr><th>parameter</th><th>value</th><th></th><th>source</th></tr>");
	for (size_t i = 0; i < sizeof prows / sizeof *prows; i++) {
		const struct prow *r = &prows[i];
		char path[160], label[160];
		if (strstr(r->path, "%d")) {   /* one row per stack */
			const char *sec = r->path[0] == 's' ? "support" : "intensity";
			const cJSON *a = c0_json_at(d->rep, sec);
			for (int k = 0; k < cJSON_GetArraySize(a); k++) {
				const char *st = cJSON_GetStringValue(c0_json_at(cJSON_GetArrayItem(a, k), "stack")), *sl = st ? strrchr(st, '/') : NULL;
				snprintf(path, sizeof path, r->path, k);
				snprintf(label, sizeof label, r->label, sl ? sl + 1 : st ? st : "?");
				prow_out(h, d->rep, r, path, label);
			}
			continue;
		}
		size_t k = strcspn(r->path, "|");
		snprintf(path, sizeof path, "%.*s", (int)k, r->path);
		if (!c0_json_at(d->rep, path) && r->path[k])
			snprintf(path, sizeof path, "%s", r->path + k + 1);
		if (c0_json_at(d->rep, path))
			prow_out(h, d->rep, r, path, r->label);
	}
	c0_html_add(h, "</table></section>\n");
}

/* ---- timings and command ---- */

void c0_tab_timings(struct c0_html *h, const struct c0_rundir *d)
{
	const cJSON *t = c0_json_at(d->rep, "timings_s"), *e;
	const int mem = c0_json_at(d->rep, "peak_rss_mb") != NULL;   /* runs before it had none */
	double total = 0, mx = 0;
	cJSON_ArrayForEach(e, t)
		if (cJSON_IsNumber(e))
			total += e->valuedouble, mx = fmax(mx, e->valuedouble);
	c0_html_printf(h, "<section id=\"timings\"><h2>Timings</h2><table class=\"timings\"><tr><th>stage</th><th>seconds</th>"
		       "%s<th></th></tr>", mem ? "<th>peak memory (MB)</th><th>its rise (MB)</th>" : "");
	cJSON_ArrayForEach(e, t) {
		if (!cJSON_IsNumber(e))
			continue;
		char p[160];
		snprintf(p, sizeof p, "timings_s.%s", e->string);
		c0_html_add(h, "<tr><td>");
		c0_html_escape(h, e->string);
		c0_html_add(h, "</td><td>");
		c0_html_num(h, p, e->valuedouble);
		for (int k = 0; mem && k < 2; k++) {
			snprintf(p, sizeof p, "%s.%s", k ? "rss_rise_mb" : "peak_rss_mb", e->string);
			c0_html_add(h, "</td><td>");
			if (c0_json_at(d->rep, p))
				c0_html_num(h, p, c0_json_num(d->rep, p, NAN));
		}
		c0_html_printf(h, "</td><td><div class=\"tbar\" style=\"width:%.0fpx\"></div></td></tr>",
			       mx > 0 ? 300 * e->valuedouble / mx : 0);
	}
	c0_html_printf(h, "<tr><td><b>total</b></td><td>%.4g</td>%s<td></td></tr></table><p class=\"what\">Wall-clock "
		       "seconds per stage, on ", total, mem ? "<td></td><td></td>" : "");
	c0_html_num(h, "threads", c0_json_num(d->rep, "threads", NAN));
	c0_html_add(h, mem ? " threads; the process's peak resident memory after each stage, and how much the stage raised "
			     "it (0: it stayed below an earlier stage's peak).</p></section>\n"
			   : " threads.</p></section>\n");
}

/* a shell word, quoted when it needs to be */
static void shell_word(struct c0_html *h, const char *a)
{
	if (*a && strspn(a, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./,=:+@%") == strlen(a)) {
		c0_html_escape(h, a);
		return;
	}
	c0_html_add(h, "'");
	for (const char *p = a; *p; p++) {
		char c[2] = { *p, 0 };
		c0_html_escape(h, *p == '\'' ? "'\\''" : c);
	}
	c0_html_add(h, "'");
}

void c0_tab_command(struct c0_html *h, const struct c0_rundir *d)
{
	const cJSON *argv = c0_json_at(d->rep, "argv");
	c0_html_add(h, "<section id=\"command\"><h2>Command</h2>");
	if (cJSON_GetArraySize(argv) < 1) {
		c0_html_add(h, "<p class=\"absent\">Made through the library or Python: report.json holds no command line; "
			       "the parameter table above has every value.</p></section>\n");
		return;
	}
	c0_html_add(h, "<p class=\"what\">This reproduces the run (from the same working directory, with the same "
		       "version):</p><pre class=\"cmd\" data-argv=\"1\">col0rme");
	for (int i = 0; i < cJSON_GetArraySize(argv); i++) {
		const char *a = cJSON_GetStringValue(cJSON_GetArrayItem(argv, i));
		c0_html_add(h, " ");
		shell_word(h, a ? a : "");
	}
	c0_html_add(h, "</pre></section>\n");
}
