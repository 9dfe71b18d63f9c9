#include "stages/depthfit.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAXQ_FIT C0_DEPTH_MAXQ

/* The candidate depths z0 + c step over [z0, z0 + range] (c < nc, at most
 * hmax apart, ends included) and their exponentials Wc[c nq + q] = g_q I0
 * e^{-p_q z}. */
struct cands {
	int nq, nc;
	double z0, step, p[MAXQ_FIT];
	double *Wc, *nrm;   /* nrm[c] = |w_c|^2, the equal weights' norms */
};

static void cands_free(struct cands *c)
{
	free(c->Wc), free(c->nrm);
	c->Wc = c->nrm = NULL;
}

static int cands_init(const struct c0_tirf *t, int nq, const double *angles, const double *gain, double z0, double range,
		      double hmax, struct cands *c)
{
	c->Wc = c->nrm = NULL;
	if (nq < 1 || nq > MAXQ_FIT || !(range > 0) || !(hmax > 0))
		return c0_fail(C0_EINVAL, "depth fit: %d angles, a range of %g nm in steps of %g nm", nq, range, hmax);
	c->nq = nq, c->z0 = z0;
	c->nc = 1 + (int)fmin(4096, ceil(range / hmax));
	c->step = range / (c->nc - 1);
	c->Wc = c0_alloc((size_t)nq * c->nc, sizeof *c->Wc), c->nrm = c0_alloc((size_t)c->nc, sizeof *c->nrm);
	int st = c->Wc && c->nrm ? C0_OK : C0_ENOMEM;
	for (int q = 0; !st && q < nq; q++) {
		if ((st = c0_tirf_p(t, angles[q], &c->p[q])))
			break;
		const double g = c0_tirf_i0(t, angles[q]) * (gain ? gain[q] : 1);
		for (int k = 0; k < c->nc; k++)
			c->Wc[(size_t)k * nq + q] = g * exp(-c->p[q] * (z0 + k * c->step));
	}
	for (int k = 0; !st && k < c->nc; k++)
		for (int q = 0; q < nq; q++)
			c->nrm[k] += c->Wc[(size_t)k * nq + q] * c->Wc[(size_t)k * nq + q];
	if (st)
		cands_free(c);
	return st;
}

/* each candidate's score for projections y under inverse variances iv (NULL:
 * 1): <w, y>^2 / |w|^2 where <w, y> > 0, else 0; the best candidate (-1:
 * none) and its amplitude <w, y> / |w|^2 */
static int scores(const struct cands *c, const double *y, const double *iv, double *score, double *amp)
{
	int best = -1;
	for (int k = 0; k < c->nc; k++) {
		const double *w = c->Wc + (size_t)k * c->nq;
		double s = 0, n = iv ? 0 : c->nrm[k];
		for (int q = 0; q < c->nq; q++)
			if (iv)
				s += w[q] * y[q] * iv[q], n += w[q] * w[q] * iv[q];
			else
				s += w[q] * y[q];
		score[k] = s > 0 ? s * s / n : 0;
		if (score[k] > 0 && (best < 0 || score[k] > score[best]))
			best = k, *amp = s / n;
	}
	return best;
}

/* the best candidate's depth, refined by a parabola through its neighbours */
static float refine(const struct cands *c, const double *score, int best)
{
	double off = 0;
	if (best > 0 && best < c->nc - 1) {
		const double s0 = score[best - 1], s1 = score[best], s2 = score[best + 1], den = s0 - 2 * s1 + s2;
		if (den < 0)
			off = fmin(0.5, fmax(-0.5, 0.5 * (s0 - s2) / den));
	}
	return (float)(c->z0 + (best + off) * c->step);
}

/* pixel p's values into y (0: nothing to fit) */
static int pixel_y(const float *const *y, int nq, size_t p, double *out)
{
	double tot = 0;
	for (int q = 0; q < nq; q++)
		out[q] = y[q][p], tot += out[q];
	return tot > 0;
}

