/* ImageJ hyperstack metadata (the ImageDescription of the first page) and
 * the OME-XML pixel size, parsed and formatted without libtiff. */
#pragma once
#include <stddef.h>
#include <stdint.h>

struct c0_ij_meta {
	int present;                       /* description starts with "ImageJ=" */
	int64_t images, channels, slices, frames;
	char unit[16];                     /* normalised: "nm", "um", "mm", "cm", "inch" or "" */
	double spacing;                    /* z step in `unit`, 0 if absent */
	double finterval;                  /* s, 0 if absent */
};

void c0_ij_parse(const char *desc, struct c0_ij_meta *m);
/* nm per unit for a normalised unit, 0 for unknown. */
double c0_unit_nm(const char *unit);
/* Normalises the spellings ImageJ and others use (micron, µm, \u00B5m, ...). */
void c0_unit_normalise(const char *in, char out[16]);
/* OME-XML: PhysicalSizeX (+ unit, default µm) in nm, 0 if absent. */
double c0_ome_pixel_size_nm(const char *xml, double *z_nm);
/* OME-XML plane layout: sizes, the stride of the channel index between
 * consecutive planes (from DimensionOrder) and the number of Image series. */
struct c0_ome_layout {
	int64_t size_c, size_z, size_t_, series, stride_c;
};
int c0_ome_layout(const char *xml, struct c0_ome_layout *l);
/* Appends "key=value\n" to the description of length len in buf; returns
 * the new length or -1 if buf is too small. */
int c0_ij_append(char *buf, size_t n, int len, const char *key, double value);
/* Writes an ImageJ description; returns the length or -1 if buf is too small. */
int c0_ij_format(char *buf, size_t n, int64_t channels, int64_t slices, int64_t frames,
		 int calibrated, double z_spacing_um, double finterval_s, double dmin, double dmax);
