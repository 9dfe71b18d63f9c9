#include "optics/tirf.h"
#include "core/c0math.h"
#include "core/err.h"

#include <math.h>

static double rad(double deg) { return deg * C0_PI / 180; }

int c0_tirf_check(const struct c0_tirf *t)
{
	if (!(t->n_glass > 0 && isfinite(t->n_glass)) || !(t->n_sample > 0))
		return c0_fail(C0_EINVAL, "n_glass %g / n_sample %g: refractive indices must be positive", t->n_glass, t->n_sample);
	if (t->n_sample >= t->n_glass)
		return c0_fail(C0_EINVAL, "n_sample %g must be below n_glass %g for total internal reflection", t->n_sample, t->n_glass);
	if (!(t->wavelength_nm > 0 && isfinite(t->wavelength_nm)))
		return c0_fail(C0_EINVAL, "wavelength_nm %g: must be positive (nm)", t->wavelength_nm);
	if (!(t->s_fraction >= 0 && t->s_fraction <= 1))
		return c0_fail(C0_EINVAL, "s_fraction %g: the s-polarisation share must be in [0, 1]", t->s_fraction);
	return C0_OK;
}

double c0_tirf_critical_deg(const struct c0_tirf *t)
{
	return asin(t->n_sample / t->n_glass) * 180 / C0_PI;
}

int c0_tirf_p(const struct c0_tirf *t, double alpha_deg, double *p)
{
	double ac = c0_tirf_critical_deg(t);
	if (!(alpha_deg > ac) || !(alpha_deg < 90))
		return c0_fail(C0_EINVAL, "angle %g deg is not between the critical angle %.3f deg and 90 deg (n_glass %g, n_sample %g)",
			       alpha_deg, ac, t->n_glass, t->n_sample);
	double s = sin(rad(alpha_deg)), sc = t->n_sample / t->n_glass;
	*p = 4 * C0_PI * t->n_glass / t->wavelength_nm * sqrt(s * s - sc * sc);
	return C0_OK;
}

void c0_tirf_i0_sp(const struct c0_tirf *t, double alpha_deg, double *is, double *ip)
{
	double n = t->n_sample / t->n_glass, c = cos(rad(alpha_deg)), s = sin(rad(alpha_deg));
	*is = 4 * c * c / (1 - n * n);
	*ip = 4 * c * c * (2 * s * s - n * n) / (n * n * n * n * c * c + s * s - n * n);
}

double c0_tirf_i0(const struct c0_tirf *t, double alpha_deg)
{
	double is, ip;
	c0_tirf_i0_sp(t, alpha_deg, &is, &ip);
	return t->s_fraction * is + (1 - t->s_fraction) * ip;
}

int c0_tirf_weights(const struct c0_tirf *t, int nq, const double *alpha_deg, const double *gain,
		    int nz, double z0, double dz, double *W)
{
	int st = c0_tirf_check(t);
	if (st)
		return st;
	if (nz <= 0 || !(dz > 0) || z0 < 0)
		return c0_fail(C0_EINVAL, "depth bins: need nz > 0, dz > 0, z0 >= 0 (got %d, %g, %g)", nz, dz, z0);
	for (int q = 0; q < nq; q++) {
		double p;
		if ((st = c0_tirf_p(t, alpha_deg[q], &p)))
			return st;
		double g = c0_tirf_i0(t, alpha_deg[q]) * (gain ? gain[q] : 1);
		for (int j = 0; j < nz; j++) {
			double a = z0 + j * dz;
			/* (e^{-pa} - e^{-p(a+dz)}) / (p dz), written to stay accurate for small p dz */
			W[q * nz + j] = g * exp(-p * a) * (-expm1(-p * dz)) / (p * dz);
		}
	}
	return C0_OK;
}