int c0_depth_fit_y(const struct c0_tirf *t, int nq, const double *angles, const double *gain, double z0, double range,
		   const float *const *y, size_t np, const float *var, float *depth)
{
	struct cands c;
	int st = cands_init(t, nq, angles, gain, z0, range, 1, &c), fail = 0;
	if (!st) {
#pragma omp parallel
		{
			double *score = malloc(sizeof *score * (size_t)c.nc), yv[MAXQ_FIT], iv[MAXQ_FIT], amp;
			if (!score)
#pragma omp atomic write
				fail = 1;
#pragma omp for schedule(static)
			for (size_t p = 0; p < np; p++) {
				for (int q = 0; var && q < nq; q++)
					iv[q] = 1 / (double)var[(size_t)q * np + p];
				const int best = score && pixel_y(y, nq, p, yv) ? scores(&c, yv, var ? iv : NULL, score, &amp) : -1;
				depth[p] = best < 0 ? 0 : refine(&c, score, best);
			}
			free(score);
		}
	}
	cands_free(&c);
	return st ? st : fail ? C0_ENOMEM : C0_OK;
}

int c0_depth_fit(const struct c0_tirf *t, int nq, const double *angles, const double *gain, int nz, double z0,
		 double dz, const float *f, size_t np, float *depth)
{
	if (nz < 1)
		return c0_fail(C0_EINVAL, "depth fit: %d bins", nz);
	struct cands c;
	double *W = c0_alloc((size_t)nq * nz, sizeof *W);
	int st = cands_init(t, nq, angles, gain, z0, nz * dz, fmin(1.0, dz / 4), &c);
	if (!st)
		st = W ? c0_tirf_weights(t, nq, angles, gain, nz, z0, dz, W) : C0_ENOMEM;
	int fail = 0;
	if (!st) {
#pragma omp parallel
		{
			double *score = malloc(sizeof *score * (size_t)c.nc), y[MAXQ_FIT], amp;
			if (!score)
#pragma omp atomic write
				fail = 1;
#pragma omp for schedule(static)
			for (size_t p = 0; p < np; p++) {
				double tot = 0;
				for (int q = 0; q < nq; q++)
					y[q] = 0;
				for (int j = 0; j < nz; j++) {
					const double v = f[(size_t)j * np + p];
					tot += v;
					for (int q = 0; q < nq && v != 0; q++)
						y[q] += W[q * nz + j] * v;
				}
				const int best = tot > 0 && score ? scores(&c, y, NULL, score, &amp) : -1;
				depth[p] = best < 0 ? 0 : refine(&c, score, best);
			}
			free(score);
		}
	}
	free(W), cands_free(&c);
	return st ? st : fail ? C0_ENOMEM : C0_OK;
}

/* Pixels per block of the noise fit's sums: the blocks' sums are added in
 * order, so the result is the same on any number of threads. */
#define NOISE_BLOCK 4096

/* One pass's sums over a block of pixels */
struct nsums {
	double m4[MAXQ_FIT], m2[MAXQ_FIT], n[MAXQ_FIT], dm2[MAXQ_FIT], d2[MAXQ_FIT];   /* the random part's regression */
	double rx, xx, r2, pred;                                                          /* the systematic part */
};

/* The residual's expectation through the weighted fit's projector R = I - H,
 * H = J (J' V^-1 J)^-1 J' V^-1, J = [m, -p m] (amplitude, depth): for each q,
 * pred_q = sum_l R_ql^2 vr_l and x_q = sum_l R_ql^2 */
