#include "cli/confopts.h"
#include "app/params.h"
#include "core/err.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The CLI's own rows (not run parameters). */
static int cli_rows(struct c0_conf_cli *m, const char *param, struct c0_opt *o)
{
	if (!strcmp(param, "channel"))
		*o = (struct c0_opt){ "channel", 0, C0_OPT_INT, &m->channel, "K", "read only channel K of multi-channel files",
				      "every channel, one stack per angle in order", 0, NULL };
	else if (!strcmp(param, "no_drift"))
		*o = (struct c0_opt){ "no-drift", 0, C0_OPT_FLAG, &m->no_drift, NULL, "the same as --drift off", NULL, 0, NULL };
	else
		return 0;
	return 1;
}

/* The option of table row i (app/params.h): numbers and lists straight into
 * m->c, the named choices as text (set by name in c0_conf_cli_finish). */
static struct c0_opt row(struct c0_conf_cli *m, int i)
{
	int n;
	const struct c0_param *p = &c0_params(&n)[i];
	void *f = (char *)&m->c + p->off;
	struct c0_opt o = { p->flag, 0, C0_OPT_DOUBLE, f, p->metavar, p->help, p->def, 0, NULL };
	switch (p->type) {
	case C0_P_DOUBLE: o.count = &m->given[i]; break;
	case C0_P_INT: o.type = C0_OPT_INT; break;
	case C0_P_FLAG: o.type = p->metavar ? C0_OPT_INT : C0_OPT_FLAG; break;
	case C0_P_STRING: o.type = C0_OPT_STRING; break;
	case C0_P_ENUM: o.type = C0_OPT_STRING, o.dst = &m->choice[i], o.defhint = NULL; break;
	case C0_P_DOUBLES:
	case C0_P_INTS:
		o.type = p->type == C0_P_INTS ? C0_OPT_INTS : C0_OPT_DOUBLES, o.max = p->max;
		o.count = p->count ? (int *)((char *)&m->c + p->count) : &m->given[i];
		break;
	}
	return o;
}

/* The name of enum value v of choices ("l1|cel0") into buf. */
static const char *choice_name(const char *choices, int v, char *buf, size_t n)
{
	const char *s = choices;
	for (int k = 0; k < v && s; k++)
		s = strchr(s, '|') ? strchr(s, '|') + 1 : NULL;
	size_t l = s ? strcspn(s, "|") : 0;
	snprintf(buf, n, "%.*s", (int)l, s ? s : "");
	return buf;
}

void c0_conf_cli_init(struct c0_conf_cli *m)
{
	memset(m, 0, sizeof *m);
	c0_run_conf_init(&m->c);
	int n;
	const struct c0_param *t = c0_params(&n);
	if (n > C0_CLI_MAXPARAMS) {   /* a row past the end would lose its option silently */
		fprintf(stderr, "col0rme: internal error: %d parameters, C0_CLI_MAXPARAMS %d\n", n, C0_CLI_MAXPARAMS);
		abort();
	}
	for (int i = 0; i < n; i++)
		if (t[i].type == C0_P_ENUM)   /* the default's name: the help shows it */
			m->choice[i] = choice_name(t[i].choices, *(int *)((char *)&m->c + t[i].off), m->names[i], sizeof m->names[i]);
}

int c0_conf_cli_opts(struct c0_conf_cli *m, const char *const *params, struct c0_opt *o)
{
	int k = 0;
	for (; params[k]; k++) {
		const struct c0_param *p = c0_param_find(params[k]);
		int n;
		if (p)
			o[k] = row(m, (int)(p - c0_params(&n)));
		else if (!cli_rows(m, params[k], &o[k]))
			o[k] = (struct c0_opt){ params[k], 0, C0_OPT_FLAG, &m->no_drift, NULL, "(unknown parameter)", NULL, 0, NULL };
	}
	return k;
}

