/* The CLI's cleanup of a half-written output directory: SIGINT, SIGTERM,
 * SIGHUP and SIGABRT (a library's failed assertion), and exit() in the
 * middle of a run (libgomp's fatal error when a thread cannot be made),
 * remove the staging directory before the process ends. The library
 * installs no handler: a host program's signals are its own. */
#define _POSIX_C_SOURCE 200809L   /* sigaction under -std=c11 (clang does not imply it) */
#include "cli/cmdkit.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char g_stage[sizeof ((struct c0_outdir *)0)->stage];
static volatile sig_atomic_t g_active;

static void on_signal(int sig)
{
	if (g_active)
		c0_outdir_remove_flat(g_stage);
	signal(sig, SIG_DFL);
	raise(sig);
}

static void on_exit_clean(void)
{
	if (g_active)
		c0_outdir_remove_flat(g_stage);
}

void c0_cli_guard(const struct c0_outdir *o)
{
	static int installed;
	g_active = 0;
	snprintf(g_stage, sizeof g_stage, "%s", o->stage);
	g_active = 1;
	if (installed)
		return;
	installed = 1;
	atexit(on_exit_clean);
	const int sigs[] = { SIGINT, SIGTERM, SIGHUP, SIGABRT };
	for (int i = 0; i < 4; i++) {
		struct sigaction sa, old;
		memset(&sa, 0, sizeof sa);
		sa.sa_handler = on_signal;
		sigemptyset(&sa.sa_mask);
		/* keep a caller's choice to ignore the signal (nohup) */
		if (!sigaction(sigs[i], NULL, &old) && old.sa_handler == SIG_IGN)
			continue;
		sigaction(sigs[i], &sa, NULL);
	}
}

void c0_cli_unguard(void)
{
	g_active = 0;
}
