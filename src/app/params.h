/* The run parameters, once: each row gives a field of struct c0_run_conf
 * its name (c0_run_conf_set, messages, Python), its command-line flag,
 * help line and default. The CLI's options and help, the library's
 * c0_run_conf_param and docs/params.md (`col0rme params --markdown`) are
 * all made from this table, so they cannot drift apart. */
#pragma once
#include "col0rme.h"

#include <stddef.h>

enum c0_ptype { C0_P_DOUBLE, C0_P_INT, C0_P_FLAG, C0_P_DOUBLES, C0_P_INTS, C0_P_ENUM, C0_P_STRING };

struct c0_param {
	const char *name;     /* the field's name */
	enum c0_ptype type;
	size_t off;           /* the field */
	size_t count;         /* lists: the count field, 0 for a fixed length */
	int max;              /* lists: capacity (the fixed length when count is 0) */
	const char *choices;  /* enums: names in value order, '|'-separated */
	const char *flag;     /* --flag, without the dashes (two parameters no command takes together may share one) */
	const char *metavar;  /* the value's form; NULL for a flag without a value */
	const char *help;     /* one line, what it does */
	const char *def;      /* the default, as text */
	const char *doc;      /* help and default, for c0_run_conf_param */
};

/* The table, in the order of the docs. */
const struct c0_param *c0_params(int *n);
/* The row of a parameter name, or NULL. */
const struct c0_param *c0_param_find(const char *name);
/* Sets p's field of c from text (c0_run_conf_set without the look-up);
 * messages name the parameter as shown (its name, or the caller's flag). */
int c0_param_set(const struct c0_param *p, struct c0_run_conf *c, const char *shown, const char *value);
/* Notes p as given in c (c0_param_set does; the CLI for the numbers it parses itself). */
void c0_param_mark_given(struct c0_run_conf *c, const struct c0_param *p);
/* 1 when the number parameter name was neither set by name nor moved from its default. */
int c0_param_assumed(const struct c0_run_conf *c, const char *name);
