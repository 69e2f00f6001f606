/*
 * The robot's own speed (mvod.speed_t) for --scale external: a subscription on a live LCM URL,
 * or an LCM log (file://PATH) read in step with the frames. Samples are matched to frames by
 * their utime, never by when they arrived.
 */
#ifndef MVOD_SPEED_H
#define MVOD_SPEED_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mvod/geom.h"

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

/*
 * Writing (mvod speed-log): the speed a robot's wheels would report along a known path, as an
 * LCM log of mvod.speed_t, for --scale external without a robot (benchmarks, tests). The
 * message of pose i (from the second) has utime = t[i] in microseconds, speed = the distance
 * from pose i-1 over the time between, distance = the path length so far.
 */
struct mvod_speed_log_opts {
	const char *channel; /* MVOD_DEFAULT_SPEED_CHANNEL */
	long samples;        /* write only the first this many messages (speed that stops); -1: all */
	long from;           /* write none before message `from` (0-based: speed that starts late) */
	bool no_distance;    /* leave has_distance false: mvod integrates the speed */
	/*
	 * A real odometer: each step's distance times (1 + bias) and times (1 + noise g), g a
	 * standard normal drawn per message from a fixed 64-bit LCG seeded by seed, so a run
	 * repeats on every machine; the speed and the distance follow from those steps.
	 */
	double noise, bias;
	uint64_t seed; /* 1 */
};
void mvod_speed_log_opts_default(struct mvod_speed_log_opts *o);
/*
 * Writes the n poses' (times t in seconds, positions pose[i].t in metres) messages to path,
 * through the output policy (util/output.h: an input of this process is refused; a regular
 * file is replaced only once the first event is written), each event stamped with its
 * message's utime. t must increase. Returns the number of messages written, or -errno with a
 * reason in err.
 */
int mvod_speed_log_write(const char *path, int n, const double *t, const struct mvod_pose *pose,
			 const struct mvod_speed_log_opts *o, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif

#endif
