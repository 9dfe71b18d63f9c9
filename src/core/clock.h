#pragma once
double c0_now(void);           /* monotonic seconds */
double c0_cpu_seconds(void);   /* this process's CPU seconds so far, user + system, all threads */
