#include "core/progress.h"
#include "core/clock.h"
#include "core/err.h"

#include <omp.h>
#include <stdio.h>

static int enabled;
static _Thread_local struct c0_progress_sink *g_sink;

void c0_progress_enable(int on) { enabled = on; }
int c0_progress_enabled(void) { return enabled; }

static void tell(struct c0_progress_sink *s, const char *stage, double f)
{
	if (f < s->fraction)
		return;
	s->fraction = f;
	if (s->fn && !s->cancelled && s->fn(stage, f, s->user))
		s->cancelled = 1;
}

void c0_progress_attach(struct c0_progress_sink *s, c0_progress_cb fn, void *user)
{
	*s = (struct c0_progress_sink){ fn, user, NULL, 0, 0 };
	g_sink = fn ? s : NULL;
}

static int cancelled(const struct c0_progress_sink *s)
{
	return c0_fail(C0_ECANCELED, "the run was stopped by its progress callback (in %s)", s->stage ? s->stage : "its start");
}

int c0_progress_detach(struct c0_progress_sink *s, int st)
{
	if (g_sink != s)
		return st;
	if (!st && s->stage)
		tell(s, s->stage, 1);
	g_sink = NULL;
	return !st && s->cancelled ? cancelled(s) : st;
}

int c0_progress_stage(const char *stage)
{
	struct c0_progress_sink *s = g_sink;
	if (!s)
		return 0;
	if (s->stage)
		tell(s, s->stage, 1);
	s->stage = stage, s->fraction = 0;
	tell(s, stage, 0);
	return s->cancelled ? cancelled(s) : 0;
}

void c0_progress_begin(struct c0_progress *p, const char *stage, double total)
{
	p->stage = stage;
	p->total = total > 0 ? total : 1;
	p->start = c0_now();
	p->last_draw = p->last_sink = 0;
	/* inside a parallel region several lines would fight over one terminal
	 * line, and the sink belongs to the run's own thread: the caller outside
	 * the region reports for all of them */
	p->sink = g_sink && g_sink->stage && !omp_in_parallel();
	p->active = enabled && !g_sink && !omp_in_parallel();
}

void c0_progress_update(struct c0_progress *p, double done)
{
	if (!p->active && !p->sink)
		return;
	double now = c0_now();
	double f = done / p->total;
	if (f > 1)
		f = 1;
	if (p->sink && g_sink && now - p->last_sink >= 0.1 && f > g_sink->fraction && f < 1) {   /* at most 10 times a second */
		p->last_sink = now;
		tell(g_sink, g_sink->stage, f);
	}
	if (!p->active || (now - p->last_draw < 0.1 && done < p->total))
		return;             /* redraw at most 10 times a second */
	p->last_draw = now;
	double el = now - p->start;
	if (f > 0.01)
		fprintf(stderr, "\r%-12s %3.0f%%  %5.1fs  ETA %5.1fs ", p->stage, 100 * f, el, el * (1 - f) / f);
	else
		fprintf(stderr, "\r%-12s %3.0f%%  %5.1fs            ", p->stage, 100 * f, el);
	fflush(stderr);
}

void c0_progress_end(struct c0_progress *p)
{
	if (!p->active)
		return;
	fprintf(stderr, "\r%-12s done in %.2fs%24s\n", p->stage, c0_now() - p->start, "");
	p->active = 0;
}