int c0_conf_cli_table(struct c0_conf_cli *m, const char *const *params, const char **outdir, int *force, int *verbose,
		      int *progress_json, struct c0_opt *o)
{
	o[0] = (struct c0_opt){ "output", 'o', C0_OPT_STRING, outdir, "DIR", "output directory (created; must be empty unless --force)", NULL, 0, NULL };
	int n = 1 + c0_conf_cli_opts(m, params, o + 1);
	o[n++] = (struct c0_opt){ "force", 0, C0_OPT_FLAG, force, NULL, "write into a non-empty output directory", NULL, 0, NULL };
	o[n++] = (struct c0_opt){ "verbose", 0, C0_OPT_FLAG, verbose, NULL, "show progress even when not on a terminal", NULL, 0, NULL };
	o[n++] = (struct c0_opt){ "progress-json", 0, C0_OPT_FLAG, progress_json, NULL, C0_PROGRESS_JSON_HELP, NULL, 0, NULL };
	return n;
}

int c0_conf_cli_finish(struct c0_conf_cli *m)
{
	int n, st = C0_OK;
	const struct c0_param *t = c0_params(&n);
	for (int i = 0; i < n && !st; i++) {
		if (m->given[i])   /* a number parsed straight into m->c */
			c0_param_mark_given(&m->c, &t[i]);
		if (t[i].type == C0_P_ENUM)
			st = c0_param_set(&t[i], &m->c, t[i].name, m->choice[i]);
		else if (t[i].type == C0_P_DOUBLE && m->given[i] && !strcmp(t[i].name, "pixel_nm") &&
			 !(m->c.pixel_nm > 0 && isfinite(m->c.pixel_nm)))
			st = c0_fail(C0_EINVAL, "pixel_nm %g: must be a positive number of nm", m->c.pixel_nm);
		else if (!t[i].count && t[i].max && m->given[i] && m->given[i] != t[i].max)
			st = c0_fail(C0_EINVAL, "%s: expected %s", t[i].name, t[i].metavar);
	}
	if (!st && m->no_drift)
		st = c0_run_conf_set(&m->c, "drift", "off");
	return st;
}

/* The flag of parameter name[0..l) (in extra first, if given), or NULL. */
static const char *flag_of(const char *name, size_t l, const struct c0_cli_name *extra, char *buf, size_t n)
{
	for (; extra && extra->param; extra++)
		if (strlen(extra->param) == l && !strncmp(extra->param, name, l))
			return extra->flag;
	if (l == 6 && !strncmp(name, "outdir", 6))
		return "-o";
	if (l == 5 && !strncmp(name, "force", 5))
		return "--force";
	int np;
	const struct c0_param *t = c0_params(&np);
	for (int i = 0; i < np; i++)
		if (strlen(t[i].name) == l && !strncmp(t[i].name, name, l)) {
			snprintf(buf, n, "--%s", t[i].flag);
			return buf;
		}
	if (l == 7 && !strncmp(name, "channel", 7))
		return "--channel";
	return NULL;
}

static int word(int ch)
{
	return isalnum((unsigned char)ch) || ch == '_';
}

/* A parameter name in a message is the first word, or has an underscore, or
 * is followed by its value, a colon or a closing parenthesis: "3 angles for"
 * stays prose. */
void c0_cli_flags(const char *msg, const struct c0_cli_name *extra, char *buf, size_t n)
{
	size_t k = 0;
	for (const char *p = msg; *p && k + 1 < n;) {
		if (!word(*p) || (p > msg && (word(p[-1]) || p[-1] == '.' || p[-1] == '/' || p[-1] == '-'))) {
			buf[k++] = *p++;
			continue;
		}
		const char *e = p;
		while (word(*e))
			e++;
		char fb[64];
		const char *f = flag_of(p, (size_t)(e - p), extra, fb, sizeof fb);
		int cited = (p == msg && (!*e || *e == ' ' || *e == ':')) || memchr(p, '_', (size_t)(e - p)) ||
			    *e == ':' || *e == ')' || (*e == ' ' && (isdigit((unsigned char)e[1]) || e[1] == '-'));
		if (*e == '.' || *e == '/')
			cited = 0;   /* a file name */
		const char *src = f && cited ? f : p;
		size_t l = f && cited ? strlen(f) : (size_t)(e - p);
		for (size_t i = 0; i < l && k + 1 < n; i++)
			buf[k++] = src[i];
		p = e;
	}
	buf[k] = '\0';
}
