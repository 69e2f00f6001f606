#include "mvod/speed.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include <lcm/eventlog.h>
#include <lcm/lcm.h>

#include "ipc/lcm_log.h"
#include "ipc/log_check.h"
#include "mvod_speed_t.h"
#include "util/errbuf.h"

/* One accepted sample: its time, the odometer there (metres) and the speed (m/s). */
struct sample {
	int64_t utime;
	double odo, speed;
};

/*
 * Live: lcm (owned), messages taken in by lcm_handle_timeout without waiting. File: the log,
 * read event by event up to the frame's time. samples is a ring of the newest ones.
 */
struct mvod_speed {
	lcm_t *lcm;
	lcm_eventlog_t *log;
	bool log_done;
	char channel[LCM_MAX_CHANNEL_NAME_LENGTH + 1];
	struct sample samples[MVOD_SPEED_SAMPLES];
	int head, n; /* the newest is samples[head] */
	struct mvod_speed_counts counts;
};

static const struct sample *nth_newest(const struct mvod_speed *s, int k)
{
	return &s->samples[(s->head - k + MVOD_SPEED_SAMPLES) % MVOD_SPEED_SAMPLES];
}

/* Checks one encoded message and keeps it: its odometer from distance or by integration. */
static void take(struct mvod_speed *s, const void *data, size_t len)
{
	mvod_speed_t m;
	if (mvod_speed_t_decode(data, 0, (int)len, &m) < 0) {
		s->counts.bad_type++;
		return;
	}
	if (!isfinite(m.speed) || fabs(m.speed) > MVOD_SPEED_MAX ||
	    (m.has_distance && !isfinite(m.distance))) {
		s->counts.bad_value++;
		return;
	}
	const struct sample *last = s->n ? nth_newest(s, 0) : NULL;
	if ((last && m.utime <= last->utime) || m.utime < 0 || m.utime > MVOD_SPEED_MAX_UTIME) {
		s->counts.bad_time++;
		s->counts.last_bad_utime = m.utime;
		return;
	}
	double odo = m.has_distance ? m.distance
		     : last        ? last->odo + 0.5 * (last->speed + m.speed) *
						   (double)(m.utime - last->utime) * 1e-6
				   : 0.0;
	s->head = (s->head + 1) % MVOD_SPEED_SAMPLES;
	s->samples[s->head] = (struct sample){m.utime, odo, m.speed};
	s->n += s->n < MVOD_SPEED_SAMPLES;
	s->counts.accepted++;
}

static void on_message(const lcm_recv_buf_t *rbuf, const char *channel, void *ctx)
{
	(void)channel;
	take(ctx, rbuf->data, rbuf->data_size);
}

/*
 * A log is checked before LCM reads it (ipc/log_check.h): LCM's reader crashes on a garbage
 * event length. One cut short at its end is read up to there.
 */
static int open_log(struct mvod_speed *s, const char *url, const char *path, char mode,
		    char *err, size_t errlen)
{
	if (mode != 'r')
		return mvod_errf(err, errlen, -EINVAL, "%s is a log to write (mode=%c): read the "
				 "speed from file://%s?mode=r", url, mode, path);
	struct mvod_lcmlog_check c;
	int ret = mvod_lcmlog_vet(path, &c, err, errlen);
	if (ret)
		return ret;
	s->log = lcm_eventlog_create(path, "r");
	return s->log ? 0 : mvod_errf(err, errlen, errno ? -errno : -EIO, "cannot read the LCM "
				      "log %s: %s", path, strerror(errno));
}