static void project(const struct cands *c, const double *m, const double *iv, const double *vr, double *pred, double *x)
{
	const int nq = c->nq;
	double a = 0, b = 0, d = 0;   /* J' V^-1 J = [a b; b d] */
	for (int q = 0; q < nq; q++)
		a += m[q] * m[q] * iv[q], b -= c->p[q] * m[q] * m[q] * iv[q], d += c->p[q] * c->p[q] * m[q] * m[q] * iv[q];
	const double det = a * d - b * b;
	for (int q = 0; q < nq; q++) {
		pred[q] = x[q] = 0;
		for (int l = 0; l < nq && det > 0; l++) {
			/* J_q G^-1 J_l' with J_q = m_q (1, -p_q) */
			const double h = m[q] * m[l] * (d + b * c->p[l] + b * c->p[q] + a * c->p[q] * c->p[l]) / det * iv[l];
			const double r = (q == l) - h;
			pred[q] += r * r * vr[l], x[q] += r * r;
		}
	}
}

/* Block [p0, p1)'s sums. pass 0: the plain fit's model against d^2 (the
 * random part's regression); pass 1: the fit weighted by vr + sys against
 * its residuals (the systematic part). model: the plain fit's best candidate
 * and amplitude per pixel (pass 0 writes them). */
static void noise_block(const struct cands *c, const float *const *y, const float *const *d, size_t p0, size_t p1, int pass,
			const double *s, const double *cq, double sys, int *best, float *amp, double *score, struct nsums *o)
{
	const int nq = c->nq;
	double yv[MAXQ_FIT], m[MAXQ_FIT], vr[MAXQ_FIT], iv[MAXQ_FIT], pred[MAXQ_FIT], x[MAXQ_FIT], a;
	memset(o, 0, sizeof *o);
	for (size_t p = p0; p < p1; p++) {
		if (pass == 0) {
			best[p] = pixel_y(y, nq, p, yv) ? scores(c, yv, NULL, score, &a) : -1;
			amp[p] = best[p] < 0 ? 0 : (float)a;
		}
		if (best[p] < 0)
			continue;
		for (int q = 0; q < nq; q++) {
			m[q] = amp[p] * c->Wc[(size_t)best[p] * nq + q];
			vr[q] = s[q] * m[q] * m[q] + cq[q];
		}
		if (pass == 0) {
			for (int q = 0; q < nq; q++) {
				const double d2 = (double)d[q][p] * d[q][p];
				o->m4[q] += m[q] * m[q] * m[q] * m[q], o->m2[q] += m[q] * m[q], o->n[q] += 1;
				o->dm2[q] += d2 * m[q] * m[q], o->d2[q] += d2;
			}
			continue;
		}
		pixel_y(y, nq, p, yv);
		for (int q = 0; q < nq; q++)
			iv[q] = 1 / (vr[q] + sys);
		const int k = scores(c, yv, iv, score, &a);
		if (k < 0)
			continue;
		for (int q = 0; q < nq; q++)
			m[q] = a * c->Wc[(size_t)k * nq + q];
		project(c, m, iv, vr, pred, x);
		for (int q = 0; q < nq; q++) {
			const double r2 = (yv[q] - m[q]) * (yv[q] - m[q]);
			o->rx += (r2 - pred[q]) * x[q], o->xx += x[q] * x[q], o->r2 += r2, o->pred += pred[q];
		}
	}
}

/* The blocks' sums, in block order */
static int noise_pass(const struct cands *c, const float *const *y, const float *const *d, size_t np, int pass,
		      const double *s, const double *cq, double sys, int *best, float *amp, struct nsums *tot)
{
	const size_t nb = (np + NOISE_BLOCK - 1) / NOISE_BLOCK;
	struct nsums *b = c0_alloc(nb ? nb : 1, sizeof *b);
	int fail = !b;
#pragma omp parallel if (nb > 1)
	{
		double *score = malloc(sizeof *score * (size_t)c->nc);
		if (!score)
#pragma omp atomic write
			fail = 1;
#pragma omp for schedule(dynamic, 1)
		for (size_t k = 0; k < (b && score ? nb : 0); k++)
			noise_block(c, y, d, k * NOISE_BLOCK, k + 1 == nb ? np : (k + 1) * NOISE_BLOCK, pass, s, cq, sys, best, amp,
				    score, &b[k]);
		free(score);
	}
	memset(tot, 0, sizeof *tot);
	for (size_t k = 0; !fail && k < nb; k++) {
		for (int q = 0; q < c->nq; q++)
			tot->m4[q] += b[k].m4[q], tot->m2[q] += b[k].m2[q], tot->n[q] += b[k].n[q], tot->dm2[q] += b[k].dm2[q],
				tot->d2[q] += b[k].d2[q];
		tot->rx += b[k].rx, tot->xx += b[k].xx, tot->r2 += b[k].r2, tot->pred += b[k].pred;
	}
	free(b);
	return fail ? C0_ENOMEM : C0_OK;
}

