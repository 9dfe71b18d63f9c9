/* Threads that behave on a shared machine.
 *
 * OpenMP threads that spin at barriers steal the cores other processes need
 * (a 1.4 s run took 5.5 s next to two busy processes): the program asks for
 * the passive wait policy, and the default thread count is the number of
 * CPUs in this process's affinity mask (what taskset, cgroups or a batch
 * system left it), not the machine's. */
#pragma once

/* Call first thing in main. libgomp reads OMP_WAIT_POLICY when it is loaded,
 * before main runs, so when the variable is unset this sets it to PASSIVE and
 * re-executes the program (once; a failed exec is ignored). A value the user
 * set is kept. */
void c0_threads_startup(char **argv);
/* CPUs in the affinity mask (at least 1). */
int c0_threads_affinity(void);
/* Thread count for the parallel regions: n > 0 as given, else
 * OMP_NUM_THREADS when set, else the affinity mask. Returns the count used. */
int c0_threads_set(int n);
int c0_threads_get(void);
/* Threads a parallel region started here may have: 1 inside another team
 * (nested regions run alone), else c0_threads_get(). What per-thread
 * workspaces are sized by. */
int c0_threads_here(void);
/* A loop over n items, one a thread, leaves threads idle at its end when n is
 * more than the threads but not a multiple of them (5 stacks on 2 threads: the
 * fifth alone, a core idle). Items [0, c0_threads_side(n)) go side by side;
 * the rest, n % threads of them, one after another, each with every thread
 * (its own parallel regions then run). n when n <= threads. */
int c0_threads_side(int n);
