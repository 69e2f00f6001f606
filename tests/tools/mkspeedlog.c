/*
 * mkspeedlog: an LCM log of mvod.speed_t made from a ground-truth trajectory, the exact speed
 * a robot's wheels would report, for --scale external (tests and BENCHMARKS.md).
 *
 *   mkspeedlog GT OUT.lcmlog [--times FILE] [--channel NAME] [--samples N] [--no-distance]
 *              [--wrong-type] [--decreasing] [--noise F] [--bias F] [--seed N] [--from N]
 *
 * GT: TUM (its own times) or KITTI (times from --times, a KITTI times.txt, seconds). One
 * message per pose from the second on: utime = the pose's time in microseconds, speed = the
 * distance from the pose before over the time between, distance = the path length so far.
 * --samples N: only the first N messages (speed that stops arriving); --from N: none before
 * the N-th (0-based: speed that starts late). --no-distance: leave
 * has_distance false (mvod integrates speed). --wrong-type: mvod.pose_t messages on the
 * channel instead. --decreasing: the 10th message's time goes back before the 9th's.
 * --noise F, --bias F: a real odometer's speed, the true one times (1 + F) (bias) and times
 * (1 + F g) with g a standard normal drawn per message (noise; a fixed --seed, default 1, so
 * runs repeat); the distance is then that speed summed over the time between messages.
 */
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <lcm/eventlog.h>

#include "mvod/traj.h"
#include "mvod_pose_t.h"
#include "mvod_speed_t.h"

struct opts {
	const char *gt, *out, *times, *channel;
	long samples, from;
	bool no_distance, wrong_type, decreasing;
	double noise, bias;
	unsigned long seed;
};

static int parse(int argc, char **argv, struct opts *o)
{
	*o = (struct opts){.channel = "MVOD_SPEED", .samples = -1, .seed = 1};
	int pos = 0;
	for (int i = 1; i < argc; i++) {
		const char *a = argv[i];
		bool more = i + 1 < argc;
		if (!strcmp(a, "--times") && more)
			o->times = argv[++i];
		else if (!strcmp(a, "--channel") && more)
			o->channel = argv[++i];
		else if (!strcmp(a, "--samples") && more)
			o->samples = atol(argv[++i]);
		else if (!strcmp(a, "--no-distance"))
			o->no_distance = true;
		else if (!strcmp(a, "--wrong-type"))
			o->wrong_type = true;
		else if (!strcmp(a, "--decreasing"))
			o->decreasing = true;
		else if (!strcmp(a, "--noise") && more)
			o->noise = atof(argv[++i]);
		else if (!strcmp(a, "--bias") && more)
			o->bias = atof(argv[++i]);
		else if (!strcmp(a, "--from") && more)
			o->from = atol(argv[++i]);
		else if (!strcmp(a, "--seed") && more)
			o->seed = strtoul(argv[++i], NULL, 10);
		else if (pos < 2 && a[0] != '-')
			*(pos++ ? &o->out : &o->gt) = a;
		else
			return -EINVAL;
	}
	return pos == 2 ? 0 : -EINVAL;
}

/* KITTI trajectories carry no times: one per line of a times.txt. */
static int read_times(const char *path, struct mvod_traj *t)
{
	FILE *f = fopen(path, "r");
	if (!f)
		return -errno;
	for (int i = 0; i < t->n; i++)
		if (fscanf(f, "%lf", &t->t[i]) != 1) {
			fclose(f);
			return -EINVAL;
		}
	fclose(f);
	return 0;
}

/* A standard normal from a 64-bit LCG (Box-Muller): the same sequence on every machine. */
static double gauss(uint64_t *state)
{
	double u[2];
	for (int i = 0; i < 2; i++) {
		*state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
		u[i] = ((double)(*state >> 11) + 0.5) / 9007199254740992.0;
	}
	return sqrt(-2 * log(u[0])) * cos(2 * M_PI * u[1]);
}

static int write_event(lcm_eventlog_t *log, const char *channel, int64_t num, int64_t utime,
		       const void *buf, int len)
{
	lcm_eventlog_event_t ev = {.eventnum = num, .timestamp = utime,
				   .channellen = (int32_t)strlen(channel), .datalen = len,
				   .channel = (char *)channel, .data = (void *)buf};
	return lcm_eventlog_write_event(log, &ev);
}

static int write_one(lcm_eventlog_t *log, const struct opts *o, int64_t num,
		     const mvod_speed_t *m)
{
	uint8_t buf[256];
	int len;
	if (o->wrong_type) {
		mvod_pose_t p = {.utime = m->utime, .orientation = {1, 0, 0, 0}};
		len = mvod_pose_t_encode(buf, 0, sizeof(buf), &p);
	} else {
		len = mvod_speed_t_encode(buf, 0, sizeof(buf), m);
	}
	return len < 0 ? -EINVAL : write_event(log, o->channel, num, m->utime, buf, len);
}

int main(int argc, char **argv)
{
	struct opts o;
	struct mvod_traj t;
	char err[512];
	if (parse(argc, argv, &o)) {
		fprintf(stderr, "usage: mkspeedlog GT OUT [--times FILE] [--channel NAME] "
				"[--samples N] [--no-distance] [--wrong-type] [--decreasing] "
				"[--noise F] [--bias F] [--seed N] [--from N]\n");
		return 2;
	}
	if (mvod_traj_load(o.gt, &t, err, sizeof(err)) ||
	    (o.times && read_times(o.times, &t))) {
		fprintf(stderr, "mkspeedlog: %s: %s\n", o.gt, o.times ? "bad --times" : err);
		return 1;
	}
	lcm_eventlog_t *log = lcm_eventlog_create(o.out, "w");
	if (!log) {
		fprintf(stderr, "mkspeedlog: cannot write %s\n", o.out);
		return 1;
	}
	double dist = 0;
	int ret = 0;
	uint64_t rng = o.seed;
	for (int i = 1; i < t.n && !ret && (o.samples < 0 || i <= o.samples); i++) {
		double d = mvod_vec3_dist(t.pose[i].t, t.pose[i - 1].t), dt = t.t[i] - t.t[i - 1];
		d *= 1 + o.bias;
		if (o.noise > 0)
			d *= 1 + o.noise * gauss(&rng);
		dist += d;
		mvod_speed_t m = {.utime = llround(t.t[i] * 1e6), .speed = dt > 0 ? d / dt : 0,
				  .has_distance = !o.no_distance, .distance = dist};
		if (o.decreasing && i == 10)
			m.utime = llround(t.t[i - 2] * 1e6);
		if (i - 1 >= o.from)
			ret = write_one(log, &o, i - 1, &m);
	}
	lcm_eventlog_destroy(log);
	mvod_traj_free(&t);
	return ret ? 1 : 0;
}
