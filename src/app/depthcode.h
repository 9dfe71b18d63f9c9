/* Depth colour code of a volume, as Fiji's "temporal color code" does for
 * time: each depth bin gets a colour (near the glass red, deep blue, through
 * yellow, green and cyan) and a pixel's hue is its bins' colours mixed
 * by intensity; its brightness is the square root of its total intensity,
 * full at the 99.5th percentile. A colour bar labelled with the depth
 * range in nm is drawn on the right. */
#pragma once
#include <stddef.h>
#include <stdint.h>

/* f: nz x M, the columns at raster indices pixel[0..M) (stages/matirf.h;
 * pixel NULL: every pixel, M = h w), the other pixels black; z0, z1: the
 * depth range the bar spans (nm). *rgb is allocated (ow x oh x 3 bytes). */
int c0_depthcode(const float *f, const int *pixel, size_t M, int nz, int h, int w, double z0, double z1, uint8_t **rgb,
		 int *ow, int *oh);
