#include "cli/cmdkit.h"
#include "cli/commands.h"
#include "core/err.h"
#include "core/comm.h"
#include "core/clock.h"
#include "core/progress.h"

#include <stdio.h>
#include <string.h>

int c0_cli_error(const char *cmd)
{
	return c0_cli_error_names(cmd, NULL);
}

int c0_cli_error_names(const char *cmd, const struct c0_cli_name *names)
{
	char msg[2048];
	c0_cli_flags(c0_errmsg(), names, msg, sizeof msg);   /* the library names parameters; we show flags */
	if (c0_comm_rank() == 0)      /* under MPI every rank has the message */
		fprintf(stderr, "col0rme %s: error: %s\n", cmd, msg);
	return 1;
}

/* The run's progress line on a terminal (or with --verbose), from the
 * library's progress callback: one line per stage, its percent and time. */
static int progress_line(const char *stage, double fraction, void *user)
{
	double *t0 = user, now = c0_now(), el = now - *t0;
	if (fraction == 0)
		*t0 = now, el = 0;
	if (fraction > 0.01 && fraction < 1)
		fprintf(stderr, "\r%-12s %3.0f%%  %6.1fs  ETA %6.1fs ", stage, 100 * fraction, el, el * (1 - fraction) / fraction);
	else
		fprintf(stderr, "\r%-12s %3.0f%%  %6.1fs%16s", stage, 100 * fraction, el, "");
	if (fraction >= 1)
		fputc('\n', stderr);
	fflush(stderr);
	return 0;
}

int c0_cli_progress_json(const char *stage, double fraction, void *user)
{
	double *t0 = user, now = c0_now();
	if (fraction == 0)
		*t0 = now;
	fprintf(stderr, "{\"progress\":{\"stage\":\"%s\",\"fraction\":%.4f,\"seconds\":%.3f}}\n", stage, fraction, now - *t0);
	fflush(stderr);
	return 0;
}

int c0_cli_start(struct c0_cli *k, struct c0_cmd_spec *spec, const char *const *params, const struct c0_opt *extra,
		 int nextra, int argc, char **argv)
{
	memset(k, 0, sizeof *k);
	c0_conf_cli_init(&k->m);
	int no = c0_conf_cli_table(&k->m, params, &k->outdir, &k->force, &k->verbose, &k->progress_json, k->opts);
	if (nextra)
		memcpy(k->opts + no, extra, (size_t)nextra * sizeof *extra);
	spec->opts = k->opts, spec->nopts = no + nextra;
	/* --help-json with the library's parameter names (c0_run_conf_set) */
	const char *pnames[64] = { "outdir" };
	for (int i = 0; params[i]; i++)
		pnames[1 + i] = params[i];
	pnames[no - 3] = "force", pnames[no - 2] = "verbose", pnames[no - 1] = "progress_json";
	for (int i = 1; i < argc && strcmp(argv[i], "--"); i++)
		if (!strcmp(argv[i], "--help-json")) {
			c0_opts_help_json(spec, pnames);
			return 1;
		}
	int na, rc = c0_opts_parse(spec, argc, argv, &na, k->paths);
	if (rc)
		return rc;
	/* a multi-channel file gives one stack per channel (or --channel's) */
	if (c0_conf_cli_finish(&k->m) || c0_frames_expand(k->paths, na, k->m.channel, C0_MAX_STACKS, &k->names, &k->n)) {
		c0_cli_error(spec->name);
		return 2;
	}
	for (int i = 0; i < k->n; i++)
		k->stacks[i].path = k->paths[i] = k->names[i];
	if ((k->progress_json || c0_progress_enabled()) && c0_comm_rank() == 0)
		c0_run_conf_set_progress(&k->m.c, k->progress_json ? c0_cli_progress_json : progress_line, &k->t0);
	return 0;
}

/* Under MPI every rank computes and rank 0 alone writes. */
int c0_cli_open(struct c0_cli *k)
{
	int st = c0_outdir_check_inputs(k->outdir, (const char *const *)k->paths, k->n);
	if (!st && c0_comm_rank() == 0)
		st = c0_outdir_open(&k->out, k->outdir, k->force);
	k->opened = !st && c0_comm_rank() == 0;
	if (k->opened)
		c0_cli_guard(&k->out);
	return c0_comm_status(st);
}

int c0_cli_end(struct c0_cli *k, const char *cmd, struct c0_result *r, int st, int argc, char **argv)
{
	if (!st && c0_comm_rank() == 0) {
		const cJSON *w;
		cJSON_ArrayForEach(w, cJSON_GetObjectItem(r->rep, "warnings"))
			fprintf(stderr, "col0rme %s: warning: %s\n", cmd, w->valuestring);
		c0_result_set_argv(r, argc, argv);
		st = c0_result_write_to(r, &k->out);
	}
	if (k->opened)
		st = c0_outdir_finish(&k->out, st);
	c0_cli_unguard();
	c0_result_free(r);
	c0_frames_expand_free(k->names, k->n);
	k->names = NULL;
	return st ? c0_cli_error(cmd) : 0;
}
