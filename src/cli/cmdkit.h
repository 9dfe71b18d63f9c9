/* The frame shared by the commands that run the method: their options
 * (-o, the parameters they take, --force, --verbose, extra rows), the
 * stacks named on the command line, the output directory, and the end
 * (write the result or roll back, print the error). */
#pragma once
#include "cli/confopts.h"
#include "app/result.h"
#include "app/single.h"
#include "app/pipeline_write.h"

struct c0_cli {
	struct c0_conf_cli m;
	const char *outdir;
	int force, verbose, progress_json;
	struct c0_opt opts[64];
	char *paths[C0_MAX_STACKS];  /* after multi-channel files were expanded (FILE:cK) */
	char **names;                /* their storage */
	struct c0_stack stacks[C0_MAX_STACKS];
	int n;
	struct c0_outdir out;
	int opened;
	double t0;                   /* the progress line's (or JSON line's) stage start */
};

/* --progress-json: the library's progress callback (user: a double, the
 * stage's start) as one JSON line per call on stderr,
 * {"progress":{"stage":S,"fraction":F,"seconds":T}}, flushed. */
int c0_cli_progress_json(const char *stage, double fraction, void *user);

/* Parses argv with spec (whose opts are filled here from params and the
 * nextra rows of extra); then the named choices. 0: go on; 1: help was
 * printed (exit 0); 2: an error was printed. */
int c0_cli_start(struct c0_cli *k, struct c0_cmd_spec *spec, const char *const *params, const struct c0_opt *extra,
		 int nextra, int argc, char **argv);
/* The output directory: not an input's, empty unless --force. */
int c0_cli_open(struct c0_cli *k);
/* The CLI's own signal cleanup (cli/sigclean.c): until c0_cli_unguard, a
 * signal or exit() removes o's staging directory. */
void c0_cli_guard(const struct c0_outdir *o);
void c0_cli_unguard(void);
/* Writes r (with argv in its report) and moves the output directory into
 * place when st is 0, else rolls back; frees r; returns the exit code,
 * printing the error. */
int c0_cli_end(struct c0_cli *k, const char *cmd, struct c0_result *r, int st, int argc, char **argv);
