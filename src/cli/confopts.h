/* Command-line options for the parameters of struct c0_run_conf, made from
 * the library's table (app/params.h), which each command picks by parameter
 * name, and the map back from parameter names to flags for messages. */
#pragma once
#include "col0rme.h"
#include "cli/opts.h"

#include <stddef.h>

/* at least the rows of the table (c0_conf_cli_init stops the program otherwise) */
#define C0_CLI_MAXPARAMS 96

/* The run parameters as options, by their row in app/params.h. */
struct c0_conf_cli {
	struct c0_run_conf c;
	const char *choice[C0_CLI_MAXPARAMS];    /* the named choices, set by name at the end */
	char names[C0_CLI_MAXPARAMS][24];        /* the defaults' names */
	int given[C0_CLI_MAXPARAMS];             /* numbers: given; fixed-length lists: values given */
	int no_drift;                            /* --no-drift: drift off */
	int channel;                             /* --channel: 0 reads every channel of a multi-channel file */
};

/* The MA-TIRF parameters of 'run' and 'matirf', in help order. */
#define C0_MATIRF_PARAMS "angles", "n_glass", "n_sample", "wavelength_nm", "s_fraction", "gains", "z_range_nm", "reg", \
	"kappa", "sparsity", "axial_weight", "matirf_iterations", "matirf_tol", "matirf_solver", "matirf_coarse"

void c0_conf_cli_init(struct c0_conf_cli *m);
/* Appends the rows of the NULL-terminated parameter names to o (room
 * needed: one per name); returns how many. */
int c0_conf_cli_opts(struct c0_conf_cli *m, const char *const *params, struct c0_opt *o);
/* --progress-json's help (the commands that run the method, and simulate) */
#define C0_PROGRESS_JSON_HELP "progress as one JSON line per update on stderr (for programs; no progress line)"
/* A command's whole table: -o, the parameters' rows, --force, --verbose,
 * --progress-json (room needed: the names plus 4); returns the row count. */
int c0_conf_cli_table(struct c0_conf_cli *m, const char *const *params, const char **outdir, int *force, int *verbose,
		      int *progress_json, struct c0_opt *o);
/* After parsing: the named choices into m->c, fixed-length lists' lengths. */
int c0_conf_cli_finish(struct c0_conf_cli *m);
/* A command's own parameter name and its flag. */
struct c0_cli_name { const char *param, *flag; };
/* msg with the parameter names it cites as flags ("fwhm_nm 0: ..." ->
 * "--fwhm 0: ..."): extra's (ended by a NULL param; may be NULL), then the
 * run parameters'. */
void c0_cli_flags(const char *msg, const struct c0_cli_name *extra, char *buf, size_t n);
