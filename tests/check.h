/* Minimal test harness: each test file is one CTest test; it prints one
 * line per failed check and a closing "N passed, N failed" line. */
#pragma once
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <time.h>

static int check_pass, check_fail;

#define CHECK(c) do { if (c) check_pass++; else { check_fail++; \
	fprintf(stderr, "%s:%d: CHECK(%s) failed\n", __FILE__, __LINE__, #c); } } while (0)
#define CHECK_MSG(c, ...) do { if (c) check_pass++; else { check_fail++; \
	fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__, __LINE__, #c); \
	fprintf(stderr, __VA_ARGS__); fputc('\n', stderr); } } while (0)
#define CHECK_CLOSE(a, b, tol) do { double a_ = (a), b_ = (b); \
	CHECK_MSG(fabs(a_ - b_) <= (tol), "%s = %.12g, %s = %.12g, tol %g", #a, a_, #b, b_, (double)(tol)); } while (0)
/* relative to max(|a|, |b|, 1e-300) */
#define CHECK_REL(a, b, tol) do { double a_ = (a), b_ = (b); \
	double s_ = fmax(fmax(fabs(a_), fabs(b_)), 1e-300); \
	CHECK_MSG(fabs(a_ - b_) <= (tol) * s_, "%s = %.12g, %s = %.12g, rel tol %g", #a, a_, #b, b_, (double)(tol)); } while (0)

/* inner product, for the adjoint tests: <A x, y> = <x, A^T y> */
static inline double dot(const double *a, const double *b, size_t n)
{
	double s = 0;
	for (size_t i = 0; i < n; i++)
		s += a[i] * b[i];
	return s;
}

static inline double dotf(const float *a, const float *b, size_t n)
{
	double s = 0;
	for (size_t i = 0; i < n; i++)
		s += (double)a[i] * b[i];
	return s;
}

/* each test function's line gives the process CPU seconds it took (all threads),
 * to see where a test's time goes */
#define RUN(t) do { int f0_ = check_fail; clock_t c0_ = clock(); t(); \
	fprintf(stderr, "%-40s %s (%.1f s CPU)\n", #t, check_fail == f0_ ? "ok" : "FAILED", \
		(double)(clock() - c0_) / CLOCKS_PER_SEC); } while (0)
#define CHECK_DONE() (printf("%d passed, %d failed\n", check_pass, check_fail), check_fail ? 1 : 0)
