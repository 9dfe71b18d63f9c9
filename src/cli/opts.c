#include "cli/opts.h"
#include "core/threads.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The default as text ("" when there is none to show). */
static void default_text(const struct c0_opt *o, char *buf, size_t n)
{
	buf[0] = '\0';
	if (o->defhint) {
		snprintf(buf, n, "%s", o->defhint);
		return;
	}
	switch (o->type) {
	case C0_OPT_INT: snprintf(buf, n, "%d", *(int *)o->dst); break;
	case C0_OPT_LONG: snprintf(buf, n, "%lld", *(long long *)o->dst); break;
	case C0_OPT_DOUBLE: snprintf(buf, n, "%g", *(double *)o->dst); break;
	case C0_OPT_STRING:
		if (*(const char **)o->dst)
			snprintf(buf, n, "%s", *(const char **)o->dst);
		break;
	case C0_OPT_DOUBLES: {
		size_t k = 0;
		for (int i = 0; i < *o->count && k < n; i++)
			k += (size_t)snprintf(buf + k, n - k, "%s%g", i ? "," : "", ((double *)o->dst)[i]);
		break;
	}
	default: break;
	}
}

static void show_default(const struct c0_opt *o, char *buf, size_t n)
{
	char d[160];
	default_text(o, d, sizeof d);
	if (*d)
		snprintf(buf, n, " (default: %s)", d);
	else
		buf[0] = '\0';
}

static void json_string(const char *s)
{
	if (!s) {
		fputs("null", stdout);
		return;
	}
	putchar('"');
	for (; *s; s++) {
		unsigned char c = (unsigned char)*s;
		if (c == '"' || c == '\\')
			printf("\\%c", c);
		else if (c == '\n')
			fputs("\\n", stdout);
		else if (c < 0x20)
			printf("\\u%04x", c);
		else
			putchar(c);
	}
	putchar('"');
}

static const char *const type_names[] = { "flag", "int", "int", "number", "string", "numbers", "ints" };

static void json_row(const char *flag, char shortname, const char *param, const char *type, const char *metavar,
		     const char *help, const char *def, int last)
{
	char sh[3] = { '-', shortname, 0 }, derived[64];
	if (!param) {   /* the flag's name, as an identifier */
		size_t i = 0;
		for (const char *p = flag + 2; *p && i + 1 < sizeof derived; p++)
			derived[i++] = *p == '-' ? '_' : *p;
		derived[i] = '\0';
		param = derived;
	}
	fputs("    {\"flag\": ", stdout), json_string(flag);
	fputs(", \"short\": ", stdout), json_string(shortname ? sh : NULL);
	fputs(", \"param\": ", stdout), json_string(param);
	fputs(", \"type\": ", stdout), json_string(type);
	fputs(", \"metavar\": ", stdout), json_string(metavar);
	fputs(", \"help\": ", stdout), json_string(help);
	fputs(", \"default\": ", stdout), json_string(def && *def ? def : NULL);
	puts(last ? "}" : "},");
}

void c0_opts_help_json(const struct c0_cmd_spec *spec, const char *const *params)
{
	fputs("{\"command\": ", stdout), json_string(spec->name);
	fputs(",\n  \"args\": ", stdout), json_string(spec->args);
	fputs(",\n  \"summary\": ", stdout), json_string(spec->summary);
	fputs(",\n  \"options\": [\n", stdout);
	for (int i = 0; i < spec->nopts; i++) {
		const struct c0_opt *o = &spec->opts[i];
		char flag[80], def[160];
		snprintf(flag, sizeof flag, "--%s", o->name);
		default_text(o, def, sizeof def);
		json_row(flag, o->shortname, params ? params[i] : NULL, type_names[o->type],
			 o->type == C0_OPT_FLAG ? NULL : o->metavar ? o->metavar : "X", o->help, def, !spec->threads && i == spec->nopts - 1);
	}
	if (spec->threads)
		json_row("--threads", 0, NULL, "int", "N", "worker threads", "the CPUs this process may run on", 1);
	puts("  ]}");
}

void c0_opts_help(const struct c0_cmd_spec *spec)
{
	printf("usage: col0rme %s %s\n\n%s\n\noptions:\n", spec->name, spec->args, spec->summary);
	for (int i = 0; i < spec->nopts; i++) {
		const struct c0_opt *o = &spec->opts[i];
		char head[64], def[192];   /* " (default: " + up to 159 characters + ")" */
		snprintf(head, sizeof head, "%c%c%s--%s %s", o->shortname ? '-' : ' ', o->shortname ? o->shortname : ' ',
			 o->shortname ? ", " : "  ", o->name, o->type == C0_OPT_FLAG ? "" : o->metavar ? o->metavar : "X");
		show_default(o, def, sizeof def);
		printf("  %-28s %s%s\n", head, o->help, def);
	}
	if (spec->threads)
		printf("  %-28s %s\n", "    --threads N", "worker threads (default: the CPUs this process may run on)");
	printf("  %-28s %s\n", "-h, --help", "show this help");
	printf("  %-28s %s\n", "    --help-json", "print these options as JSON (flag, param, type, metavar, help, default) and exit");
}

