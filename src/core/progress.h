/* Progress of long work. Two readers: a line on stderr (stage, percent,
 * ETA), shown only when enabled (the CLI enables it on a terminal or with
 * --verbose); and a run's observer (a sink: c0_run_conf's progress
 * callback), which hears each run stage's start and end and its fraction
 * done in between, and may ask the run to stop. Without either every call
 * is a no-op. */
#pragma once

struct c0_progress {
	const char *stage;
	double total;
	double start;
	double last_draw, last_sink;
	int active;   /* drawing the line */
	int sink;     /* telling the sink */
};

void c0_progress_enable(int on);
int c0_progress_enabled(void);
void c0_progress_begin(struct c0_progress *p, const char *stage, double total);
void c0_progress_update(struct c0_progress *p, double done);
void c0_progress_end(struct c0_progress *p);

/* The observer of one run, on the thread that runs it: fn(stage, fraction,
 * user) with the run stage's name; a nonzero return asks the run to stop,
 * which it does at its next stage (c0_progress_stage). While a sink is
 * attached the stderr line is not drawn (the sink's owner shows progress).
 * Calls from inside a parallel region are not passed on. */
typedef int (*c0_progress_cb)(const char *stage, double fraction, void *user);
struct c0_progress_sink {
	c0_progress_cb fn;
	void *user;
	const char *stage;   /* the run stage now working (a string literal) */
	double fraction;     /* the last told: a stage's parts never move it back */
	int cancelled;
};
/* Attaches s (fn NULL: none) to this thread until c0_progress_detach. */
void c0_progress_attach(struct c0_progress_sink *s, c0_progress_cb fn, void *user);
/* Ends the run's last stage (fraction 1 when st is 0) and detaches: st,
 * or C0_ECANCELED when the sink asked to stop. */
int c0_progress_detach(struct c0_progress_sink *s, int st);
/* A new run stage: the previous one ends (1), this one starts (0).
 * C0_ECANCELED (and its message) once the sink asked to stop, else 0. */
int c0_progress_stage(const char *stage);
