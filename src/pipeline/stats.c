/*
 * The run's book-keeping: counts, stage and frame times (a histogram in fixed memory), state
 * changes, the status messages and the summary.
 */
#include "internal.h"

#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <unistd.h>

#include "mvod/log.h"
#include "util/clock.h"

/* Resident set size in KiB; read with read(2) into the stack, since stdio would malloc. */
static int64_t rss_kb(void)
{
	char buf[128];
	int fd = open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
	if (fd < 0)
		return -1;
	ssize_t n = read(fd, buf, sizeof(buf) - 1);
	close(fd);
	long pages, resident;
	if (n <= 0)
		return -1;
	buf[n] = '\0';
	if (sscanf(buf, "%ld %ld", &pages, &resident) != 2)
		return -1;
	return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

void mvod_run_publish_status(struct run *r, const struct mvod_frame *f,
			   const struct mvod_vo_result *res)
{
	struct mvod_run_summary *s = r->sum;
	double now = mvod_now_s();
	double n = s->frames ? (double)s->frames : 1;
	struct mvod_status st = {
		.utime = f->utime,
		.fps = s->frames / fmax(now - r->t_start, 1e-9),
		.features = res->features,
		.matches = res->matches,
		.inliers = res->inliers,
		.frames = s->frames,
		.dropped = s->dropped,
		.rss_kb = rss_kb(),
		.uptime_s = now - r->t_start,
		.state = r->state,
		.faults = r->faults.bits,
		.map_points = res->map_points,
		.keyframes = res->keyframes,
		.scale = res->scale,
		.scale_confidence = res->scale_confidence,
		.latency_ms = r->latency_ms,
	};
	for (int k = 0; k < MVOD_STAGE_COUNT; k++)
		st.stage_ms[k] = r->stage_total[k] / n;
	mvod_run_sinks_status(r, &st, r->faults.status_due || r->state == MVOD_RUN_STOPPING);
	r->last_status = now;
	r->faults.status_due = false;
}

static void hist_add(uint32_t *hist, double ms)
{
	double b = ms > FT_MIN_MS ? log(ms / FT_MIN_MS) / log(FT_GROWTH) : 0;
	hist[b < FT_BINS - 1 ? (int)b : FT_BINS - 1]++;
}

/* The q-quantile of n counted times: the middle of the bin it falls in. */
static double hist_quantile(const uint32_t *hist, int64_t n, double q)
{
	int64_t want = (int64_t)ceil(q * (double)n), seen = 0;
	for (int b = 0; b < FT_BINS; b++) {
		seen += hist[b];
		if (seen >= want && seen > 0)
			return FT_MIN_MS * pow(FT_GROWTH, b + 0.5);
	}
	return 0;
}

static double record_times(struct run *r, const struct mvod_vo_result *res)
{
	struct mvod_run_summary *s = r->sum;
	double frame_ms = 0;
	for (int k = 0; k < MVOD_STAGE_COUNT; k++) {
		r->stage_total[k] += res->ms[k];
		s->stage_ms_max[k] = fmax(s->stage_ms_max[k], res->ms[k]);
		frame_ms += res->ms[k];
	}
	hist_add(r->frame_hist, frame_ms);
	return frame_ms;
}

bool mvod_run_status_due(const struct run *r)
{
	return mvod_now_s() - r->last_status >= 1.0 / r->o->status_hz;
}

/*
 * Why the state changed, for the log: the frame's status, but for a lost map, whose frame the
 * two-view algorithm takes (its status, often rotation: too little parallax yet for a new map,
 * is not why tracking was lost). buf holds the text when it is not a status name.
 */
static const char *state_reason(const struct mvod_vo_result *res, char *buf, size_t n)
{
	if (!res->map_lost)
		return mvod_frame_status_name(res->status);
	const char *rebuilt = "a new map is built from the last tracked frame";
	if (res->map_lost_inliers >= 0)
		snprintf(buf, n, "map lost: %d map points fit the pose, %d needed; %s",
			 res->map_lost_inliers, res->map_lost_need, rebuilt);
	else
		snprintf(buf, n, "map lost: too few map points found in the frame to try a pose, %d "
			 "needed; %s", res->map_lost_need, rebuilt);
	return buf;
}

/* The run's own book-keeping of a frame: counts, times, state changes. Returns frame ms. */
double mvod_run_record(struct run *r, const struct mvod_frame *f, const struct mvod_vo_result *res)
{
	struct mvod_run_summary *s = r->sum;
	s->frames++;
	s->tracked += mvod_vo_tracked(res);
	double frame_ms = record_times(r, res);
	enum mvod_run_state state = (enum mvod_run_state)res->state; /* same values */
	if (state != r->state) {
		char why[160];
		LOG(INFO, "frame %lld: %s -> %s (%s)", (long long)f->index,
		    mvod_run_state_name(r->state), mvod_run_state_name(state),
		    state_reason(res, why, sizeof(why)));
		r->state = state;
		r->faults.status_due = true; /* a state change is news: status goes with this frame */
	}
	LOG(DEBUG, "frame %lld: %s, %d features, %d matches, %d inliers, step %.4f (%s)%s, map %d "
	    "points, %d keyframes", (long long)f->index, mvod_frame_status_name(res->status),
	    res->features, res->matches, res->inliers, res->step_m,
	    mvod_scale_source_name(res->scale_source), res->keyframe ? ", keyframe" : "",
	    res->map_points, res->keyframes);
	return frame_ms;
}

void mvod_run_summarise(struct run *r)
{
	struct mvod_run_summary *s = r->sum;
	s->wall_s = mvod_now_s() - r->t_start;
	s->fps = s->wall_s > 0 ? s->frames / s->wall_s : 0;
	s->held = s->frames - s->tracked;
	for (int k = 0; k < MVOD_STAGE_COUNT; k++)
		s->stage_ms_mean[k] = s->frames ? r->stage_total[k] / (double)s->frames : 0;
	s->frame_ms_median = hist_quantile(r->frame_hist, s->frames, 0.5);
	s->frame_ms_p95 = hist_quantile(r->frame_hist, s->frames, 0.95);
}
