/* MPI ranks (built with COL0RME_MPI). MPI starts only under mpirun, so the
 * same binary runs as a plain program too. */
#include "core/comm.h"
#include "core/err.h"

#include <mpi.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int on, rank, size = 1;

int c0_comm_init(int *argc, char ***argv)
{
	/* launched by mpirun (Open MPI, or any PMI/PMIx launcher)? */
	if (!getenv("OMPI_COMM_WORLD_SIZE") && !getenv("PMI_SIZE") && !getenv("PMIX_RANK"))
		return 0;
	int prov;
	if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &prov) != MPI_SUCCESS)
		return c0_fail(C0_EINVAL, "MPI: cannot start");
	on = 1;
	MPI_Comm_rank(MPI_COMM_WORLD, &rank);
	MPI_Comm_size(MPI_COMM_WORLD, &size);
	return 0;
}

void c0_comm_finalize(void)
{
	if (on)
		MPI_Finalize();
	on = 0;
}

int c0_comm_rank(void) { return rank; }
int c0_comm_size(void) { return size; }

void c0_comm_max(double *v, int n)
{
	if (on && size > 1)
		MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
}

void c0_comm_sum(double *v, int n)
{
	if (on && size > 1)
		MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
}

int c0_comm_status(int st)
{
	if (!on || size == 1)
		return st;
	/* the lowest failing rank sends its status and message to all */
	int who = st ? rank : size, first;
	MPI_Allreduce(&who, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
	if (first == size)
		return 0;
	char msg[512];
	int code = st;
	snprintf(msg, sizeof msg, "%s", c0_errmsg());
	MPI_Bcast(&code, 1, MPI_INT, first, MPI_COMM_WORLD);
	MPI_Bcast(msg, sizeof msg, MPI_CHAR, first, MPI_COMM_WORLD);
	if (rank != first)
		c0_fail(code, "%s", msg);
	return code;
}

int c0_comm_gather_rows(void *buf, size_t row_bytes, int row0, int nrows)
{
	if (!on || size == 1)
		return 0;
	int my[2] = { row0, nrows }, *all = malloc(sizeof(int) * 2 * (size_t)size);
	int *cnt = malloc(sizeof(int) * (size_t)size), *dsp = malloc(sizeof(int) * (size_t)size);
	if (!all || !cnt || !dsp) {
		free(all), free(cnt), free(dsp);
		return C0_ENOMEM;
	}
	MPI_Allgather(my, 2, MPI_INT, all, 2, MPI_INT, MPI_COMM_WORLD);
	/* rows as a contiguous datatype: counts stay small for large images */
	MPI_Datatype row;
	MPI_Type_contiguous((int)row_bytes, MPI_BYTE, &row);
	MPI_Type_commit(&row);
	for (int k = 0; k < size; k++)
		dsp[k] = all[2 * k], cnt[k] = all[2 * k + 1];
	char *mine = (char *)buf + (size_t)row0 * row_bytes;
	if (rank == 0)
		MPI_Gatherv(MPI_IN_PLACE, nrows, row, buf, cnt, dsp, row, 0, MPI_COMM_WORLD);
	else
		MPI_Gatherv(mine, nrows, row, NULL, NULL, NULL, row, 0, MPI_COMM_WORLD);
	MPI_Type_free(&row);
	free(all), free(cnt), free(dsp);
	return 0;
}
