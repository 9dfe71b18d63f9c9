/* The render step, and its planes: made when written and when the
 * library's caller first asks for them (c0_result_render). */
#include "app/render.h"
#include "app/steps.h"
#include "app/report_json.h"
#include "ops/splat.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>

/* Rows of the render made at a time: a band of the fine grid, not n planes
 * of it (1.3 GB for 5 stacks at 2048 x 2048 camera pixels). */
#define C0_RENDER_BAND 256

/* rows y0..y1 of plane q of the render into out; xb: room for the rows of
 * x within the radius of the band */
static int render_rows(const struct c0_result *r, int q, double sigma, int y0, int y1, float *xb, float *out)
{
	const int rr = c0_splat_radius(sigma), t0 = y0 - rr < 0 ? 0 : y0 - rr, t1 = y1 + rr > r->Ly ? r->Ly : y1 + rr;
	c0_result_x_rows(r, q, t0, t1, xb);
	return c0_splat_rows(xb, t0, r->Ly, r->Lx, sigma, y0, y1, out);
}

static float *render_xbuf(const struct c0_result *r, double sigma)
{
	return c0_alloc((size_t)(C0_RENDER_BAND + 2 * c0_splat_radius(sigma)) * r->Lx, sizeof(float));
}

int c0_render_plane(const struct c0_result *r, int q, float *plane)
{
	const double sigma = r->render_sd_nm / (r->pixel_nm / r->srf);
	float *xb = render_xbuf(r, sigma);
	int st = xb ? C0_OK : C0_ENOMEM;
	for (int y0 = 0; !st && y0 < r->Ly; y0 += C0_RENDER_BAND)
		st = render_rows(r, q, sigma, y0, y0 + C0_RENDER_BAND < r->Ly ? y0 + C0_RENDER_BAND : r->Ly, xb,
				 plane + (size_t)y0 * r->Lx);
	free(xb);
	return st;
}

/* The render's planes are made when written (and when the library's caller
 * asks for them); the step fixes their Gaussian and their display range. */
int c0_step_render(struct c0_result *r)
{
	const struct c0_step_clock t = c0_step_begin("render");
	const double fine = r->pixel_nm / r->srf;
	double prec = -1;
	for (int k = 0; r->sres && k < r->nsup; k++)
		prec = fmax(prec, r->sres[k].precision_nm);
	const double sd = fmax(prec, 0.5 * fine);
	float *band = c0_alloc((size_t)C0_RENDER_BAND * r->Lx, sizeof *band), *xb = render_xbuf(r, sd / fine);
	float lo = INFINITY, hi = -INFINITY;
	int st = band && xb ? C0_OK : C0_ENOMEM;
	for (int q = 0; !st && q < r->n; q++)
		for (int y0 = 0; !st && y0 < r->Ly; y0 += C0_RENDER_BAND) {
			const int y1 = y0 + C0_RENDER_BAND < r->Ly ? y0 + C0_RENDER_BAND : r->Ly;
			st = render_rows(r, q, sd / fine, y0, y1, xb, band);
			for (size_t i = 0; !st && i < (size_t)(y1 - y0) * r->Lx; i++) {
				if (band[i] < lo) lo = band[i];
				if (band[i] > hi) hi = band[i];
			}
		}
	free(band), free(xb);
	if (st)
		return st;
	r->render_sd_nm = sd, r->render_lo = lo, r->render_hi = hi;
	c0_report_render(r->rep, sd, prec, fine);
	c0_step_end(r, &t);
	return C0_OK;
}

const float *c0_result_render(const struct c0_result *r, int q, int *h, int *w)
{
	if (!(r->render_sd_nm > 0) || q < 0 || q >= r->n)
		return NULL;
	if (h)
		*h = r->Ly;
	if (w)
		*w = r->Lx;
	const size_t L = (size_t)r->Ly * r->Lx;
	struct c0_result *m = (struct c0_result *)r;   /* the cache is not const to its callers */
	if (!m->render && (m->render = c0_alloc(L * (size_t)r->n, sizeof *m->render)))
		for (int k = 0; k < r->n; k++)
			if (c0_render_plane(r, k, m->render + k * L)) {
				free(m->render), m->render = NULL;
				break;
			}
	return m->render ? m->render + q * L : NULL;
}
