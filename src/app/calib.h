/* The camera's calibration maps (calib.c). */
#pragma once
#include "app/result.h"
#include "app/pipeline_conf.h"
#include "io/frames.h"

/* The camera calibration maps of c (offset_map, variance_map, gain_map):
 * read and checked against f (size, values, the offset map's region),
 * attached to the frames and sc's support, owned by r. */
int c0_calib_attach(const struct c0_run_conf *c, struct c0_frames *f, int n, struct c0_stage_confs *sc, struct c0_result *r);
