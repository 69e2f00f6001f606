#include "mvod/pipeline.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mvod/capture.h"
#include "mvod/log.h"
#include "util/body_frame.h"
#include "mvod/speed.h"
#include "util/clock.h"
#include "util/errbuf.h"
#include "util/notify.h"
#include "util/output.h"
#include "mvod_status_t.h"

/* The built-in sinks (eval, notify, LCM, plot, trajectory) and the caller's. */
#define MAX_SINKS 16

/* How long the live loop waits for a frame before it looks at the stop flag again. */
#define LIVE_WAIT_MS 100

/*
 * Frame times go into a fixed histogram of 1 % wide logarithmic bins from 0.01 ms to ~80 s, so
 * a daemon running for months keeps its median and 95th percentile in constant memory.
 */
#define FT_BINS 1600
#define FT_MIN_MS 0.01
#define FT_GROWTH 1.01

const char *mvod_run_state_name(enum mvod_run_state s)
{
	static const char *const names[] = {"STARTING", "INITIALIZING", "TRACKING",
					    "LOST",     "SOURCE_DOWN",  "STOPPING"};
	return (unsigned)s < sizeof(names) / sizeof(names[0]) ? names[s] : "UNKNOWN";
}

const char *const mvod_axes_names[] = {"camera", "ros", NULL};
const char *const mvod_clock_names[] = {"monotonic", "realtime", NULL};

void mvod_run_opts_default(struct mvod_run_opts *o)
{
	*o = (struct mvod_run_opts){.traj_format = MVOD_TRAJ_TUM, .status_hz = 1,
				    .speed_channel = MVOD_DEFAULT_SPEED_CHANNEL};
	mvod_vo_params_default(&o->vo);
}

struct run {
	const struct mvod_run_opts *o;
	struct mvod_source *src;
	struct mvod_source_info info;
	struct mvod_camera cam;
	struct mvod_traj gt;
	char gt_from[PATH_MAX]; /* the ground truth's file: --gt, or the one the dataset carries */
	bool gt_from_source;    /* the dataset's: frames before it begins are skipped when needed */
	int64_t skipped_lead;   /* frames skipped so */
	struct mvod_vo *vo;
	struct mvod_body_frame body; /* --frame, --camera-to-body: the output poses' frame */
	double latency_ms;           /* of the last frame: delivered by the source to published */
	struct mvod_ipc *ipc;
	struct mvod_sink sinks[MAX_SINKS]; /* in the order they are called */
	bool owned[MAX_SINKS];             /* made here: destroyed here */
	int n_sinks;
	struct mvod_run_summary *sum;
	double stage_total[MVOD_STAGE_COUNT];
	uint32_t frame_hist[FT_BINS];
	double t_start, last_status;
	enum mvod_run_state state;
	struct mvod_frame last_frame;      /* for status messages sent between frames */
	struct mvod_vo_result last_res;
	struct mvod_capture *cap;          /* live sources: their capture thread */
	int epoch;                         /* times the live source came back */
	int64_t last_index;                /* of the last frame processed, -1 before */
	bool restarted;                    /* the VO forgot the scene before the next frame */
	/* mvod.status_t FAULT_ bits seen so far; status_due: publish status with the next frame */
	struct mvod_faults faults;
	struct mvod_speed *speed;          /* --scale external */
	bool speed_stale;                  /* the last frame had no speed near its time */
	struct mvod_speed_counts speed_refused; /* refused messages already logged */
};

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

