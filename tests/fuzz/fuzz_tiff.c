/* libFuzzer target: any byte string must give a clean status from the TIFF
 * reader, never a crash, leak or undefined behaviour. */
#include "io/tiff.h"

#include <stdint.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct c0_tiff_reader *r;
	if (c0_tiff_open_mem(data, size, "fuzz", &r))
		return 0;
	const struct c0_tiff_info *in = c0_tiff_get_info(r);
	size_t n = (size_t)in->width * in->height;
	if (n <= (1u << 20)) {      /* larger claims only exercise the allocator */
		float *plane = malloc(n * sizeof *plane);
		for (int64_t p = 0; plane && p < in->pages && p < 8; p++)
			if (c0_tiff_read_f32(r, p, plane))
				break;
		free(plane);
	}
	c0_tiff_close(r);
	return 0;
}
