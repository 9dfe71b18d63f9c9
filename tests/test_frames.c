/* The frames' sums and profiles (io/frames.c): summed in 8 interleaved parts
 * where the values are small integers, in order otherwise; both against
 * the plain in-order double sums, bit for bit. */
#include "check.h"
#include "io/frames.h"
#include "core/rng.h"
#include "core/err.h"

#include <math.h>
#include <stdlib.h>

enum { W = 37, H = 5, T = 5, N = W * H };

static void test_sums(void)
{
	struct c0_rng rng;
	c0_rng_init(&rng, 11, 0);
	float *v = malloc(sizeof *v * N * T);
	for (int i = 0; i < N; i++) {
		const double u = c0_rng_uniform(&rng);
		v[i] = (float)floor(65536 * u);                             /* uint16 */
		v[N + i] = (float)floor(8388608 * (u - 0.5));              /* integers to 2^22, signed */
		v[2 * N + i] = i == N / 2 ? 0.5f : v[i];                   /* one half among them */
		v[3 * N + i] = (float)ldexp(c0_rng_normal(&rng), (int)(80 * u) - 40);   /* order matters here */
		v[4 * N + i] = i == 3 ? 16777216.f : v[i];                 /* 2^24: beyond the fast path's bound */
	}
	struct c0_frames f;
	CHECK(c0_frames_wrap(&f, v, T, H, W, 100, "frames") == C0_OK);
	CHECK(c0_frames_keep_profiles(&f) == C0_OK);
	const double *sum, *rows, *cols;
	CHECK(c0_frames_profiles(&f, &sum, &rows, &cols) == C0_OK);
	int same = 1;
	for (int t = 0; t < T; t++) {
		const float *fr = v + (size_t)t * N;
		double s = 0;
		for (int i = 0; i < N; i++)
			s += fr[i];
		same &= s == sum[t];
		for (int y = 0; y < H; y++) {
			double r = 0;
			for (int x = 0; x < W; x++)
				r += fr[y * W + x];
			same &= r == rows[t * H + y];
		}
		for (int x = 0; x < W; x++) {
			double c = 0;
			for (int y = 0; y < H; y++)
				c += fr[y * W + x];
			same &= c == cols[t * W + x];
		}
	}
	CHECK_MSG(same, "frame sums or profiles differ from the in-order sums");
	c0_frames_close(&f);
	free(v);
}

int main(void)
{
	RUN(test_sums);
	return CHECK_DONE();
}
