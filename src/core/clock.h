#pragma once
double c0_now(void);   /* monotonic seconds */
