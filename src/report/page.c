/* report.html as a whole: the output directory loaded, the error map
 * computed, the sections in reading order, then error_qNN.tif and the page
 * written (each atomically; on a failure the files this call wrote are
 * removed, so an error leaves the directory as it was). */
#include "report/html.h"
#include "io/atomic.h"
#include "io/tiff.h"
#include "core/err.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char css[] =
	"body{font:14px/1.45 system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;color:#222;background:#fafafa;"
	"margin:0}main{max-width:1240px;margin:0 auto;padding:18px 28px 40px}"
	"h1{font-size:22px;margin:8px 0 2px}h2{font-size:17px;margin:0 0 6px;border-bottom:1px solid #ddd;padding-bottom:3px}"
	"section{background:#fff;border:1px solid #e2e2e2;border-radius:4px;padding:12px 16px;margin:14px 0}"
	".sub{color:#555;margin:0 0 10px}.what{color:#555;max-width:980px;margin:4px 0 10px}.absent{color:#888;font-style:italic}"
	".panels{display:flex;flex-wrap:wrap;gap:12px;align-items:flex-start}"
	"figure{margin:0}figcaption{font-size:12px;color:#444;max-width:440px;margin-top:3px}"
	".panel figcaption{max-width:184px}.cbar figcaption{max-width:80px}.panel svg{display:block;background:#000}.panel image{image-rendering:pixelated}.cbar svg{background:none}"
	".cbar text{font-size:11px;fill:#333}.bar{fill:#fff;stroke:#000;stroke-width:.6}"
	".barlabel{fill:#fff;font-size:12px;text-anchor:middle;paint-order:stroke;stroke:#000;stroke-width:2px}"
	".plot .grid{stroke:#eee}.plot .frame{fill:none;stroke:#999}.plot .tick{font-size:10.5px;fill:#444}"
	".plot .label{font-size:12px;fill:#222}.plot .marklabel{font-size:11px;fill:#c0392b}"
	"table{border-collapse:collapse;font-size:13px}td,th{border-bottom:1px solid #eee;padding:3px 10px 3px 0;"
	"text-align:left;vertical-align:top}th{color:#555;font-weight:600}"
	"tr.given td:nth-child(3){color:#1f4e8c;font-weight:600}tr.chosen td:nth-child(3){color:#a04000;font-weight:600}"
	"tr.default td:nth-child(3){color:#777}.params td:nth-child(4){color:#555;max-width:560px}"
	".tbar{height:9px;background:#7a93b8}ul.warnings{margin:0;padding-left:20px}"
	"li.warn{color:#8a3b00}li.warn::marker{content:'\\26A0  '}li.note{color:#444}li.ok{color:#1e6b36}"
	"pre.cmd{background:#f3f3f3;border:1px solid #ddd;padding:8px;white-space:pre-wrap;word-break:break-all;font-size:12.5px}"
	"nav a{margin-right:12px;color:#1f4e8c;text-decoration:none}"
	".cols{display:grid;grid-template-columns:repeat(auto-fit,minmax(560px,1fr));gap:0 14px}.cols section{margin:14px 0 0}";

static void header(struct c0_html *h, const struct c0_rundir *d)
{
	const char *cmd = cJSON_GetStringValue(c0_json_at(d->rep, "command")),
		   *when = cJSON_GetStringValue(c0_json_at(d->rep, "created")),
		   *ver = cJSON_GetStringValue(c0_json_at(d->rep, "versions.col0rme"));
	c0_html_add(h, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
		       "<meta name=\"viewport\" content=\"width=device-width\"><title>col0rme ");
	c0_html_escape(h, cmd ? cmd : "");
	c0_html_printf(h, " report</title><style>%s</style></head><body><main>\n<h1>col0rme ", css);
	c0_html_escape(h, cmd ? cmd : "");
	c0_html_add(h, "</h1><p class=\"sub\">");
	c0_html_escape(h, when ? when : "");
	c0_html_add(h, " \u00b7 col0rme ");
	c0_html_escape(h, ver ? ver : "?");
	if (d->n && d->ny)
		c0_html_printf(h, " \u00b7 %d stack%s of %d\u00d7%d pixels of %g nm, fine grid %g nm (\u00d7%d)", d->n,
			       d->n > 1 ? "s" : "", d->nx, d->ny, d->grid.pixel_nm, c0_grid_fine_nm(&d->grid), d->grid.srf);
	c0_html_add(h, "</p><nav><a href=\"#warnings\">warnings</a><a href=\"#mean\">mean</a><a href=\"#render\">render</a>"
		       "<a href=\"#depth\">depth</a><a href=\"#error-map\">error map</a><a href=\"#lambda\">\u03bb</a>"
		       "<a href=\"#drift\">drift</a><a href=\"#bleach\">bleaching</a><a href=\"#frc\">FRC</a>"
		       "<a href=\"#parameters\">parameters</a><a href=\"#timings\">timings</a><a href=\"#command\">command</a></nav>\n");
}

static void page(struct c0_html *h, const struct c0_rundir *d)
{
	header(h, d);
	c0_tab_warnings(h, d);
	c0_fig_mean(h, d);
	c0_fig_render(h, d);
	c0_fig_depth(h, d);
	c0_fig_errmap(h, d);
	c0_html_add(h, "<div class=\"cols\">");
	c0_fig_lambda(h, d);
	c0_fig_frc(h, d);
	c0_fig_drift(h, d);
	c0_fig_bleach(h, d);
	c0_html_add(h, "</div>\n");
	c0_tab_parameters(h, d);
	c0_tab_timings(h, d);
	c0_tab_command(h, d);
	c0_html_add(h, "<p class=\"what\">Written by col0rme from this directory's report.json and TIFFs; "
		       "<code>col0rme report DIR</code> writes it again.</p></main></body></html>\n");
}

static int write_errors(const struct c0_rundir *d, int *written)
{
	for (int q = 0; q < d->n; q++) {
		if (!d->err[q])
			continue;
		char path[4400];
		snprintf(path, sizeof path, "%s/error_q%02d.tif", d->dir, q + 1);
		struct c0_tiff_wopts o = { .width = d->nx, .height = d->ny, .dtype = C0_F32, .pixel_size_nm = d->grid.pixel_nm,
					   .software = "col0rme report: data mean - forward model of the estimate" };
		int st = c0_tiff_save_f32(path, &o, d->err[q]);
		if (st)
			return st;
		written[q] = 1;
	}
	return C0_OK;
}

int c0_report_html(const char *outdir)
{
	if (!outdir || !*outdir)
		return c0_fail(C0_EINVAL, "report: no output directory given");
	struct c0_rundir d;
	int st = c0_rundir_load(&d, outdir);
	if (st)
		return st;
	struct c0_html h = { 0 };
	if (!(st = c0_errmap(&d))) {
		page(&h, &d);
		st = h.st < 0 ? c0_fail(C0_ENOMEM, "report.html: out of memory") : h.st;
	}
	int written[C0_MAX_STACKS] = { 0 };
	if (!st)
		st = write_errors(&d, written);
	char path[4400];
	snprintf(path, sizeof path, "%s/report.html", outdir);
	if (!st)
		st = c0_write_file(path, h.s, h.n);
	for (int q = 0; st && q < d.n; q++)
		if (written[q]) {
			snprintf(path, sizeof path, "%s/error_q%02d.tif", outdir, q + 1);
			remove(path);
		}
	free(h.s);
	c0_rundir_free(&d);
	return st;
}
