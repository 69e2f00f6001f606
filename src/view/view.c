#include "mvod/view.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "mvod/plot.h"
#include "mvod_pose2_t.h"
#include "mvod_pose_t.h"
#include "mvod_status2_t.h"
#include "mvod_status_t.h"

/* A second of poses is enough for a steady rate and short enough to follow a change. */
#define RATE_WINDOW_US 1000000
/* No pose for this long: the rate shown is stale, and the panel says since when. */
#define STALE_US 2000000

int mvod_view_init(struct mvod_view *v, int max_poses)
{
	*v = (struct mvod_view){.state = MVOD_RUN_STARTING, .pose_hz = NAN};
	mvod_pose_identity(&v->pose);
	return mvod_path_init(&v->path, max_poses);
}

void mvod_view_fini(struct mvod_view *v)
{
	mvod_path_fini(&v->path);
}

static void update_rate(struct mvod_view *v, int64_t recv_us)
{
	if (v->poses == 1 || recv_us < v->rate_start_us) {
		v->rate_start_us = recv_us;
		v->rate_start_poses = 1;
		return;
	}
	int64_t dt = recv_us - v->rate_start_us;
	if (dt < RATE_WINDOW_US)
		return;
	v->pose_hz = (double)(v->poses - v->rate_start_poses) * 1e6 / (double)dt;
	v->rate_start_us = recv_us;
	v->rate_start_poses = v->poses;
}

static void note_state(struct mvod_view *v, int state)
{
	v->state = (enum mvod_run_state)mvod_run_state_from_wire(state);
	if (v->state != MVOD_RUN_STOPPING)
		v->last_state = v->state;
}

void mvod_view_add_pose2(struct mvod_view *v, const mvod_pose2_t *msg, int64_t recv_us)
{
	v->v2 = true;
	/* No pose (nan, a zero quaternion): drawn, it would make the path and the heading nan. */
	char why[192];
	if (mvod_pose_from_quat(msg->position, msg->orientation, &v->pose, why, sizeof(why))) {
		if (v->refused++ == 0)
			snprintf(v->refused_why, sizeof(v->refused_why), "frame %lld: %s",
				 (long long)msg->frame, why);
		return;
	}
	v->poses++;
	v->frame = msg->frame;
	note_state(v, msg->state);
	v->tracked += msg->state == MVOD_RUN_TRACKING;
	v->scale_source = msg->scale_source;
	/* A held frame (SCALE_NONE) has no step, and says nothing about the run's scale. */
	if (msg->scale_source != MVOD_POSE_T_SCALE_NONE)
		v->metric = msg->scale_source == MVOD_POSE_T_SCALE_GROUND_TRUTH ||
			    msg->scale_source == MVOD_POSE_T_SCALE_HEIGHT ||
			    msg->scale_source == MVOD_POSE_T_SCALE_EXTERNAL;
	v->frame_status = msg->frame_status;
	v->features = msg->features;
	v->matches = msg->matches;
	v->inliers = msg->inliers;
	v->quality = msg->quality;
	mvod_path_add(&v->path, v->pose.t);
	v->last_pose_us = recv_us;
	update_rate(v, recv_us);
}

void mvod_view_add_status2(struct mvod_view *v, const mvod_status2_t *msg)
{
	v->v2 = true;
	v->statuses++;
	note_state(v, msg->state);
	mvod_status_from_msg(msg, &v->status);
}

/* A v1 message counts only until the first v2 one: mvod publishes the v2 first, then the v1. */
void mvod_view_add_pose(struct mvod_view *v, const mvod_pose_t *msg, int64_t recv_us)
{
	if (v->v2)
		return;
	mvod_pose2_t m;
	mvod_pose_msg_upgrade(msg, &m);
	mvod_view_add_pose2(v, &m, recv_us);
	v->v2 = false;
}

void mvod_view_add_status(struct mvod_view *v, const mvod_status_t *msg)
{
	if (v->v2)
		return;
	mvod_status2_t m;
	mvod_status_msg_upgrade(msg, &m);
	mvod_view_add_status2(v, &m);
	v->v2 = false;
}

double mvod_view_yaw_deg(const struct mvod_view *v)
{
	/* Forward is the camera's z axis: the third column of camera-to-world. */
	double fx = v->pose.R[2], fz = v->pose.R[8];
	if (!v->poses || !(hypot(fx, fz) > 1e-6))
		return NAN;
	double deg = atan2(fx, fz) * 180.0 / M_PI;
	return deg <= -180.0 ? 180.0 : deg;
}

const char *mvod_view_unit(const struct mvod_view *v, bool brief)
{
	return brief && !v->metric ? "units" : mvod_plot_unit(v->metric);
}

static void row(struct mvod_view_row *rows, int max_rows, int *n, const char *label,
		const char *fmt, ...) __attribute__((format(printf, 5, 6)));

static void row(struct mvod_view_row *rows, int max_rows, int *n, const char *label,
		const char *fmt, ...)
{
	if (*n >= max_rows)
		return;
	struct mvod_view_row *r = &rows[(*n)++];
	snprintf(r->label, sizeof(r->label), "%s", label);
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(r->value, sizeof(r->value), fmt, ap);
	va_end(ap);
}

