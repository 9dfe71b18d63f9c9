/* The run's own warnings that the single-step calls share (pipeline.c). */
#pragma once
#include "col0rme.h"

struct c0_result;
/* The one warning of an MA-TIRF run that left wavelength_nm or n_sample at its default. */
void c0_warn_assumed_optics(struct c0_result *r, const struct c0_run_conf *c);
