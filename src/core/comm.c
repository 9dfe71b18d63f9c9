/* One process: built when MPI is not (see src/mpi/comm_mpi.c). */
#ifndef C0_HAVE_MPI
#include "core/comm.h"

#include <stdlib.h>

int c0_comm_init(int *argc, char ***argv)
{
	(void)argc, (void)argv;
	return 0;
}
void c0_comm_finalize(void) {}
int c0_comm_rank(void) { return 0; }
int c0_comm_size(void) { return 1; }
void c0_comm_max(double *v, int n) { (void)v, (void)n; }
void c0_comm_sum(double *v, int n) { (void)v, (void)n; }
int c0_comm_status(int st) { return st; }
int c0_comm_gather_rows(void *buf, size_t row_bytes, int row0, int nrows)
{
	(void)buf, (void)row_bytes, (void)row0, (void)nrows;
	return 0;
}
#endif