static int open_camera(struct run *r)
{
	char err[MVOD_ERR_MAX] = "";
	const struct mvod_run_opts *o = r->o;
	if (o->calib) {
		int ret = mvod_calib_load(o->calib, &r->cam, err, sizeof(err));
		if (ret)
			LOG(ERROR, "calibration: %s", err);
		if (ret)
			return ret;
	} else if (mvod_source_camera(r->src, &r->cam) != 0) {
		LOG(ERROR, "%s carries no camera intrinsics: pass --calib FILE (mvod JSON or KITTI "
			   "calib.txt)", o->source);
		return -EINVAL;
	}
	if (r->cam.width == 0 && r->cam.height == 0) {
		r->cam.width = r->info.width;
		r->cam.height = r->info.height;
	}
	if (r->cam.width != r->info.width || r->cam.height != r->info.height) {
		LOG(ERROR, "calibration is for %dx%d images but %s delivers %dx%d: use the "
			   "calibration made for this camera mode",
		    r->cam.width, r->cam.height, o->source, r->info.width, r->info.height);
		return -EINVAL;
	}
	if (mvod_camera_check(&r->cam, err, sizeof(err))) {
		LOG(ERROR, "calibration %s cannot be a camera of %dx%d: %s; is it this camera's?",
		    o->calib ? o->calib : o->source, r->cam.width, r->cam.height, err);
		return -EINVAL;
	}
	if (isnan(r->info.focus))
		return 0;
	LOG(INFO, "%s: autofocus off, focus held at %g", o->source, r->info.focus);
	/* A focus change moves the focal length: the calibration holds only at its own focus. */
	if (r->cam.has_focus && r->cam.focus != r->info.focus)
		LOG(WARN, "the calibration was made at focus %g but the camera is at %g: the "
			  "intrinsics may be off; set the focus back (v4l2-ctl -c focus_absolute=%g) "
			  "or calibrate again", r->cam.focus, r->info.focus, r->cam.focus);
	return 0;
}

/* --gt FILE, or else the ground truth the dataset carries (KITTI poses/, EuRoC, TUM). */
static int open_gt(struct run *r)
{
	char err[MVOD_ERR_MAX] = "";
	const struct mvod_run_opts *o = r->o;
	int ret;
	if (o->gt) {
		snprintf(r->gt_from, sizeof(r->gt_from), "%s", o->gt);
		ret = mvod_traj_load(o->gt, &r->gt, err, sizeof(err));
	} else {
		ret = mvod_source_ground_truth(r->src, &r->gt, r->gt_from, sizeof(r->gt_from), err,
					       sizeof(err));
		r->gt_from_source = ret == 0;
		if (ret == 0)
			LOG(INFO, "ground truth: %s (%d poses), which %s carries; --gt FILE "
				  "overrides", r->gt_from, r->gt.n, o->source);
		if (ret == -ENOENT) /* the source carries none */
			ret = 0;
	}
	if (ret) {
		LOG(ERROR, "ground truth: %s", err);
		return ret;
	}
	if (!r->gt.n && (o->vo.scale_mode == MVOD_SCALE_MODE_GT || o->require_gt)) {
		LOG(ERROR, "%s needs a ground-truth trajectory and %s carries none: pass --gt FILE",
		    o->require_gt ? "benchmarking" : "--scale gt", o->source);
		return -EINVAL;
	}
	return 0;
}

/* --frame, --camera-to-body and --clock, against what the source can do. */
static int check_output_frame(struct run *r)
{
	const struct mvod_run_opts *o = r->o;
	char err[MVOD_ERR_MAX] = "";
	int ret = mvod_body_frame_init(o->axes, o->camera_to_body, &r->body, err, sizeof(err));
	if (ret) {
		LOG(ERROR, "%s", err);
		return ret;
	}
	if (o->clock == MVOD_CLOCK_REALTIME && !r->info.monotonic) {
		LOG(ERROR, "--clock realtime: %s stamps its frames with its own times (media time, "
			   "times.txt, the dataset's), not a clock; only cameras (v4l2:, libcamera:) "
			   "can: drop --clock", o->source);
		return -EINVAL;
	}
	return 0;
}

/* Which height --scale height takes, and from where (the VO takes the same, vo.c's mount()). */
static void log_height(const struct run *r)
{
	const struct mvod_run_opts *o = r->o;
	const struct mvod_camera *c = &r->cam;
	if (o->vo.camera_height_m > 0)
		LOG(INFO, "--scale height: the camera is %.4f m above the ground (--camera-height)",
		    o->vo.camera_height_m);
	else
		LOG(INFO, "--scale height: the camera is %.4f m above the ground (the mount in %s)",
		    c->mount_height_m, o->calib ? o->calib : "the calibration");
	if (c->has_mount)
		LOG(INFO, "--scale height: the ground's first normal from the mount: pitch %.2f deg, "
			  "roll %.2f deg", c->mount_pitch_deg, c->mount_roll_deg);
}

