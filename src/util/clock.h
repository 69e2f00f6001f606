/* The clock intervals are measured on. */
#ifndef MVOD_CLOCK_H
#define MVOD_CLOCK_H

#include <stdint.h>
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

/* The same clock in whole microseconds, the unit of frame timestamps, for comparing with them. */
static inline int64_t mvod_now_us(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

#ifdef __cplusplus
}
#endif

#endif