static void pose_rows(const struct mvod_view *v, int64_t now_us, struct mvod_view_row *rows,
		      int max, int *n)
{
	row(rows, max, n, "frame", "%lld (%s)", (long long)v->frame,
	    mvod_frame_status_name((enum mvod_frame_status)v->frame_status));
	char label[sizeof(rows->label)];
	snprintf(label, sizeof(label), "position [%s]", mvod_view_unit(v, true));
	row(rows, max, n, label, "%.2f %.2f %.2f", v->pose.t[0], v->pose.t[1], v->pose.t[2]);
	row(rows, max, n, "scale from", "%s",
	    mvod_scale_source_name((enum mvod_scale_source)v->scale_source));
	row(rows, max, n, "feat/match/inl", "%d / %d / %d", v->features, v->matches, v->inliers);
	if (v->v2)
		row(rows, max, n, "quality", "%.2f", v->quality);
	double idle_s = (double)(now_us - v->last_pose_us) / 1e6;
	if (idle_s * 1e6 >= STALE_US)
		row(rows, max, n, "poses received", "none for %.0f s", idle_s);
	else if (isnan(v->pose_hz))
		row(rows, max, n, "poses received", "measuring");
	else
		row(rows, max, n, "poses received", "%.1f /s", v->pose_hz);
}

/* The fault bits mvod has reported, by name ("" when none). */
static void fault_names(int32_t faults, char *buf, size_t len)
{
	static const struct {
		int32_t bit;
		const char *name;
	} names[] = {
		{MVOD_STATUS_T_FAULT_TRAJECTORY_WRITE, "trajectory"},
		{MVOD_STATUS_T_FAULT_FRAME_UNREADABLE, "bad frames"},
		{MVOD_STATUS_T_FAULT_SOURCE_BROKEN, "source broken"},
		{MVOD_STATUS_T_FAULT_PUBLISH, "publish"},
	};
	size_t used = 0;
	buf[0] = '\0';
	for (size_t i = 0; i < sizeof(names) / sizeof(names[0]) && used < len; i++)
		if (faults & names[i].bit)
			used += (size_t)snprintf(buf + used, len - used, "%s%s", used ? ", " : "",
						 names[i].name);
}

/* What only mvod.status2_t carries. */
static void v2_status_rows(const struct mvod_status *s, struct mvod_view_row *rows, int max,
			   int *n)
{
	row(rows, max, n, "map points/keyfr.", "%d / %d", s->map_points, s->keyframes);
	if (s->scale > 0)
		row(rows, max, n, "scale", "%.3g m/unit (conf. %.2f)", s->scale,
		    s->scale_confidence);
	else
		row(rows, max, n, "scale", "unknown (free)");
	row(rows, max, n, "latency", "%.1f ms", s->latency_ms);
}

static void status_rows(const struct mvod_view *v, struct mvod_view_row *rows, int max, int *n)
{
	const struct mvod_status *s = &v->status;
	long long up = (long long)s->uptime_s;
	row(rows, max, n, "mvod fps", "%.1f", s->fps);
	row(rows, max, n, "frames", "%lld", (long long)s->frames);
	row(rows, max, n, "dropped frames", "%lld", (long long)s->dropped);
	row(rows, max, n, "ms detect/match", "%.1f / %.1f", s->stage_ms[MVOD_STAGE_DETECT],
	    s->stage_ms[MVOD_STAGE_MATCH]);
	row(rows, max, n, "ms capt/prep/pose", "%.1f / %.1f / %.1f",
	    s->stage_ms[MVOD_STAGE_CAPTURE], s->stage_ms[MVOD_STAGE_PREPROCESS],
	    s->stage_ms[MVOD_STAGE_POSE]);
	if (v->v2)
		v2_status_rows(s, rows, max, n);
	row(rows, max, n, "RSS", "%.1f MiB", (double)s->rss_kb / 1024.0);
	row(rows, max, n, "uptime", "%lld:%02lld:%02lld", up / 3600, up / 60 % 60, up % 60);
	char faults[96];
	fault_names(s->faults, faults, sizeof(faults));
	if (*faults)
		row(rows, max, n, "faults", "%s", faults);
}

int mvod_view_rows(const struct mvod_view *v, int64_t now_us, struct mvod_view_row *rows,
		   int max_rows)
{
	int n = 0;
	if (v->poses)
		pose_rows(v, now_us, rows, max_rows, &n);
	else
		row(rows, max_rows, &n, "poses", "none yet");
	if (v->statuses)
		status_rows(v, rows, max_rows, &n);
	else
		row(rows, max_rows, &n, "status", "none yet");
	row(rows, max_rows, &n, "messages", "%lld poses, %lld status", (long long)v->poses,
	    (long long)v->statuses);
	if (v->poses && v->tracked)
		row(rows, max_rows, &n, "tracked", "%lld of %lld poses", (long long)v->tracked,
		    (long long)v->poses);
	else if (v->poses)
		row(rows, max_rows, &n, "tracked", "never");
	return n;
}
