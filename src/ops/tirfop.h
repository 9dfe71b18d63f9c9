/* The MA-TIRF forward operator on a volume stored as M columns times nz
 * depths (u[j * M + k]): y_q[k] = sum_j W[q][j] u[j * M + k] for each of the
 * nq angles (y[q * M + k]), W from optics/tirf.h. */
#pragma once
#include <stddef.h>

struct c0_tirfop { int nq, nz; size_t M; const double *W; };

void c0_tirfop_forward(const struct c0_tirfop *o, const float *u, float *y);
/* u += W^T y (adds, so that a regulariser's adjoint can go first) */
void c0_tirfop_adjoint_add(const struct c0_tirfop *o, const float *y, float *u);
