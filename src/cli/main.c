#define _POSIX_C_SOURCE 200809L
#include "cli/commands.h"
#include "cli/confopts.h"
#include "core/err.h"
#include "core/progress.h"
#include "core/threads.h"
#include "core/comm.h"
#include "c0_version.h"

#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <stdio.h>
#include <string.h>
#include <unistd.h>

static const struct {
	const char *name;
	int (*run)(int, char **);
	const char *summary;
} commands[] = {
	{ "eval", cmd_eval, "accuracy against ground truth: Jaccard, PSNR, depth error" },
	{ "info", cmd_info, "describe TIFF stacks: size, frames, type, calibration, statistics" },
	{ "simulate", cmd_simulate, "simulate MA-TIRF blinking stacks with ground truth" },
	{ "intensity", cmd_intensity, "per-angle intensity and background on a support" },
	{ "params", cmd_params, "every run parameter: name, option, default, meaning (Markdown)" },
	{ "matirf", cmd_matirf, "MA-TIRF axial reconstruction from one image per angle" },
	{ "run", cmd_run, "the whole method: support, intensities, MA-TIRF volume" },
	{ "report", cmd_report, "report.html again from an output directory's files" },
	{ "support", cmd_support, "COL0RME support estimation from the stacks' covariance" },
};

static void usage(FILE *f)
{
	fprintf(f, "usage: col0rme <command> [options]\n\n"
		   "3D super-resolution from multi-angle TIRF stacks of blinking fluorophores (3D-COL0RME).\n\ncommands:\n");
	for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
		fprintf(f, "  %-10s %s\n", commands[i].name, commands[i].summary);
	fprintf(f, "\n'col0rme <command> --help' describes each command; --version prints the version.\n");
}

int main(int argc, char **argv)
{
#ifdef __GLIBC__
	/* The tiles' covariance windows and solver arrays (tens of MB each,
	 * freed and allocated again tile after tile) were each a fresh mmap
	 * faulted in page by page. One heap that keeps up to 64 MB of free
	 * memory reuses them: 1024x1024x500 support with a fixed lambda and one
	 * iteration, 1.10M -> 0.51M page faults, 29.9 -> 24.5 s, peak RSS
	 * 817 -> 837 MB. */
	mallopt(M_ARENA_MAX, 1);
	mallopt(M_MMAP_THRESHOLD, 256 << 20);
	mallopt(M_TRIM_THRESHOLD, 64 << 20);
#endif
	c0_threads_startup(argv);
	if (argc < 2) {
		usage(stderr);
		return 2;
	}
	if (!strcmp(argv[1], "--version")) {
		printf("col0rme %s\n", C0_VERSION);
		return 0;
	}
	if (!strcmp(argv[1], "-h") || !strcmp(argv[1], "--help") || !strcmp(argv[1], "help")) {
		usage(stdout);
		return 0;
	}
	/* progress lines only on a terminal; --verbose turns them on elsewhere */
	int verbose = 0;
	for (int i = 2; i < argc; i++)
		if (!strcmp(argv[i], "--verbose"))
			verbose = 1;
	c0_progress_enable(verbose || isatty(STDERR_FILENO));
	for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
		if (!strcmp(argv[1], commands[i].name)) {
			if (c0_comm_init(&argc, &argv))
				return c0_cli_error(argv[1]);
			int rc = commands[i].run(argc - 1, argv + 1);
			c0_comm_finalize();
			return rc;
		}
	fprintf(stderr, "col0rme: error: unknown command '%s'\n", argv[1]);
	usage(stderr);
	return 2;
}
