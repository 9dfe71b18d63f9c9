/* JSON report (cJSON): every command writes its parameters, estimates,
 * timings and versions here. */
#pragma once
#include <cjson/cJSON.h>

cJSON *c0_report_new(const char *command, int argc, char **argv);
/* Adds an array of n doubles under key. */
cJSON *c0_report_add_array(cJSON *obj, const char *key, const double *v, int n);
/* Serialises atomically to path. */
int c0_report_write(const cJSON *report, const char *path);