static int bad(const struct c0_cmd_spec *spec, const char *name, const char *val, const char *why)
{
	fprintf(stderr, "col0rme %s: error: --%s %s: %s\n", spec->name, name, val ? val : "", why);
	return 2;
}

static int parse_list(const struct c0_cmd_spec *spec, const struct c0_opt *o, const char *v)
{
	int n = 0;
	const char *p = v;
	while (*p) {
		if (n >= o->max)
			return bad(spec, o->name, v, "too many values");
		char *end;
		errno = 0;
		if (o->type == C0_OPT_DOUBLES)
			((double *)o->dst)[n] = strtod(p, &end);
		else {
			long x = strtol(p, &end, 10);
			((int *)o->dst)[n] = (int)x;
		}
		if (end == p || errno || (*end && *end != ','))
			return bad(spec, o->name, v, "expected a comma-separated list of numbers");
		n++;
		p = *end ? end + 1 : end;
	}
	if (!n)
		return bad(spec, o->name, v, "empty list");
	*o->count = n;
	return 0;
}

static int set_value(const struct c0_cmd_spec *spec, const struct c0_opt *o, const char *v)
{
	char *end;
	errno = 0;
	switch (o->type) {
	case C0_OPT_INT: {
		long x = strtol(v, &end, 10);
		if (end == v || *end || errno || x < -2147483647L || x > 2147483647L)
			return bad(spec, o->name, v, "expected an integer");
		*(int *)o->dst = (int)x;
		return 0;
	}
	case C0_OPT_LONG: {
		long long x = strtoll(v, &end, 10);
		if (end == v || *end || errno)
			return bad(spec, o->name, v, "expected an integer");
		*(long long *)o->dst = x;
		return 0;
	}
	case C0_OPT_DOUBLE: {
		double x = strtod(v, &end);
		if (end == v || *end || errno || x != x)
			return bad(spec, o->name, v, "expected a number");
		*(double *)o->dst = x;
		if (o->count)   /* given: a default that means "not given" (0) can then be told apart */
			*o->count = 1;
		return 0;
	}
	case C0_OPT_STRING:
		*(const char **)o->dst = v;
		return 0;
	case C0_OPT_DOUBLES:
	case C0_OPT_INTS:
		return parse_list(spec, o, v);
	default:
		return 2;
	}
}

int c0_opts_parse(const struct c0_cmd_spec *spec, int argc, char **argv, int *npos, char **pos)
{
	int np = 0, only_pos = 0, threads = 0;
	for (int i = 1; i < argc; i++) {
		char *a = argv[i];
		if (only_pos || a[0] != '-' || !a[1]) {
			if (spec->max_pos < 0 || np < spec->max_pos)
				pos[np] = a;       /* pos holds max_pos entries; the count is checked below */
			np++;
			continue;
		}
		if (!strcmp(a, "--")) {
			only_pos = 1;
			continue;
		}
		if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
			c0_opts_help(spec);
			return 1;
		}
		if (!strcmp(a, "--help-json")) {
			c0_opts_help_json(spec, NULL);
			return 1;
		}
		const struct c0_opt *o = NULL;
		const char *val = NULL;
		if (spec->threads && (!strcmp(a, "--threads") || !strncmp(a, "--threads=", 10))) {
			const char *v = a[9] ? a + 10 : i + 1 < argc ? argv[++i] : "";
			char *end;
			long n = strtol(v, &end, 10);
			if (!*v || *end || n < 1 || n > 4096)
				return bad(spec, "threads", v, "expected a positive number of threads");
			threads = (int)n;
			continue;
		}
		if (a[1] == '-') {
			const char *name = a + 2, *eq = strchr(name, '=');
			size_t l = eq ? (size_t)(eq - name) : strlen(name);
			for (int k = 0; k < spec->nopts; k++)
				if (strlen(spec->opts[k].name) == l && !strncmp(spec->opts[k].name, name, l))
					o = &spec->opts[k];
			if (eq)
				val = eq + 1;
		} else if (!a[2]) {
			for (int k = 0; k < spec->nopts; k++)
				if (spec->opts[k].shortname == a[1])
					o = &spec->opts[k];
		}
		if (!o) {
			fprintf(stderr, "col0rme %s: error: unknown option %s (see col0rme %s --help)\n", spec->name, a, spec->name);
			return 2;
		}
		if (o->type == C0_OPT_FLAG) {
			if (val)
				return bad(spec, o->name, val, "takes no value");
			*(int *)o->dst = 1;
			continue;
		}
		if (!val) {
			if (i + 1 >= argc)
				return bad(spec, o->name, "", "missing value");
			val = argv[++i];
		}
		if (set_value(spec, o, val))
			return 2;
	}
	if (np < spec->min_pos || (spec->max_pos >= 0 && np > spec->max_pos)) {
		fprintf(stderr, "col0rme %s: error: expected %s (see col0rme %s --help)\n", spec->name, spec->args, spec->name);
		return 2;
	}
	*npos = np;
	c0_threads_set(threads);
	return 0;
}