/* d^2 ~ s m^2 + c by least squares with s, c >= 0 */
static void nnls2(double m4, double m2, double n, double dm2, double d2, double *s, double *c)
{
	const double det = m4 * n - m2 * m2;
	*s = det > 0 ? (dm2 * n - m2 * d2) / det : -1;
	*c = det > 0 ? (m4 * d2 - m2 * dm2) / det : -1;
	if (*s >= 0 && *c >= 0)
		return;
	const double s1 = m4 > 0 ? fmax(0, dm2 / m4) : 0, c1 = n > 0 ? d2 / n : 0;   /* c = 0, or s = 0 */
	const double e1 = s1 * s1 * m4 - 2 * s1 * dm2, e2 = c1 * c1 * n - 2 * c1 * d2;   /* the errors less sum d^4 */
	*s = e1 <= e2 ? s1 : 0, *c = e1 <= e2 ? 0 : c1;
}

int c0_depth_noise(const struct c0_tirf *t, int nq, const double *angles, const double *gain, double z0, double range,
		   const float *const *y, const float *const *d, size_t np, float *var, struct c0_depth_noise *out)
{
	struct cands c;
	memset(out, 0, sizeof *out);
	int st = cands_init(t, nq, angles, gain, z0, range, 1, &c);
	int *best = st ? NULL : c0_alloc(np ? np : 1, sizeof *best);
	float *amp = st ? NULL : c0_alloc(np ? np : 1, sizeof *amp);
	if (!st && (!best || !amp))
		st = C0_ENOMEM;
	double s[MAXQ_FIT] = { 0 }, cq[MAXQ_FIT] = { 0 }, sys = 0;
	struct nsums tot;
	if (!st)
		st = noise_pass(&c, y, d, np, 0, s, cq, 0, best, amp, &tot);
	for (int q = 0; !st && q < nq; q++) {
		nnls2(tot.m4[q], tot.m2[q], tot.n[q], tot.dm2[q], tot.d2[q], &s[q], &cq[q]);
		out->rel_sd[q] = sqrt(s[q]);
		out->abs_share[q] = s[q] * tot.m2[q] > 0 ? cq[q] * tot.n[q] / (s[q] * tot.m2[q]) : INFINITY;
	}
	out->nq = nq, out->pixels = st ? 0 : (size_t)tot.n[0];
	for (int it = 0; !st && it < 3; it++) {   /* sys settles in 2-3 steps (measured with 11cec5f's bench/depth_weights.py) */
		st = noise_pass(&c, y, d, np, 1, s, cq, sys, best, amp, &tot);
		sys = tot.xx > 0 ? fmax(0, tot.rx / tot.xx) : 0;
		out->resid_ratio = tot.pred > 0 ? tot.r2 / tot.pred : 0;
	}
	out->sys_var = sys;
	for (size_t p = 0; !st && p < np; p++)
		for (int q = 0; q < nq; q++) {
			const double m = best[p] < 0 ? 0 : amp[p] * c.Wc[(size_t)best[p] * nq + q];
			var[(size_t)q * np + p] = (float)fmax(s[q] * m * m + cq[q] + sys, 1e-30);
		}
	free(best), free(amp), cands_free(&c);
	return st;
}
