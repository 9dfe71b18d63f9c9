/* The whole method on TIFF stacks, written to a directory as `col0rme run`
 * does:  run_files OUTDIR ANGLES STACK...  (ANGLES: e.g. 62,65,68, one per
 * stack; pixel size from the files' calibration, FWHM 229 nm).
 *   cc -std=c11 -Wall -Werror run_files.c $(pkg-config --cflags --libs col0rme) */
#include <col0rme.h>

#include <stdio.h>

int main(int argc, char **argv)
{
	if (argc < 4 || argc - 3 > C0_MAX_STACKS) {
		fprintf(stderr, "usage: %s OUTDIR ANGLES STACK...\n", argv[0]);
		return 2;
	}
	struct c0_run_conf conf;
	c0_run_conf_init(&conf);
	if (c0_run_conf_set(&conf, "angles", argv[2]) || c0_run_conf_set(&conf, "fwhm_nm", "229")) {
		fprintf(stderr, "%s\n", c0_last_error());
		return 2;
	}
	struct c0_stack stacks[C0_MAX_STACKS] = { { 0 } };
	const int n = argc - 3;
	for (int i = 0; i < n; i++)
		stacks[i].path = argv[3 + i];
	struct c0_result *res;
	if (c0_run(&conf, stacks, n, &res)) {
		fprintf(stderr, "run: %s\n", c0_last_error());
		return 1;
	}
	int st = c0_result_write(res, argv[1], 0);
	if (st)
		fprintf(stderr, "write: %s\n", c0_last_error());
	else
		printf("wrote %s\n", argv[1]);
	c0_result_free(res);
	return st ? 1 : 0;
}
