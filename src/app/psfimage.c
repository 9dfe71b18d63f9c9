#include "app/psfimage.h"
#include "io/tiff.h"
#include "core/err.h"

#include <stdlib.h>

int c0_psf_fit_file(const char *path, struct c0_psf_fit *out, double *pixel_nm)
{
	struct c0_tiff_info in;
	float *v;
	int st = c0_tiff_load_f32(path, &in, &v);
	if (st)
		return st;
	const size_t np = (size_t)in.width * in.height;
	for (int64_t p = 1; p < in.pages; p++)   /* average the planes */
		for (size_t i = 0; i < np; i++)
			v[i] += v[(size_t)p * np + i];
	for (size_t i = 0; in.pages > 1 && i < np; i++)
		v[i] /= (float)in.pages;
	*pixel_nm = in.pixel_size_nm;
	st = c0_psf_fit_image(v, (int)in.width, (int)in.height, path, out);
	free(v);
	return st;
}
