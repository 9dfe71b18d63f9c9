#define _POSIX_C_SOURCE 200809L
#include "io/report.h"
#include "io/atomic.h"
#include "core/err.h"
#include "core/threads.h"
#include "core/comm.h"
#include "c0_version.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <tiffio.h>

cJSON *c0_report_new(const char *command, int argc, char **argv)
{
	cJSON *r = cJSON_CreateObject();
	cJSON_AddStringToObject(r, "command", command);
	cJSON *args = cJSON_AddArrayToObject(r, "argv");
	for (int i = 0; i < argc; i++)
		cJSON_AddItemToArray(args, cJSON_CreateString(argv[i]));
	cJSON *v = cJSON_AddObjectToObject(r, "versions");
	cJSON_AddStringToObject(v, "col0rme", C0_VERSION);
	char tv[64];
	snprintf(tv, sizeof tv, "%s", TIFFGetVersion());
	tv[strcspn(tv, "\n")] = '\0';     /* first line: "LIBTIFF, Version x.y.z" */
	cJSON_AddStringToObject(v, "libtiff", tv);
	cJSON_AddStringToObject(v, "cjson", cJSON_Version());
	char ts[32];
	time_t now = time(NULL);
	struct tm tm;
	gmtime_r(&now, &tm);
	strftime(ts, sizeof ts, "%Y-%m-%dT%H:%M:%SZ", &tm);
	cJSON_AddStringToObject(r, "created", ts);
	cJSON_AddNumberToObject(r, "threads", c0_threads_get());
	cJSON_AddNumberToObject(r, "mpi_ranks", c0_comm_size());
	const char *wp = getenv("OMP_WAIT_POLICY");
	cJSON_AddStringToObject(r, "omp_wait_policy", wp ? wp : "");
	return r;
}

cJSON *c0_report_add_array(cJSON *obj, const char *key, const double *v, int n)
{
	cJSON *a = cJSON_CreateDoubleArray(v, n);
	cJSON_AddItemToObject(obj, key, a);
	return a;
}

int c0_report_write(const cJSON *report, const char *path)
{
	char *s = cJSON_Print(report);
	if (!s)
		return c0_fail(C0_ENOMEM, "%s: cannot serialise report", path);
	size_t n = strlen(s);
	s[n] = '\n';   /* cJSON leaves room: replace the terminator, write n+1 */
	int st = c0_write_file(path, s, n + 1);
	free(s);
	return st;
}
