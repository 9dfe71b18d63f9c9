/* Table-driven options: one row gives parsing, help text and the default
 * (the value already in dst when parsing starts). */
#pragma once

enum c0_opt_type {
	C0_OPT_FLAG,     /* int, set to 1 */
	C0_OPT_INT,      /* int */
	C0_OPT_LONG,     /* long long */
	C0_OPT_DOUBLE,   /* double */
	C0_OPT_STRING,   /* const char * */
	C0_OPT_DOUBLES,  /* comma list into double[max], count in *count */
	C0_OPT_INTS,     /* comma list into int[max], count in *count */
};

struct c0_opt {
	const char *name;      /* long name, without "--" */
	char shortname;        /* 0 for none */
	enum c0_opt_type type;
	void *dst;
	const char *metavar;
	const char *help;
	const char *defhint;   /* shown instead of the current value, if set */
	int max;               /* list options: capacity */
	int *count;            /* list options: parsed length; C0_OPT_DOUBLE: set to 1 when given */
};

struct c0_cmd_spec {
	const char *name;
	const char *args;      /* e.g. "[options] FILE..." */
	const char *summary;
	const struct c0_opt *opts;
	int nopts;
	int min_pos, max_pos;  /* positional argument count (max < 0: any) */
	int threads;           /* 1: the command takes --threads N (core/threads.h) */
};

#define C0_NOPTS(a) ((int)(sizeof(a) / sizeof((a)[0])))

/* Returns 0 to go on, 1 when help was printed (exit 0), 2 on error (message
 * already printed). Positional arguments are left in pos[0..*npos); pos
 * needs room for max_pos of them (argc when max_pos < 0). */
int c0_opts_parse(const struct c0_cmd_spec *spec, int argc, char **argv, int *npos, char **pos);
void c0_opts_help(const struct c0_cmd_spec *spec);
/* --help-json: the options as JSON for programs (the ImageJ plugin builds
 * its dialogs from it): command, args, summary and per option flag, short,
 * param (params[i] when params is given, else the flag's name with '_'),
 * type, metavar, help and default (the text --help shows, or null). */
void c0_opts_help_json(const struct c0_cmd_spec *spec, const char *const *params);
