/* The clock intervals are measured on. */
#ifndef MVOD_CLOCK_H
#define MVOD_CLOCK_H

#include <time.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Seconds on CLOCK_MONOTONIC, for rates, periods and timeouts: it never jumps with the wall
 * clock. Frame timestamps come from the source, never from here. Inline: a call per frame.
 */
static inline double mvod_now_s(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

#ifdef __cplusplus
}
#endif

#endif