/* --scale height needs a height; --scale external its source of speed. */
static int open_scale(struct run *r)
{
	const struct mvod_run_opts *o = r->o;
	if (o->vo.scale_mode == MVOD_SCALE_MODE_HEIGHT && !(o->vo.camera_height_m > 0) &&
	    !r->cam.has_mount) {
		LOG(ERROR, "--scale height needs the camera's height above the ground: pass "
			   "--camera-height M (metres), set [vo] camera-height in the --config file, "
			   "or give a --calib file with a \"mount\" block (height_m, pitch_deg, "
			   "roll_deg)");
		return -EINVAL;
	}
	if (o->vo.scale_mode == MVOD_SCALE_MODE_HEIGHT)
		log_height(r);
	if (o->vo.scale_mode != MVOD_SCALE_MODE_EXTERNAL)
		return 0;
	if (!o->speed_url) {
		LOG(ERROR, "--scale external needs the robot's speed (mvod.speed_t): pass "
			   "--speed-url URL (an LCM URL or file://LOG?mode=r), or leave LCM on to "
			   "read it where mvod publishes");
		return -EINVAL;
	}
	char err[MVOD_ERR_MAX] = "";
	int ret = mvod_speed_create(o->speed_url, o->speed_channel, &r->speed, err, sizeof(err));
	if (ret)
		LOG(ERROR, "--speed-url: %s", err);
	return ret;
}

static int open_inputs(struct run *r)
{
	char err[MVOD_ERR_MAX] = "";
	const struct mvod_run_opts *o = r->o;
	int ret = mvod_source_open(o->source, &r->src, err, sizeof(err));
	if (ret) {
		LOG(ERROR, "cannot open source %s: %s", o->source, err);
		return ret;
	}
	mvod_source_info(r->src, &r->info);
	if (r->info.times_assumed)
		LOG(WARN, "%s has no times.txt: timestamps assume 10 Hz", o->source);
	ret = check_output_frame(r);
	if (!ret) {
		ret = open_camera(r);
		r->sum->calib_failed = ret != 0;
	}
	if (ret)
		return ret;
	ret = open_gt(r);
	if (ret)
		return ret;
	ret = open_scale(r);
	if (ret)
		return ret;
	ret = mvod_vo_check_size(&o->vo, &r->cam, err, sizeof(err));
	if (ret) {
		LOG(ERROR, "%s: %s", o->source, err);
		return ret;
	}
	r->sum->frontend = mvod_vo_frontend(&o->vo);
	LOG(INFO, "front end: %s%s", mvod_frontend_names[r->sum->frontend],
	    o->vo.frontend == MVOD_FRONTEND_AUTO ? " (--frontend auto)" : "");
	/* Info, as the front end's choice: documented behaviour, not a fault (-q hides it). */
	const char *no_map = mvod_vo_map_missing(&o->vo);
	if (no_map)
		LOG(INFO, "%s: running --mode twoview", no_map);
	/*
	 * A file or dataset is read as fast as it is processed, so waiting for bundle adjustment
	 * costs no frame, and its result is then the same on every machine; on a live camera the
	 * wait would hold frames back, so only --ba-sync asks for it there. Measured (quiet run,
	 * KITTI 07, map mode on ORB): drift 3.80 without the wait, 1.38 with it.
	 */
	struct mvod_vo_params vp = o->vo;
	vp.ba_sync = vp.ba_sync || !r->info.live;
	ret = mvod_vo_create(&vp, &r->cam, &r->vo);
	if (ret)
		LOG(ERROR, "cannot set up visual odometry for %dx%d: %s", r->cam.width,
		    r->cam.height, strerror(-ret));
	return ret;
}

/* Appends a sink made by the caller of mvod_run (owned false) or here (true), after ret 0. */
static int add_sink(struct run *r, int ret, const struct mvod_sink *made, bool owned)
{
	if (ret)
		return ret;
	if (r->n_sinks == MAX_SINKS) {
		if (owned && made->ops->destroy)
			made->ops->destroy(made->ctx);
		return -E2BIG;
	}
	r->owned[r->n_sinks] = owned;
	r->sinks[r->n_sinks++] = *made;
	return 0;
}

/*
 * Outputs open last, so bad input never leaves an empty or truncated output behind; every one
 * goes through the output policy (util/output.h), and none truncates before its first record. The
 * evaluation comes first (the plot draws what it kept), then the caller's sinks (they see
 * each frame before it is published), systemd, LCM, the plot and the trajectory.
 */