static int open_source(struct mvod_speed *s, const char *url, char *err, size_t errlen)
{
	char path[4096], mode;
	int ret = mvod_lcm_file_url(url, path, sizeof(path), &mode);
	if (ret == 0)
		return open_log(s, url, path, mode, err, errlen);
	if (ret != -ENOENT)
		return mvod_errf(err, errlen, ret, "%s is no log to read (file:///PATH?mode=r): %s",
				 url, strerror(-ret));
	s->lcm = lcm_create(*url ? url : NULL);
	if (!s->lcm)
		return mvod_errf(err, errlen, -EINVAL, "cannot open LCM at %s", *url ? url
				 : "the default URL");
	if (!lcm_subscribe(s->lcm, s->channel, on_message, s))
		return mvod_errf(err, errlen, -EINVAL, "cannot subscribe to %s", s->channel);
	return 0;
}

int mvod_speed_create(const char *url, const char *channel, struct mvod_speed **out, char *err,
		      size_t errlen)
{
	if (!channel)
		channel = MVOD_DEFAULT_SPEED_CHANNEL;
	if (!*channel || strlen(channel) > LCM_MAX_CHANNEL_NAME_LENGTH)
		return mvod_errf(err, errlen, -EINVAL, "speed channel \"%s\": give 1 to %d "
				 "characters", channel, LCM_MAX_CHANNEL_NAME_LENGTH);
	struct mvod_speed *s = calloc(1, sizeof(*s));
	if (!s)
		return mvod_errf(err, errlen, -ENOMEM, "out of memory");
	strcpy(s->channel, channel);
	int ret = open_source(s, url ? url : "", err, errlen);
	if (ret) {
		mvod_speed_destroy(s);
		return ret;
	}
	*out = s;
	return 0;
}

void mvod_speed_destroy(struct mvod_speed *s)
{
	if (!s)
		return;
	if (s->lcm)
		lcm_destroy(s->lcm);
	if (s->log)
		lcm_eventlog_destroy(s->log);
	free(s);
}

/* Takes in the samples up to the first one after utime (file) or all that arrived (live). */
static void pull(struct mvod_speed *s, int64_t utime)
{
	while (s->lcm && lcm_handle_timeout(s->lcm, 0) > 0)
		;
	while (s->log && !s->log_done && !(s->n && nth_newest(s, 0)->utime > utime)) {
		lcm_eventlog_event_t *ev = lcm_eventlog_read_next_event(s->log);
		if (!ev) {
			s->log_done = true;
			break;
		}
		if (strcmp(ev->channel, s->channel) == 0)
			take(s, ev->data, (size_t)ev->datalen);
		lcm_eventlog_free_event(ev);
	}
}

int mvod_speed_odometer(struct mvod_speed *s, int64_t utime, double *metres)
{
	pull(s, utime);
	/* Outside the samples' range a frame is stale by far; inside, no difference overflows. */
	if (!s->n || utime < -MVOD_SPEED_MAX_UTIME || utime > 2 * MVOD_SPEED_MAX_UTIME)
		return -EAGAIN;
	int k = 0; /* the newest sample at or before utime is nth_newest(k) */
	while (k < s->n - 1 && nth_newest(s, k)->utime > utime)
		k++;
	const struct sample *a = nth_newest(s, k);
	if (a->utime <= utime && k > 0) {
		const struct sample *b = nth_newest(s, k - 1);
		/* Inside a gap in the messages: as stale as after the last one. */
		if (utime - a->utime > MVOD_SPEED_STALE_US && b->utime - utime > MVOD_SPEED_STALE_US)
			return -EAGAIN;
		double w = (double)(utime - a->utime) / (double)(b->utime - a->utime);
		*metres = a->odo + w * (b->odo - a->odo);
		return 0;
	}
	/* Before the oldest kept or after the newest: the nearest, at its speed. */
	int64_t dt = utime - a->utime;
	if (llabs(dt) > MVOD_SPEED_STALE_US)
		return -EAGAIN;
	*metres = a->odo + a->speed * (double)dt * 1e-6;
	return 0;
}

void mvod_speed_counts(const struct mvod_speed *s, struct mvod_speed_counts *c)
{
	*c = s->counts;
}
