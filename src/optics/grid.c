#include "optics/grid.h"
#include "optics/psf.h"
#include "core/err.h"

#include <math.h>

int c0_grid_check(const struct c0_grid *g)
{
	const double pixel_nm = g->pixel_nm, fwhm_nm = g->fwhm_nm;
	if (!(pixel_nm > 0 && isfinite(pixel_nm)))
		return c0_fail(C0_EINVAL, "pixel_nm %g: must be a positive number of nm", pixel_nm);
	if (!(fwhm_nm > 0 && isfinite(fwhm_nm)))
		return c0_fail(C0_EINVAL, "fwhm_nm %g: must be a positive number of nm", fwhm_nm);
	/* the banded covariance, the PSF tables and their integer widths are
	 * sized by FWHM / pixel: outside this range the input is not a
	 * microscope image sampled by its camera */
	if (!(fwhm_nm >= C0_PSF_MIN_PX * pixel_nm && fwhm_nm <= C0_PSF_MAX_PX * pixel_nm))
		return c0_fail(C0_EINVAL, "fwhm_nm %g: %.3g camera pixels of %g nm; must be %g to %g pixels", fwhm_nm, fwhm_nm / pixel_nm,
			       pixel_nm, C0_PSF_MIN_PX, C0_PSF_MAX_PX);
	if (g->srf < 1 || g->srf > 16)
		return c0_fail(C0_EINVAL, "srf %d: must be 1..16", g->srf);
	return C0_OK;
}

double c0_grid_sigma_px(const struct c0_grid *g)
{
	return c0_psf_sigma_px(g->fwhm_nm, g->pixel_nm);
}

double c0_grid_fine_nm(const struct c0_grid *g)
{
	return g->pixel_nm / g->srf;
}

int c0_grid_lag(const struct c0_grid *g, int lag)
{
	return lag > 0 ? lag : (int)ceil(6 * c0_grid_sigma_px(g));
}