static int open_outputs(struct run *r)
{
	const struct mvod_run_opts *o = r->o;
	char err[MVOD_ERR_MAX] = "", target[4096];
	int ret = o->plot ? mvod_output_check("--plot", o->plot, target, sizeof(target), NULL, err,
					      sizeof(err))
			  : 0;
	if (!ret && r->ipc)
		ret = mvod_ipc_open_log(r->ipc, err, sizeof(err));
	if (ret) {
		LOG(ERROR, "%s", err);
		return ret;
	}
	struct mvod_sink m;
	bool metric = mvod_scale_mode_metric(o->vo.scale_mode); /* metres: no scale alignment */
	ret = add_sink(r, mvod_sink_eval_create(!metric, r->gt.n, &m), &m, true);
	const struct mvod_sink *eval = &r->sinks[0];
	for (int i = 0; i < o->n_sinks; i++)
		ret = add_sink(r, ret, &o->sinks[i], false);
	if (!ret)
		ret = add_sink(r, mvod_sink_notify_create(&m), &m, true);
	if (!ret && r->ipc)
		ret = add_sink(r, mvod_sink_lcm_create(r->ipc, &r->faults, &m), &m, true);
	if (!ret && o->plot) {
		ret = mvod_sink_plot_create(o->plot, o->source, metric, eval, &m);
		ret = add_sink(r, ret, &m, true);
	}
	if (ret || !o->trajectory)
		return ret;
	ret = mvod_sink_traj_create(o->trajectory, o->traj_format, &r->faults, &m, err,
				    sizeof(err));
	if (ret)
		LOG(ERROR, "%s", err);
	return add_sink(r, ret, &m, true);
}

/* The fan-out: each sink's hook in order. frame and finish return the first error. */
static int sinks_frame(struct run *r, const struct mvod_frame_out *f)
{
	int ret = 0;
	for (int i = 0; i < r->n_sinks; i++) {
		const struct mvod_sink *s = &r->sinks[i];
		int sret = s->ops->frame ? s->ops->frame(s->ctx, f) : 0;
		ret = ret ? ret : sret;
	}
	return ret;
}

static void sinks_status(struct run *r, const struct mvod_status *st, bool news)
{
	for (int i = 0; i < r->n_sinks; i++)
		if (r->sinks[i].ops->status)
			r->sinks[i].ops->status(r->sinks[i].ctx, st, news);
}

static void sinks_between(struct run *r, bool reopen)
{
	for (int i = 0; i < r->n_sinks; i++)
		if (r->sinks[i].ops->between)
			r->sinks[i].ops->between(r->sinks[i].ctx, reopen);
}

static int sinks_finish(struct run *r)
{
	int ret = 0;
	for (int i = 0; i < r->n_sinks; i++) {
		const struct mvod_sink *s = &r->sinks[i];
		int sret = s->ops->finish ? s->ops->finish(s->ctx, r->sum) : 0;
		ret = ret ? ret : sret;
	}
	return ret;
}

static void sinks_destroy(struct run *r)
{
	for (int i = r->n_sinks - 1; i >= 0; i--)
		if (r->owned[i] && r->sinks[i].ops->destroy)
			r->sinks[i].ops->destroy(r->sinks[i].ctx);
}

/* Ground truth for a frame: KITTI files by index, TUM files by nearest timestamp. */
static const struct mvod_pose *gt_for(const struct run *r, const struct mvod_frame *f)
{
	if (!r->gt.n)
		return NULL;
	if (r->gt.format == MVOD_TRAJ_KITTI)
		return f->index < r->gt.n ? &r->gt.pose[f->index] : NULL;
	double t = f->utime / 1e6;
	int lo = 0, hi = r->gt.n - 1;
	while (lo < hi) {
		int mid = (lo + hi) / 2;
		if (r->gt.t[mid] < t)
			lo = mid + 1;
		else
			hi = mid;
	}
	if (lo > 0 && fabs(r->gt.t[lo - 1] - t) < fabs(r->gt.t[lo] - t))
		lo--;
	/* Within 5 ms: a different clock or a missing pose is not a match. */
	return fabs(r->gt.t[lo] - t) <= 0.005 ? &r->gt.pose[lo] : NULL;
}

