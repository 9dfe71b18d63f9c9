/* Line plots as inline SVG: axes with round ticks (decades on a log axis),
 * curves, marked points and a legend, in data units. */
#include "report/html.h"

#include <math.h>
#include <stdio.h>

#define ML 62   /* margins: left, right, top, bottom */
#define MR 14
#define MT 12
#define MB 42

static double tx(const struct c0_plot *p, double x)
{
	double a = p->logx ? log10(p->x0) : p->x0, b = p->logx ? log10(p->x1) : p->x1, v = p->logx ? log10(x) : x;
	return ML + (v - a) / (b - a) * (p->w - ML - MR);
}

static double ty(const struct c0_plot *p, double y)
{
	double a = p->logy ? log10(p->y0) : p->y0, b = p->logy ? log10(p->y1) : p->y1, v = p->logy ? log10(y) : y;
	return p->h - MB - (v - a) / (b - a) * (p->h - MT - MB);
}

/* a round step giving about 5 ticks over [a, b] */
static double step_of(double a, double b)
{
	double raw = (b - a) / 5, m = pow(10, floor(log10(raw))), f = raw / m;
	return m * (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10);
}

static void ticks(struct c0_html *h, const struct c0_plot *p, int yaxis)
{
	double a = yaxis ? p->y0 : p->x0, b = yaxis ? p->y1 : p->x1;
	int lg = yaxis ? p->logy : p->logx;
	double v = lg ? pow(10, ceil(log10(a) - 1e-9)) : ceil(a / step_of(a, b) - 1e-9) * step_of(a, b);
	for (int k = 0; k < 40 && v <= b * (1 + 1e-9) + (lg ? 0 : 1e-12); k++) {
		double pos = yaxis ? ty(p, v) : tx(p, v);
		char lab[32];
		snprintf(lab, sizeof lab, lg ? "%g" : "%.4g", fabs(v) < 1e-12 * (b - a) ? 0 : v);
		if (yaxis)
			c0_html_printf(h, "<line class=\"grid\" x1=\"%d\" x2=\"%d\" y1=\"%.1f\" y2=\"%.1f\"/>"
				       "<text class=\"tick\" x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%s</text>", ML, p->w - MR, pos, pos,
				       ML - 5, pos + 4, lab);
		else
			c0_html_printf(h, "<line class=\"grid\" x1=\"%.1f\" x2=\"%.1f\" y1=\"%d\" y2=\"%d\"/>"
				       "<text class=\"tick\" x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%s</text>", pos, pos, MT,
				       p->h - MB, pos, p->h - MB + 15, lab);
		v = lg ? v * 10 : v + step_of(a, b);
	}
}

void c0_plot_begin(struct c0_html *h, struct c0_plot *p, const char *xlabel, const char *ylabel)
{
	if (!p->w)
		p->w = 440, p->h = 270;
	if (!(p->x1 > p->x0))
		p->x1 = p->x0 + 1;
	if (!(p->y1 > p->y0))
		p->y1 = p->y0 + 1;
	c0_html_printf(h, "<svg class=\"plot\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" role=\"img\">", p->w, p->h, p->w,
		       p->h);
	ticks(h, p, 0);
	ticks(h, p, 1);
	c0_html_printf(h, "<rect class=\"frame\" x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\"/>", ML, MT, p->w - ML - MR,
		       p->h - MT - MB);
	c0_html_printf(h, "<text class=\"label\" x=\"%d\" y=\"%d\" text-anchor=\"middle\">", (ML + p->w - MR) / 2, p->h - 6);
	c0_html_escape(h, xlabel);
	c0_html_printf(h, "</text><text class=\"label\" transform=\"translate(14 %d) rotate(-90)\" text-anchor=\"middle\">",
		       (MT + p->h - MB) / 2);
	c0_html_escape(h, ylabel);
	c0_html_add(h, "</text>");
}

static int inside(const struct c0_plot *p, double x, double y)
{
	return isfinite(x) && isfinite(y) && (!p->logx || x > 0) && (!p->logy || y > 0);
}

void c0_plot_line(struct c0_html *h, const struct c0_plot *p, const double *x, const double *y, int n, const char *colour,
		  int dashed)
{
	c0_html_printf(h, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.6\"%s points=\"", colour,
		       dashed ? " stroke-dasharray=\"5 3\"" : "");
	for (int i = 0; i < n; i++)
		if (inside(p, x[i], y[i]))   /* clipped to the frame */
			c0_html_printf(h, "%.1f,%.1f ", fmax(ML, fmin(p->w - MR, tx(p, x[i]))), fmax(MT, fmin(p->h - MB, ty(p, y[i]))));
	c0_html_add(h, "\"/>");
}

void c0_plot_mark(struct c0_html *h, const struct c0_plot *p, double x, double y, const char *colour, const char *label)
{
	if (!inside(p, x, y))
		return;
	double X = tx(p, x), Y = ty(p, y);
	c0_html_printf(h, "<line x1=\"%.1f\" x2=\"%.1f\" y1=\"%d\" y2=\"%d\" stroke=\"%s\" stroke-dasharray=\"2 3\"/>"
		       "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4.5\" fill=\"%s\" stroke=\"#fff\"/>", X, X, MT, p->h - MB, colour, X, Y,
		       colour);
	if (label) {
		int right = X > (ML + p->w - MR) / 2.0;
		c0_html_printf(h, "<text class=\"marklabel\" x=\"%.1f\" y=\"%.1f\" text-anchor=\"%s\">", X + (right ? -7 : 7),
			       fmax(MT + 10, Y - 8), right ? "end" : "start");
		c0_html_escape(h, label);
		c0_html_add(h, "</text>");
	}
}

void c0_plot_legend(struct c0_html *h, const struct c0_plot *p, int row, const char *colour, int dashed, const char *text)
{
	double x = p->legend_low ? ML + 10 : p->w - MR - 150, y = p->legend_low ? p->h - MB - 10 - 15 * row : MT + 14 + 15 * row;
	c0_html_printf(h, "<line x1=\"%.0f\" x2=\"%.0f\" y1=\"%.0f\" y2=\"%.0f\" stroke=\"%s\" stroke-width=\"2\"%s/>"
		       "<text class=\"tick\" x=\"%.0f\" y=\"%.0f\">", x, x + 18, y - 4, y - 4, colour,
		       dashed ? " stroke-dasharray=\"5 3\"" : "", x + 23, y);
	c0_html_escape(h, text);
	c0_html_add(h, "</text>");
}

void c0_plot_end(struct c0_html *h)
{
	c0_html_add(h, "</svg>");
}
