/* 8-bit RGB PNG through libpng, written under a temporary name and renamed
 * on success. */
#pragma once
#include <stdint.h>

/* rgb: h rows of w pixels, 3 bytes each. */
int c0_png_write_rgb(const char *path, int w, int h, const uint8_t *rgb);
