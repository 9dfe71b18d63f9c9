/* libFuzzer target over command lines: the input's first byte picks run,
 * support or matirf, the rest is split at newlines and NULs into options,
 * and the harness appends -o and tiny stacks (written once, in a scratch
 * directory, removed at exit). Any options must end in a status (0, 1 or 2) without a crash,
 * a leak or undefined behaviour, and leave no staging directory behind.
 * Options that name other output directories or files are dropped (the
 * fuzzer must not write or replace anything outside its scratch), and
 * iteration counts are capped so that one input stays well under a second.
 * The harness works in its scratch directory (chdir at start): give the
 * fuzzer absolute corpus and artifact paths. */
#define _GNU_SOURCE
#include "cli/commands.h"
#include "io/tiff.h"
#include "core/progress.h"
#include "core/rng.h"

#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char dir[256], out[300], stk[2][300], img[2][300], hyp[300];

static void write_stack(const char *path, int frames, int channels, uint64_t seed)
{
	const int W = 16, H = 16;
	float *v = malloc(sizeof(float) * W * H * frames * channels);
	struct c0_rng r;
	c0_rng_init(&r, seed, 0);
	for (int i = 0; i < W * H * frames * channels; i++)   /* blinking-like: mostly dark, some bright */
		v[i] = (float)(100 + (c0_rng_uniform(&r) < 0.1 ? 400 * c0_rng_uniform(&r) : 5 * c0_rng_uniform(&r)));
	struct c0_tiff_wopts o = { .width = W, .height = H, .frames = frames, .channels = channels, .dtype = C0_U16,
				   .pixel_size_nm = 100 };
	if (c0_tiff_save_f32(path, &o, v))
		abort();
	free(v);
}

static void remove_out(void);

/* The scratch directory goes when the fuzzer exits (libFuzzer ends with exit()). */
static void remove_scratch(void)
{
	remove_out();
	for (int q = 0; q < 2; q++)
		unlink(stk[q]), unlink(img[q]);
	unlink(hyp);
	if (chdir("/") == 0)
		rmdir(dir);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
	(void)argc, (void)argv;
	snprintf(dir, sizeof dir, "/tmp/c0_fuzz_cli_XXXXXX");
	if (!mkdtemp(dir) || chdir(dir))
		abort();
	snprintf(out, sizeof out, "%s/out", dir);
	for (int q = 0; q < 2; q++) {
		snprintf(stk[q], sizeof stk[q], "%s/stack%d.tif", dir, q + 1);
		snprintf(img[q], sizeof img[q], "%s/image%d.tif", dir, q + 1);
		write_stack(stk[q], 12, 1, 7 + q);
		write_stack(img[q], 1, 1, 9 + q);
	}
	snprintf(hyp, sizeof hyp, "%s/hyper.tif", dir);
	write_stack(hyp, 12, 2, 11);
	c0_progress_enable(0);
	atexit(remove_scratch);
	return 0;
}

/* An option the harness owns, or one naming a path. */
static int dropped(const char *a)
{
	return !strcmp(a, "-o") || !strncmp(a, "--output", 8) || !strcmp(a, "--") || strchr(a, '/') || !strncmp(a, "-o", 2);
}

/* Iteration counts and lags above a small cap (kept out: they only make the run slow). */
static int too_slow(char **a, int n)
{
	static const char *capped[] = { "iterations", "reweightings", "lag", "srf", "matirf-iterations", "graph-radius" };
	for (int i = 0; i < n; i++) {
		if (strncmp(a[i], "--", 2))
			continue;
		for (size_t k = 0; k < sizeof capped / sizeof *capped; k++) {
			size_t l = strlen(capped[k]);
			if (strncmp(a[i] + 2, capped[k], l) || (a[i][2 + l] && a[i][2 + l] != '='))
				continue;
			const char *v = a[i][2 + l] == '=' ? a[i] + 3 + l : i + 1 < n ? a[i + 1] : "0";
			if (strtod(v, NULL) > 300)
				return 1;
		}
	}
	return 0;
}

static void remove_out(void)
{
	DIR *d = opendir(dir);
	for (struct dirent *e; d && (e = readdir(d));) {
		if (strncmp(e->d_name, "out", 3))
			continue;
		char p[600];
		snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
		DIR *s = opendir(p);
		for (struct dirent *f; s && (f = readdir(s));) {
			char q[1200];
			snprintf(q, sizeof q, "%s/%s", p, f->d_name);
			if (f->d_name[0] != '.' || (strcmp(f->d_name, ".") && strcmp(f->d_name, "..")))
				unlink(q);
		}
		if (s)
			closedir(s);
		/* a staging directory left behind by a command is a bug */
		if (strstr(e->d_name, ".c0tmp-"))
			abort();
		rmdir(p);
	}
	if (d)
		closedir(d);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	if (size < 1 || size > 512)
		return 0;
	char *buf = malloc(size);
	memcpy(buf, data + 1, size - 1);
	buf[size - 1] = '\0';
	char *argv[80];
	int argc = 0;
	static const char *cmds[] = { "run", "support", "matirf" };
	const int cmd = data[0] % 3;
	argv[argc++] = (char *)cmds[cmd];
	/* short solves unless the input asks otherwise (up to the cap) */
	argv[argc++] = cmd == 1 ? "--iterations" : "--matirf-iterations";
	argv[argc++] = "30";
	for (char *p = buf; p < buf + size - 1 && argc < 70;) {
		size_t l = strcspn(p, "\n");
		p[l] = '\0';
		if (*p && !dropped(p))
			argv[argc++] = p;
		p += l + 1;
	}
	if (too_slow(argv + 1, argc - 1)) {
		free(buf);
		return 0;
	}
	argv[argc++] = "-o";
	argv[argc++] = out;
	if (cmd == 2) {
		argv[argc++] = img[0], argv[argc++] = img[1];
	} else if (data[0] & 8) {
		argv[argc++] = hyp;   /* two channels: two stacks */
	} else {
		argv[argc++] = stk[0], argv[argc++] = stk[1];
	}
	argv[argc] = NULL;
	int rc = cmd == 0 ? cmd_run(argc, argv) : cmd == 1 ? cmd_support(argc, argv) : cmd_matirf(argc, argv);
	if (rc < 0 || rc > 2)
		abort();
	remove_out();
	free(buf);
	return 0;
}
