/*
 * The run loop: read a frame, process it, fan the result out to the sinks. Files, image
 * folders and datasets: every frame, in order (loop); cameras: always the newest (live_loop).
 */
#include "mvod/pipeline.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "mvod/log.h"
#include "internal.h"
#include "util/clock.h"
#include "mvod_status_t.h"

/* How long the live loop waits for a frame before it looks at the stop flag again. */
#define LIVE_WAIT_MS 100

void mvod_run_opts_default(struct mvod_run_opts *o)
{
	*o = (struct mvod_run_opts){.traj_format = MVOD_TRAJ_TUM, .status_hz = 1,
				    .speed_channel = MVOD_DEFAULT_SPEED_CHANNEL};
	mvod_vo_params_default(&o->vo);
}

static int process_frame(struct run *r, const struct mvod_frame *f, double capture_ms)
{
	const struct mvod_pose *gt = mvod_run_gt_for(r, f);
	if ((r->o->vo.scale_mode == MVOD_SCALE_MODE_GT || r->o->require_gt) && !gt) {
		if (mvod_run_before_gt(r, f))
			return 0;
		mvod_run_log_missing_gt(r, f);
		return -ENOENT;
	}
	if (r->speed)
		mvod_run_feed_speed(r, f);
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
	struct mvod_frame_out out = {f, &res, &pose, gt, mvod_run_record(r, f, &res), r->restarted};
	r->restarted = false;
	ret = mvod_run_sinks_frame(r, &out);
	r->latency_ms = (double)(mvod_now_us() - f->delivered_us) / 1e3;
	if (r->faults.status_due || mvod_run_status_due(r))
		mvod_run_publish_status(r, f, &res);
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
	mvod_run_sinks_between(r, reopen);
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
	if (r->faults.status_due || mvod_run_status_due(r))
		mvod_run_publish_status(r, &r->last_frame, &r->last_res);
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
		mvod_run_publish_status(r, &r->last_frame, &r->last_res);
	}
}

int mvod_run(const struct mvod_run_opts *opts, struct mvod_ipc *ipc, volatile sig_atomic_t *stop,
	     struct mvod_run_summary *summary)
{
	struct run r = {.o = opts, .ipc = ipc, .sum = summary, .state = MVOD_RUN_STARTING,
			.last_index = -1};
	*summary = (struct mvod_run_summary){.gt_first = -1, .gt_last = -1};
	int ret = mvod_run_open_inputs(&r);
	if (!ret)
		ret = mvod_run_open_outputs(&r);
	summary->config_failed = ret && r.src && ret != -ENOMEM;
	if (!ret) {
		r.t_start = mvod_now_s();
		ret = r.info.live ? live_loop(&r, stop) : loop(&r, stop);
		mvod_capture_stop(r.cap);
		report_stop(&r);
		mvod_run_summarise(&r);
		int fret = mvod_run_sinks_finish(&r);
		if (!ret)
			ret = fret;
	}
	mvod_run_sinks_destroy(&r);
	mvod_speed_destroy(r.speed);
	mvod_vo_destroy(r.vo);
	mvod_traj_free(&r.gt);
	mvod_source_close(r.src);
	return ret;
}
