/* The run's inputs: the source, its camera, the ground truth, the scale's sources, the VO. */
#include "internal.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "mvod/calibrate.h"
#include "mvod/log.h"
#include "util/errbuf.h"

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
		const char *good = mvod_calib_verdict_name(MVOD_VERDICT_GOOD);
		if (r->cam.verdict[0] && strcmp(r->cam.verdict, good) != 0)
			LOG(WARN, "calibration %s was judged \"%s\" by mvod calibrate: the poses may "
				  "be off; calibrate again (mvod calibrate --help)", o->calib,
			    r->cam.verdict);
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

/* Whether frames of cam's size, scaled by --resize, are large enough for the VO. */
static int check_frames(const struct mvod_vo_params *params, const struct mvod_camera *cam,
			char *err, size_t errlen)
{
	/* As mvod_cv_preproc_create rounds. */
	int w = (int)(cam->width * params->resize + 0.5), h = (int)(cam->height * params->resize + 0.5);
	if (w >= MVOD_VO_MIN_PX && h >= MVOD_VO_MIN_PX)
		return 0;
	if (params->resize < 1)
		return mvod_errf(err, errlen, -EINVAL, "frames of %dx%d are %dx%d after --resize %g, "
				 "smaller than the %dx%d pixels the feature detector needs: raise "
				 "--resize", cam->width, cam->height, w, h, params->resize,
				 MVOD_VO_MIN_PX, MVOD_VO_MIN_PX);
	return mvod_errf(err, errlen, -EINVAL, "frames of %dx%d are smaller than the %dx%d pixels "
			 "the feature detector needs", cam->width, cam->height, MVOD_VO_MIN_PX,
			 MVOD_VO_MIN_PX);
}

/*
 * The front end that runs, and why when auto chose. --features with klt is no clash (it was
 * auto's switch to orb): a file may set it for when orb runs; but a user who set it to go
 * faster or see more is told, once, what klt reads instead. By value, as auto reads options.
 */
static void log_frontend(const struct mvod_vo_params *p)
{
	const char *name = mvod_vo_frontend_name(p), *opt = mvod_vo_descriptor_option(p);
	if (p->frontend != MVOD_FRONTEND_AUTO)
		LOG(INFO, "front end: %s", name);
	else if (opt)
		LOG(INFO, "front end: %s (--frontend auto: --%s is an option of orb and sift only)",
		    name, opt);
	else
		LOG(INFO, "front end: %s (--frontend auto)", name);
	struct mvod_vo_params d;
	mvod_vo_params_default(&d);
	if (mvod_vo_frontend(p) == MVOD_FRONTEND_KLT && p->max_features != d.max_features)
		LOG(WARN, "--features %d is the orb and sift front ends' feature count; klt runs, "
			  "whose budget is --tracks (%d)", p->max_features, p->max_tracks);
}

int mvod_run_open_inputs(struct run *r)
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
	ret = check_frames(&o->vo, &r->cam, err, sizeof(err));
	if (ret) {
		LOG(ERROR, "%s: %s", o->source, err);
		return ret;
	}
	r->sum->frontend = mvod_vo_frontend_name(&o->vo);
	log_frontend(&o->vo);
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

/* Ground truth for a frame: KITTI files by index, TUM files by nearest timestamp. */
const struct mvod_pose *mvod_run_gt_for(const struct run *r, const struct mvod_frame *f)
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

/* Why frame f has no ground-truth pose, for a run that needs one for every frame. */
void mvod_run_log_missing_gt(const struct run *r, const struct mvod_frame *f)
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
bool mvod_run_before_gt(struct run *r, const struct mvod_frame *f)
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
void mvod_run_feed_speed(struct run *r, const struct mvod_frame *f)
{
	double odo = NAN;
	bool stale = mvod_speed_odometer(r->speed, f->utime, &odo) != 0;
	mvod_vo_set_odometer(r->vo, stale ? NAN : odo);
	log_refused_speed(r);
	bool map = r->o->vo.mode == MVOD_VO_MAP;
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