static void publish_status(struct run *r, const struct mvod_frame *f,
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
	sinks_status(r, &st, r->faults.status_due || r->state == MVOD_RUN_STOPPING);
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

static bool status_periodic_due(const struct run *r)
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
static double record(struct run *r, const struct mvod_frame *f, const struct mvod_vo_result *res)
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

/* Why frame f has no ground-truth pose, for a run that needs one for every frame. */
static void log_missing_gt(const struct run *r, const struct mvod_frame *f)
{
	const char *why = r->o->vo.scale_mode == MVOD_SCALE_MODE_GT ? "--scale gt" : "benchmarking";
	if (r->gt.format == MVOD_TRAJ_KITTI) {
		LOG(ERROR, "ground truth %s has %d poses (KITTI, one per frame) but %s has more frames: "
			   "frame %lld has none, and %s needs every frame; pass --max-frames %d or "
			   "the ground truth of this sequence",
		    r->gt_from, r->gt.n, r->o->source, (long long)f->index, why, r->gt.n);
		return;
	}
	LOG(ERROR, "frame %lld (t = %.6f s) has no pose within 5 ms in ground truth %s, whose "
		   "poses span t = %.6f .. %.6f s: the clocks differ or the file has a gap; %s needs "
		   "every frame",
	    (long long)f->index, f->utime / 1e6, r->gt_from, r->gt.t[0], r->gt.t[r->gt.n - 1], why);
}

/*
 * A dataset's ground truth often begins after its camera (EuRoC's by a second or so): a run
 * that needs a pose for every frame starts at the first frame that has one.
 */
static bool before_dataset_gt(struct run *r, const struct mvod_frame *f)
{
	if (!r->gt_from_source || r->sum->frames > 0 || f->utime / 1e6 >= r->gt.t[0])
		return false;
	if (r->skipped_lead++ == 0)
		LOG(INFO, "frame %lld (t = %.6f s) comes before the ground truth %s begins (t = "
			  "%.6f s): the frames before it are skipped", (long long)f->index,
		    f->utime / 1e6, r->gt_from, r->gt.t[0]);
	return true;
}

/* Speed messages refused since the last frame: the first of each reason is logged. */
static void log_refused_speed(struct run *r)
{
	struct mvod_speed_counts c;
	mvod_speed_counts(r->speed, &c);
	const char *ch = r->o->speed_channel;
	if (c.bad_type && !r->speed_refused.bad_type)
		LOG(WARN, "messages on %s are not mvod.speed_t (their fingerprint differs): "
			  "refused; publish mvod.speed_t there or name its channel with "
			  "--speed-channel", ch);
	if (c.bad_time && !r->speed_refused.bad_time)
		LOG(WARN, "an mvod.speed_t on %s has utime %lld, not after the one before or not "
			  "in 0 .. 2^61 us: refused (times must increase; later ones are only "
			  "counted)", ch,
		    (long long)c.last_bad_utime);
	if (c.bad_value && !r->speed_refused.bad_value)
		LOG(WARN, "an mvod.speed_t on %s has a speed or distance that is not finite or "
			  "beyond %g m/s: refused", ch, MVOD_SPEED_MAX);
	r->speed_refused = c;
}

/* --scale external: the robot's odometer at this frame's time, into the VO. */
static void feed_speed(struct run *r, const struct mvod_frame *f)
{
	double odo = NAN;
	bool stale = mvod_speed_odometer(r->speed, f->utime, &odo) != 0;
	mvod_vo_set_odometer(r->vo, stale ? NAN : odo);
	log_refused_speed(r);
	bool map = mvod_vo_run_mode(&r->o->vo) == MVOD_VO_MAP;
	if (stale && !r->speed_stale)
		LOG(WARN, "frame %lld (t = %.6f s): no mvod.speed_t on %s within %.1f s: %s until "
			  "speed arrives", (long long)f->index, f->utime / 1e6, r->o->speed_channel,
		    MVOD_SPEED_STALE_US / 1e6,
		    map ? "the map keeps its last scale (scale source \"map\", confidence falling)"
			: "steps keep the last scale from structure (scale source \"structure\", "
			  "confidence falling)");
	if (!stale && r->speed_stale)
		LOG(INFO, "frame %lld: speed on %s again", (long long)f->index, r->o->speed_channel);
	r->speed_stale = stale;
}

static int process_frame(struct run *r, const struct mvod_frame *f, double capture_ms)
{
	const struct mvod_pose *gt = gt_for(r, f);
	if ((r->o->vo.scale_mode == MVOD_SCALE_MODE_GT || r->o->require_gt) && !gt) {
		if (before_dataset_gt(r, f))
			return 0;
		log_missing_gt(r, f);
		return -ENOENT;
	}
	if (r->speed)
		feed_speed(r, f);
	struct mvod_vo_result res;
	int ret = mvod_vo_process(r->vo, &f->img, gt ? gt->t : NULL, &res);
	if (ret) {
		LOG(ERROR, "frame %lld: processing failed: %s", (long long)f->index, strerror(-ret));
		return ret;
	}
	res.ms[MVOD_STAGE_CAPTURE] = capture_ms;
	res.quality = mvod_vo_quality(&r->o->vo, &res); /* here, once, whatever made the pose */
	struct mvod_pose pose;
	mvod_body_frame_apply(&r->body, &res.pose, res.scale > 0 ? res.scale : 1, &pose);
	struct mvod_frame_out out = {f, &res, &pose, gt, record(r, f, &res), r->restarted};
	r->restarted = false;
	ret = sinks_frame(r, &out);
	r->latency_ms = (double)(mvod_now_us() - f->delivered_us) / 1e3;
	if (r->faults.status_due || status_periodic_due(r))
		publish_status(r, f, &res);
	r->last_frame = *f;
	r->last_res = res;
	return ret;
}

static bool stopped(const struct run *r, volatile sig_atomic_t *stop)
{
	return (stop && *stop) || (r->o->max_frames && r->sum->frames >= r->o->max_frames);
}

/* Between frames, in both loops: the watchdog sees the loop turn; a SIGHUP is acted on. */
static void between_frames(struct run *r)
{
	bool reopen = r->o->reopen && *r->o->reopen;
	if (reopen)
		*r->o->reopen = 0;
	sinks_between(r, reopen);
}

/*
 * One bad frame (undecodable, too large, of another size) is skipped, not fatal; counted by
 * reason for the summary, and logged the first time of each reason only.
 */
static void skip_unreadable(struct run *r, const struct mvod_frame *f)
{
	mvod_faults_set(&r->faults, MVOD_STATUS_T_FAULT_FRAME_UNREADABLE);
	if (r->sum->skipped[f->bad]++ == 0)
		LOG(WARN, "%s: frame %lld is %s (the sequence is %dx%d): skipped; later frames "
			  "skipped for this reason are only counted, in the summary",
		    r->o->source, (long long)f->index, mvod_bad_frame_name(f->bad), r->info.width,
		    r->info.height);
}

/* A read that failed for good: the run ends with the reason. */
static int read_failed(struct run *r, int ret)
{
	if (ret == -EIO) {
		mvod_faults_set(&r->faults, MVOD_STATUS_T_FAULT_SOURCE_BROKEN);
		LOG(ERROR, "%s broke off after %lld frames, before its announced end (a truncated "
			   "or corrupt file?): the outputs hold the frames before", r->o->source,
		    (long long)r->sum->frames);
		return ret;
	}
	LOG(ERROR, "%s: reading frame %lld failed: %s", r->o->source, (long long)r->sum->frames,
	    strerror(-ret));
	return ret;
}

static int start_capture(struct run *r)
{
	int ret = mvod_capture_start(r->src, r->o->source, &r->cap);
	if (ret)
		LOG(ERROR, "%s: cannot start the capture thread: %s", r->o->source, strerror(-ret));
	else
		r->src = NULL; /* the capture thread's now */
	return ret;
}

/*
 * Every frame of a source that is not live, in order, decoded on the capture thread while the
 * one before is processed. The capture stage's time is how long the loop waited for a frame.
 */
static int loop(struct run *r, volatile sig_atomic_t *stop)
{
	int ret = start_capture(r);
	while (!ret && !stopped(r, stop)) {
		between_frames(r);
		struct mvod_frame f;
		int epoch;
		double t0 = mvod_now_s();
		ret = mvod_capture_next(r->cap, LIVE_WAIT_MS, &f, &epoch);
		if (ret == -ENODATA)
			return 0;
		if (ret == -EAGAIN || ret == -EINVAL) {
			if (ret == -EINVAL)
				skip_unreadable(r, &f);
			ret = 0;
			continue;
		}
		if (ret)
			return read_failed(r, ret);
		ret = process_frame(r, &f, (mvod_now_s() - t0) * 1e3);
	}
	return ret;
}

/* While the capture thread reopens a source that went away, status says so every second. */
static void report_down(struct run *r)
{
	if (!mvod_capture_down(r->cap))
		return;
	bool changed = r->state != MVOD_RUN_SOURCE_DOWN;
	if (changed)
		LOG(INFO, "%s -> %s", mvod_run_state_name(r->state),
		    mvod_run_state_name(MVOD_RUN_SOURCE_DOWN));
	r->state = MVOD_RUN_SOURCE_DOWN;
	r->faults.status_due |= changed;
	if (r->faults.status_due || status_periodic_due(r))
		publish_status(r, &r->last_frame, &r->last_res);
}

/*
 * The source came back: what the VO knew of the scene is stale, so tracking starts over, but
 * from the last pose, so that a robot integrating the poses sees no jump back to the origin.
 */
static void restart_vo(struct run *r, const struct mvod_frame *f, int epoch)
{
	mvod_vo_restart(r->vo);
	r->epoch = epoch;
	r->restarted = true;
	const double *t = r->last_res.pose.t;
	LOG(INFO, "frame %lld: tracking re-initialised after the source came back; poses go on "
		  "from the last one, at (%.3f, %.3f, %.3f)",
	    (long long)f->index, t[0], t[1], t[2]);
}

/*
 * The frames a live source could not decode before f and not yet counted: into the summary's
 * skipped and the status's faults from this frame on (the capture thread logged them).
 */
static int64_t take_bad(struct run *r, const struct mvod_frame *f)
{
	int64_t n = 0;
	for (int k = 0; k < MVOD_BAD_COUNT; k++) {
		n += f->bad_before[k] - r->sum->skipped[k];
		r->sum->skipped[k] = f->bad_before[k];
	}
	if (n)
		mvod_faults_set(&r->faults, MVOD_STATUS_T_FAULT_FRAME_UNREADABLE);
	return n;
}

/*
 * Frames from a live source's capture thread, the newest each time. Frame numbers count every
 * frame the source produced, so a gap is exactly the frames dropped, by the driver or because
 * processing fell behind, and those that could not be decoded.
 */
static int live_loop(struct run *r, volatile sig_atomic_t *stop)
{
	int ret = start_capture(r);
	if (ret)
		return ret;
	r->sum->live = true;
	while (!stopped(r, stop)) {
		between_frames(r);
		struct mvod_frame f;
		int epoch;
		double t0 = mvod_now_s();
		ret = mvod_capture_next(r->cap, LIVE_WAIT_MS, &f, &epoch);
		if (ret == -EAGAIN) {
			report_down(r);
			continue;
		}
		if (ret == -ENODATA)
			return 0;
		if (ret)
			return read_failed(r, ret);
		if (epoch != r->epoch)
			restart_vo(r, &f, epoch);
		if (r->o->clock == MVOD_CLOCK_REALTIME)
			f.utime += mvod_realtime_offset_us();
		r->sum->dropped += f.index - r->last_index - 1 - take_bad(r, &f);
		r->last_index = f.index;
		ret = process_frame(r, &f, (mvod_now_s() - t0) * 1e3);
		if (ret)
			return ret;
	}
	return 0;
}

/* The last status: what was processed and dropped in all, and that mvod is stopping. */
static void report_stop(struct run *r)
{
	if (r->sum->frames) {
		r->state = MVOD_RUN_STOPPING;
		publish_status(r, &r->last_frame, &r->last_res);
	}
}

static void summarise(struct run *r)
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

int mvod_run(const struct mvod_run_opts *opts, struct mvod_ipc *ipc, volatile sig_atomic_t *stop,
	     struct mvod_run_summary *summary)
{
	struct run r = {.o = opts, .ipc = ipc, .sum = summary, .state = MVOD_RUN_STARTING,
			.last_index = -1};
	*summary = (struct mvod_run_summary){.gt_first = -1, .gt_last = -1};
	int ret = open_inputs(&r);
	if (!ret)
		ret = open_outputs(&r);
	summary->config_failed = ret && r.src && ret != -ENOMEM;
	if (!ret) {
		r.t_start = mvod_now_s();
		ret = r.info.live ? live_loop(&r, stop) : loop(&r, stop);
		mvod_capture_stop(r.cap);
		report_stop(&r);
		summarise(&r);
		int fret = sinks_finish(&r);
		if (!ret)
			ret = fret;
	}
	sinks_destroy(&r);
	mvod_speed_destroy(r.speed);
	mvod_vo_destroy(r.vo);
	mvod_traj_free(&r.gt);
	mvod_source_close(r.src);
	return ret;
}
