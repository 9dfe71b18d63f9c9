#define _GNU_SOURCE
#include "core/threads.h"

#include <omp.h>
#include <sched.h>
#include <stdlib.h>
#include <unistd.h>

void c0_threads_startup(char **argv)
{
	if (getenv("OMP_WAIT_POLICY"))
		return;
	if (setenv("OMP_WAIT_POLICY", "PASSIVE", 1))
		return;
	/* libomp (clang) reads the variable lazily and needs no re-exec, but
	 * libgomp has read it already; the exec keeps the pid (mpirun's ranks) */
	execv("/proc/self/exe", argv);
}

int c0_threads_affinity(void)
{
	cpu_set_t set;
	CPU_ZERO(&set);
	if (sched_getaffinity(0, sizeof set, &set))
		return 1;
	int n = CPU_COUNT(&set);
	return n > 0 ? n : 1;
}

int c0_threads_set(int n)
{
	if (n <= 0) {
		const char *e = getenv("OMP_NUM_THREADS");
		n = e && atoi(e) > 0 ? atoi(e) : c0_threads_affinity();
	}
	omp_set_num_threads(n);
	return n;
}

int c0_threads_get(void)
{
	return omp_get_max_threads();
}

int c0_threads_here(void)
{
	return omp_in_parallel() ? 1 : omp_get_max_threads();
}

int c0_threads_side(int n)
{
	const int t = c0_threads_here();
	return t > 1 && n > t ? n - n % t : n;
}
