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

/*
 * CLOCK_REALTIME minus CLOCK_MONOTONIC now, microseconds: added to a camera's monotonic frame
 * time, the same instant in Unix time (--clock realtime). Sampled per frame, so a step of the
 * wall clock (NTP, a GPS fix) shows in the next frame's time.
 */
static inline int64_t mvod_realtime_offset_us(void)
{
	struct timespec rt, mono;
	clock_gettime(CLOCK_REALTIME, &rt);
	clock_gettime(CLOCK_MONOTONIC, &mono);
	return ((int64_t)rt.tv_sec - mono.tv_sec) * 1000000 + (rt.tv_nsec - mono.tv_nsec) / 1000;
}

#ifdef __cplusplus
}
#endif

#endif
