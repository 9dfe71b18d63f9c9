/* FFTW's planner is not thread-safe, and destroying a plan is no more so:
 * every plan is made inside the named critical section c0_fftw_plan, and
 * released here, inside the same one (tiles and drift blocks free theirs
 * from parallel regions). */
#pragma once
#include <complex.h>   /* before fftw3.h: fftw_complex is then C99 complex, as in its users */
#include <fftw3.h>

/* Releases p (NULL: nothing). */
static inline void c0_fftw_destroy(fftw_plan p)
{
	if (!p)
		return;
#pragma omp critical(c0_fftw_plan)
	fftw_destroy_plan(p);
}

/* The same for a single-precision plan. */
static inline void c0_fftwf_destroy(fftwf_plan p)
{
	if (!p)
		return;
#pragma omp critical(c0_fftw_plan)
	fftwf_destroy_plan(p);
}
