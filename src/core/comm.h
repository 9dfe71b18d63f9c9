/* The processes that share one run (MPI ranks), behind a small interface:
 * the library calls these everywhere, and without MPI at build time (or
 * when not started by mpirun) they describe one process and do nothing.
 * The MPI versions are in src/mpi/comm_mpi.c, built with COL0RME_MPI. */
#pragma once
#include <stddef.h>

/* Starts MPI when the program was launched by mpirun; else a no-op. */
int c0_comm_init(int *argc, char ***argv);
void c0_comm_finalize(void);
int c0_comm_rank(void);
int c0_comm_size(void);
/* In place over all ranks: element-wise maximum / sum of n doubles. */
void c0_comm_max(double *v, int n);
void c0_comm_sum(double *v, int n);
/* Status agreed by all ranks: the first non-zero status of any rank (so
 * that no rank waits forever for one that failed). */
int c0_comm_status(int st);
/* Every rank holds buf (rows of row_bytes) filled in rows row0..row0+nrows-1;
 * afterwards rank 0 holds every rank's rows. */
int c0_comm_gather_rows(void *buf, size_t row_bytes, int row0, int nrows);
