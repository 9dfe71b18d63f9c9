/* Progress line on stderr for long work: stage, percent, ETA.
 * Shown only when enabled (the CLI enables it on a terminal or with
 * --verbose); otherwise every call is a no-op. */
#pragma once

struct c0_progress {
	const char *stage;
	double total;
	double start;
	double last_draw;
	int active;
};

void c0_progress_enable(int on);
int c0_progress_enabled(void);
void c0_progress_begin(struct c0_progress *p, const char *stage, double total);
void c0_progress_update(struct c0_progress *p, double done);
void c0_progress_end(struct c0_progress *p);
