/*
 * The robot's own speed (mvod.speed_t) for --scale external: a subscription on a live LCM URL,
 * or an LCM log (file://PATH) read in step with the frames. Samples are matched to frames by
 * their utime, never by when they arrived.
 */
#ifndef MVOD_SPEED_H
#define MVOD_SPEED_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MVOD_DEFAULT_SPEED_CHANNEL "MVOD_SPEED"
/*
 * A frame further than this from the nearest sample gets no odometer (microseconds): at
 * 10 m/s a wheel speed held for 0.5 s is off by under 0.5 m/s per 1 m/s^2 of acceleration.
 */
#define MVOD_SPEED_STALE_US 500000
/* Samples kept: 2.5 s at 100 Hz, a frame's time is never older than the newest 0.5 s. */
#define MVOD_SPEED_SAMPLES 256
/* A speed beyond this (m/s) is refused as garbage. */
#define MVOD_SPEED_MAX 100.0
/*
 * Sample times (utime, microseconds) are taken in [0, this]: 73 000 years, past any clock,
 * and small enough that the difference of two times and of a time and a frame's never
 * overflows int64 (a utime of +-(2^63 - 1) did: undefined behaviour, UBSan).
 */
#define MVOD_SPEED_MAX_UTIME (INT64_MAX / 4)

struct mvod_speed;

/*
 * url: an LCM URL to subscribe on ("" = LCM's default), or file://PATH[?...] to read the log
 * PATH. Returns 0 or -errno with the reason in err.
 */
int mvod_speed_create(const char *url, const char *channel, struct mvod_speed **out, char *err,
		      size_t errlen);
void mvod_speed_destroy(struct mvod_speed *s);

/*
 * The odometer at utime, in metres: takes in what arrived (live) or reads the log up to the
 * first sample after utime, then interpolates between the samples around utime (distance
 * when the messages carry it, else speed integrated by the trapezoid rule), or extrapolates
 * the nearest at its speed up to MVOD_SPEED_STALE_US. -EAGAIN when no sample is that close.
 */
int mvod_speed_odometer(struct mvod_speed *s, int64_t utime, double *metres);

/* Messages refused so far, by reason, for the caller to log. */
struct mvod_speed_counts {
	int64_t accepted;
	int64_t bad_type;  /* not an mvod.speed_t (its fingerprint differs) */
	int64_t bad_time;  /* utime not after the previous sample's, or not in [0, MAX_UTIME] */
	int64_t bad_value; /* speed or distance not finite, or |speed| > MVOD_SPEED_MAX */
	int64_t last_bad_utime; /* the utime of the last one refused for its time */
};
void mvod_speed_counts(const struct mvod_speed *s, struct mvod_speed_counts *c);

#ifdef __cplusplus
}
#endif

#endif
