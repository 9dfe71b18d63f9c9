#include "app/depthcode.h"
#include "core/err.h"
#include "core/mem.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* hue from 0 (red) to 240 degrees (blue) at full saturation and value */
static void lut(double t, double rgb[3])
{
	double h = 4 * fmin(fmax(t, 0), 1);   /* 0..4 in 60-degree sectors */
	int s = h >= 4 ? 3 : (int)h;
	double f = h - s;
	static const double c[5][3] = { { 1, 0, 0 }, { 1, 1, 0 }, { 0, 1, 0 }, { 0, 1, 1 }, { 0, 0, 1 } };
	for (int k = 0; k < 3; k++)
		rgb[k] = c[s][k] + f * (c[s + 1][k] - c[s][k]);
}

/* 3x5 glyphs for the bar's labels, one row per 3-bit number (MSB left) */
static const char *glyph_chars = "0123456789.-nm";
static const uint8_t glyphs[][5] = {
	{ 7, 5, 5, 5, 7 }, { 2, 6, 2, 2, 7 }, { 7, 1, 7, 4, 7 }, { 7, 1, 7, 1, 7 }, { 5, 5, 7, 1, 1 },
	{ 7, 4, 7, 1, 7 }, { 7, 4, 7, 5, 7 }, { 7, 1, 1, 1, 1 }, { 7, 5, 7, 5, 7 }, { 7, 5, 7, 1, 7 },
	{ 0, 0, 0, 0, 2 }, { 0, 0, 7, 0, 0 }, { 0, 0, 6, 5, 5 }, { 0, 0, 7, 7, 5 },
};
#define SCALE 2
#define ADV (4 * SCALE)

static void text(uint8_t *img, int ow, int oh, int x, int y, const char *s)
{
	for (; *s; s++, x += ADV) {
		const char *g = strchr(glyph_chars, *s);
		if (!g)
			continue;
		const uint8_t *b = glyphs[g - glyph_chars];
		for (int r = 0; r < 5 * SCALE; r++)
			for (int c = 0; c < 3 * SCALE; c++)
				if (b[r / SCALE] >> (2 - c / SCALE) & 1) {
					int px = x + c, py = y + r;
					if (px >= 0 && px < ow && py >= 0 && py < oh)
						memset(img + ((size_t)py * ow + px) * 3, 255, 3);
				}
	}
}

static int cmp_float(const void *a, const void *b)
{
	float x = *(const float *)a, y = *(const float *)b;
	return (x > y) - (x < y);
}

int c0_depthcode(const float *f, const int *pixel, size_t M, int nz, int h, int w, double z0, double z1, uint8_t **rgb,
		 int *ow, int *oh)
{
	const size_t np = M;
	char top[32], bot[32];
	snprintf(top, sizeof top, "%g", z0);
	snprintf(bot, sizeof bot, "%gnm", z1);
	const int bar_x = w + 8, bar_w = 12, label_x = bar_x + bar_w + 4;
	int label_w = (int)(strlen(bot) > strlen(top) ? strlen(bot) : strlen(top)) * ADV;
	*ow = label_x + label_w + 4;
	*oh = h > 64 ? h : 64;
	float *tot = c0_alloc(np, sizeof *tot);
	*rgb = c0_alloc((size_t)*ow * *oh * 3, 1);
	if (!tot || !*rgb) {
		free(tot), free(*rgb), *rgb = NULL;
		return C0_ENOMEM;
	}
	size_t nn = 0;
	for (size_t p = 0; p < np; p++) {
		double s = 0;
		for (int j = 0; j < nz; j++)
			s += fmax(f[j * np + p], 0);
		if (s > 0)
			tot[nn++] = (float)s;
	}
	double norm = 1;
	if (nn) {
		qsort(tot, nn, sizeof *tot, cmp_float);
		norm = tot[(size_t)(0.995 * (double)(nn - 1))];
	}
	free(tot);
	double col[512][3];
	for (int j = 0; j < nz && j < 512; j++)
		lut(nz > 1 ? (double)j / (nz - 1) : 0, col[j]);
	for (size_t p = 0; p < M; p++) {    /* the image's other pixels stay black */
		const size_t y = pixel ? (size_t)pixel[p] / w : p / w, x = pixel ? (size_t)pixel[p] % w : p % w;
		double c[3] = { 0, 0, 0 }, t = 0;
		for (int j = 0; j < nz && j < 512; j++) {
			double v = fmax(f[j * np + p], 0);
			t += v;
			for (int k = 0; k < 3; k++)
				c[k] += v * col[j][k];
		}
		/* the hue is the intensity-weighted mix; the brightness goes as
		 * the square root of the intensity so that dim structures show */
		double b = t > 0 ? sqrt(fmin(t / norm, 1)) / t : 0;
		uint8_t *o = *rgb + ((size_t)y * *ow + x) * 3;
		for (int k = 0; k < 3; k++)
			o[k] = (uint8_t)lrint(255 * fmin(c[k] * b, 1));
	}
	/* the bar: z0 at the top, z1 at the bottom, as the labels say */
	const int bar_top = 2, bar_h = *oh - 4 - 5 * SCALE;
	for (int y = 0; y < bar_h; y++) {
		double c[3];
		lut((double)y / (bar_h - 1), c);
		for (int x = 0; x < bar_w; x++)
			for (int k = 0; k < 3; k++)
				(*rgb)[((size_t)(bar_top + y) * *ow + bar_x + x) * 3 + k] = (uint8_t)lrint(255 * c[k]);
	}
	text(*rgb, *ow, *oh, label_x, bar_top, top);
	text(*rgb, *ow, *oh, label_x, bar_top + bar_h - 5 * SCALE, bot);
	return C0_OK;
}
