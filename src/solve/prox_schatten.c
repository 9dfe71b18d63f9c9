#include "solve/prox_schatten.h"

#include <math.h>

void c0_eig3(double a[3][3], double v[3][3])
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			v[i][j] = i == j;
	for (int sweep = 0; sweep < 12; sweep++) {
		double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
		if (off < 1e-15 * (fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2])) || off == 0)
			break;
		for (int p = 0; p < 2; p++)
			for (int q = p + 1; q < 3; q++) {
				if (a[p][q] == 0)
					continue;
				double th = (a[q][q] - a[p][p]) / (2 * a[p][q]);
				double t = (th >= 0 ? 1 : -1) / (fabs(th) + sqrt(th * th + 1));
				double cs = 1 / sqrt(t * t + 1), sn = t * cs;
				for (int k = 0; k < 3; k++) {      /* A <- J^T A J */
					double akp = a[k][p], akq = a[k][q];
					a[k][p] = cs * akp - sn * akq;
					a[k][q] = sn * akp + cs * akq;
				}
				for (int k = 0; k < 3; k++) {
					double apk = a[p][k], aqk = a[q][k];
					a[p][k] = cs * apk - sn * aqk;
					a[q][k] = sn * apk + cs * aqk;
				}
				for (int k = 0; k < 3; k++) {
					double vkp = v[k][p], vkq = v[k][q];
					v[k][p] = cs * vkp - sn * vkq;
					v[k][q] = sn * vkp + cs * vkq;
				}
			}
	}
}

void c0_spectral_clip(double h[6], double k)
{
	const double r2 = sqrt(2.0);
	double a[3][3] = { { h[0], h[3] / r2, h[4] / r2 }, { h[3] / r2, h[1], h[5] / r2 }, { h[4] / r2, h[5] / r2, h[2] } };
	double v[3][3], e[3];
	c0_eig3(a, v);
	int clip = 0;
	for (int j = 0; j < 3; j++) {
		e[j] = a[j][j];
		if (e[j] > k) e[j] = k, clip = 1;
		if (e[j] < -k) e[j] = -k, clip = 1;
	}
	if (!clip)
		return;
	double m[3][3];
	for (int p = 0; p < 3; p++)
		for (int q = 0; q < 3; q++)
			m[p][q] = v[p][0] * e[0] * v[q][0] + v[p][1] * e[1] * v[q][1] + v[p][2] * e[2] * v[q][2];
	h[0] = m[0][0], h[1] = m[1][1], h[2] = m[2][2];
	h[3] = r2 * m[0][1], h[4] = r2 * m[0][2], h[5] = r2 * m[1][2];
}
