/*
 * mvod speed-log's writer: the mvod.speed_t a robot's wheels would report along a known path,
 * as an LCM log (mvod/speed.h).
 */
#include "mvod/speed.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include <lcm/lcm.h>

#include "ipc/lcm_log.h"
#include "mvod_speed_t.h"
#include "util/errbuf.h"

void mvod_speed_log_opts_default(struct mvod_speed_log_opts *o)
{
	*o = (struct mvod_speed_log_opts){.channel = MVOD_DEFAULT_SPEED_CHANNEL, .samples = -1,
					  .seed = 1};
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

/* The message of pose i (from 1): the step since pose i-1 as the odometer measured it. */
static mvod_speed_t message(int i, const double *t, const struct mvod_pose *pose,
			    const struct mvod_speed_log_opts *o, uint64_t *rng, double *dist)
{
	double d = mvod_vec3_dist(pose[i].t, pose[i - 1].t), dt = t[i] - t[i - 1];
	d *= 1 + o->bias;
	if (o->noise > 0)
		d *= 1 + o->noise * gauss(rng);
	*dist += d;
	return (mvod_speed_t){.utime = llround(t[i] * 1e6), .speed = dt > 0 ? d / dt : 0,
			      .has_distance = !o->no_distance, .distance = *dist};
}

int mvod_speed_log_write(const char *path, int n, const double *t, const struct mvod_pose *pose,
			 const struct mvod_speed_log_opts *o, char *err, size_t errlen)
{
	for (int i = 1; i < n; i++)
		if (!(t[i] > t[i - 1]) || !(t[i] * 1e6 < (double)MVOD_SPEED_MAX_UTIME) || t[i] < 0)
			return mvod_errf(err, errlen, -EINVAL, "time %d (%.17g s) is not after the "
					 "one before (%.17g s), or not in [0, %.0f] s", i, t[i],
					 t[i - 1], (double)MVOD_SPEED_MAX_UTIME * 1e-6);
	struct mvod_lcm_log *log = NULL;
	mvod_speed_t m = {0};
	size_t max = strlen(o->channel) + (size_t)mvod_speed_t_encoded_size(&m);
	int ret = mvod_lcm_log_open("speed log", path, max, &log, err, errlen);
	if (ret)
		return ret;
	double dist = 0;
	uint64_t rng = o->seed;
	int written = 0;
	for (int i = 1; i < n && !ret && (o->samples < 0 || i <= o->samples); i++) {
		m = message(i, t, pose, o, &rng, &dist);
		uint8_t buf[64];
		int len = mvod_speed_t_encode(buf, 0, sizeof(buf), &m);
		if (i - 1 < o->from)
			continue;
		ret = len < 0 ? -EMSGSIZE
			      : mvod_lcm_log_write_at(log, o->channel, buf, (size_t)len, m.utime);
		written += !ret;
	}
	int closed = mvod_lcm_log_close(log);
	ret = ret ? ret : closed;
	if (ret)
		return mvod_errf(err, errlen, ret, "cannot write %s: %s", path, strerror(-ret));
	/* A stream truncates at its first event: none would leave the file before in place. */
	if (!written)
		return mvod_errf(err, errlen, -ENODATA, "%s: no message to write (%d poses, the "
				 "first %ld from message %ld)", path, n, o->samples, o->from);
	return written;
}
