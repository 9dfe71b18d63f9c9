/* The whole method on stacks in memory: simulate three small acquisitions
 * with the library's simulator, run 3D-COL0RME on the arrays, and print
 * what came out. Build against an installed col0rme:
 *   cc -std=c11 -Wall -Werror run_arrays.c $(pkg-config --cflags --libs col0rme) */
#include <col0rme.h>

#include <stdio.h>

int main(void)
{
	/* 3 angles x 200 frames of 24 x 24 camera pixels */
	struct c0_simulation *sim;
	if (c0_simulation_new(&sim) || c0_simulation_set(sim, "width", "24") || c0_simulation_set(sim, "height", "24") ||
	    c0_simulation_set(sim, "frames", "200") || c0_simulation_set(sim, "angles", "62,65,68") ||
	    c0_simulation_set(sim, "filaments", "2") || c0_simulation_run(sim)) {
		fprintf(stderr, "simulate: %s\n", c0_last_error());
		return 1;
	}
	struct c0_stack stacks[3] = { { 0 } };
	for (int q = 0; q < 3; q++)
		stacks[q].data = c0_simulation_stack(sim, q, &stacks[q].frames, &stacks[q].height, &stacks[q].width);

	/* the method's parameters: documented defaults, then what this data needs */
	struct c0_run_conf conf;
	c0_run_conf_init(&conf);
	if (c0_run_conf_set(&conf, "angles", "62,65,68") || c0_run_conf_set(&conf, "pixel_nm", "100") ||
	    c0_run_conf_set(&conf, "fwhm_nm", "229")) {
		fprintf(stderr, "%s\n", c0_last_error());
		return 1;
	}
	struct c0_result *res;
	if (c0_run(&conf, stacks, 3, &res)) {
		fprintf(stderr, "run: %s\n", c0_last_error());
		c0_simulation_free(sim);
		return 1;
	}
	int nz, h, w, on = 0;
	const float *vol = c0_result_volume(res, &nz, &h, &w);
	const float *depth = c0_result_depth(res, &h, &w);
	const uint8_t *support = c0_result_support(res, &h, &w);
	double total = 0, dsum = 0;
	for (long i = 0; i < (long)nz * h * w; i++)
		total += vol[i];
	for (long i = 0; i < (long)h * w; i++)
		if (support[i] && depth[i] > 0)
			on++, dsum += depth[i];
	printf("col0rme %s: volume %d x %d x %d (sum %.4g), %d support pixels with a depth, mean depth %.0f nm\n",
	       c0_version(), nz, h, w, total, on, on ? dsum / on : 0.0);
	c0_result_free(res);
	c0_simulation_free(sim);
	return on > 0 ? 0 : 1;
}
