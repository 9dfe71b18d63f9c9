#include "core/order.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>

static int cmp_double(const void *a, const void *b)
{
	const double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

double c0_median(double *v, size_t n)
{
	if (!n)
		return NAN;
	if (n <= 16)   /* a pixel's few neighbours: insertion sort, no call per comparison */
		for (size_t i = 1; i < n; i++)
			for (size_t j = i; j > 0 && v[j - 1] > v[j]; j--) {
				const double t = v[j];
				v[j] = v[j - 1], v[j - 1] = t;
			}
	else
		qsort(v, n, sizeof *v, cmp_double);
	return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double c0_median_of(const float *v, size_t n)
{
	double *w = c0_alloc(n ? n : 1, sizeof *w);
	if (!w)
		return NAN;
	for (size_t i = 0; i < n; i++)
		w[i] = v[i];
	const double m = c0_median(w, n);
	free(w);
	return m;
}

/* the k-th smallest of a[0..n), k < n, in place: quickselect with a
 * three-way partition (a fine grid's values are mostly equal zeros, on which
 * a two-way one goes quadratic). The same value as a sort's a[k], in
 * expected linear time: sorting 67 M fine pixels took most of a 2048 x 2048
 * report. */
static float select_k(float *a, size_t n, size_t k)
{
	size_t lo = 0, hi = n;
	while (hi - lo > 1) {
		float x = a[lo], y = a[lo + (hi - lo) / 2], z = a[hi - 1];
		const float p = x < y ? (y < z ? y : x < z ? z : x) : (x < z ? x : y < z ? z : y);   /* median of 3 */
		size_t lt = lo, i = lo, gt = hi;    /* [lo,lt) < p, [lt,i) == p, [gt,hi) > p */
		while (i < gt) {
			const float v = a[i];
			if (v < p)
				a[i++] = a[lt], a[lt++] = v;
			else if (v > p)
				a[i] = a[--gt], a[gt] = v;
			else
				i++;
		}
		if (k < lt)
			hi = lt;
		else if (k >= gt)
			lo = gt;
		else
			return p;
	}
	return a[lo];
}

double c0_quantile(const float *v, size_t n, double q)
{
	float *s = c0_alloc(n ? n : 1, sizeof *s);
	size_t m = 0;
	for (size_t i = 0; s && i < n; i++)
		if (!isnan(v[i]))
			s[m++] = v[i];
	const double r = m ? select_k(s, m, (size_t)fmin((double)m - 1, floor(q * (double)m))) : 0;
	free(s);
	return r;
}
