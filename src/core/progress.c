#include "core/progress.h"
#include "core/clock.h"

#include <omp.h>
#include <stdio.h>

static int enabled;

void c0_progress_enable(int on) { enabled = on; }
int c0_progress_enabled(void) { return enabled; }

void c0_progress_begin(struct c0_progress *p, const char *stage, double total)
{
	p->stage = stage;
	p->total = total > 0 ? total : 1;
	p->start = c0_now();
	p->last_draw = 0;
	/* inside a parallel region several lines would fight over one terminal
	 * line: the caller outside the region reports for all of them */
	p->active = enabled && !omp_in_parallel();
}

void c0_progress_update(struct c0_progress *p, double done)
{
	if (!p->active)
		return;
	double now = c0_now();
	if (now - p->last_draw < 0.1 && done < p->total)
		return;             /* redraw at most 10 times a second */
	p->last_draw = now;
	double f = done / p->total;
	if (f > 1)
		f = 1;
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
