/* report.json's support sections (report_json_support.c). */
#pragma once
#include "stages/support.h"
#include <cjson/cJSON.h>

/* One support stack's entry (lambda rule, FRC, precision). */
cJSON *c0_report_support_stack(const char *name, const struct c0_support_result *s, const struct c0_support_conf *c);
/* "support_parameters". */
void c0_report_support_params(cJSON *rep, const struct c0_support_conf *c);
