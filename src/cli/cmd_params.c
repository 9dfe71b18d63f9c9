/* col0rme params: the run parameters' table (app/params.h) as the
 * reference list of docs/params.md, so the docs are made from the code. */
#include "cli/commands.h"
#include "cli/opts.h"
#include "app/params.h"

#include <stdio.h>

/* The anchor of a parameter's section in docs/defaults.md: its name, lower
 * case, anything but letters, digits and '_' as '-' (test_docs.py checks
 * that every one exists). */
static void slug(const char *s)
{
	for (; *s; s++) {
		char c = *s >= 'A' && *s <= 'Z' ? (char)(*s - 'A' + 'a') : *s;
		putchar((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' ? c : '-');
	}
}

/* s with Markdown's cell separator escaped */
static void cell(const char *s)
{
	for (; *s; s++)
		fputs(*s == '|' ? "\\|" : (char[2]){ *s, 0 }, stdout);
}

int cmd_params(int argc, char **argv)
{
	struct c0_cmd_spec spec = { "params", "[options]",
		"Prints every run parameter as a Markdown table: its name in the library and the\n"
		"Python package (c0_run_conf_set, col0rme.run keywords), its command-line option,\n"
		"the value it takes, its default and what it does. docs/params.md is this output.",
		NULL, 0, 0, 0, 0 };
	char *pos[1];
	int npos, rc = c0_opts_parse(&spec, argc, argv, &npos, pos);
	if (rc)
		return rc == 1 ? 0 : 2;
	int n;
	const struct c0_param *t = c0_params(&n);
	printf("# Parameters\n\n"
	       "Made by `col0rme params` from the library's table (`src/app/params.c`): the\n"
	       "command-line help and `col0rme.parameters()` in Python come from the same rows.\n"
	       "Each name links to its section of `docs/defaults.md`: the default, why, and the\n"
	       "measurement that decided it. How to choose them: `docs/guide.md`.\n\n"
	       "| parameter | option | value | default | what it does |\n|---|---|---|---|---|\n");
	for (int i = 0; i < n; i++) {
		printf("| [`%s`](defaults.md#", t[i].name), slug(t[i].name);
		printf(") | `--%s` | ", t[i].flag);
		if (t[i].metavar)
			fputs("`", stdout), cell(t[i].metavar), fputs("`", stdout);
		else
			fputs("(flag)", stdout);
		fputs(" | ", stdout), cell(t[i].def), fputs(" | ", stdout), cell(t[i].help), puts(" |");
	}
	return 0;
}
