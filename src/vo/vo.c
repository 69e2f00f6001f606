#include "mvod/vo.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vo/optim/ba_shim.h"
#include "vo/frontend/cv_shim.h"
#include "vo/frontend/klt.h"
#include "vo/map/mapvo.h"
#include "vo/frontend/match.h"
#include "util/clock.h"
#include "util/errbuf.h"
#include "vo_internal.h"
#include "vo_seam.h"

/*
 * A rotation-only frame keeps the reference while it shares at least this many times
 * min_matches with it, so parallax can build up over the next frames; the margin of 2 leaves
 * the next frame, which overlaps the reference a little less again, above min_matches.
 */
#define ROTATION_KEEP_OVERLAP 2

/*
 * The matches below which a ROTATION frame moves the reference on. Map mode waiting for a map
 * (first or rebuilt) holds the translation of steps too short for one (mapping.c), and takes
 * their rotation from an essential matrix against the kept reference: it keeps the reference
 * only while the margin leaves the next frame the points a map needs. Measured on mvod-synth's
 * turn (320x240, 3.75 deg a frame): with min_matches' margin (60) the reference of frame 29
 * was kept until frame 35, whose 38 inliers gave a rotation 24 deg off, held ever after
 * (rotation error 0.446 deg a frame, max 24.4); with 200 the reference moves on at frame 31
 * (185 matches), the map is rebuilt at 34 from 31 (was 45 from 35), and the worst frame is
 * 0.11 deg off (mean 0.022). 100-250 all rotate as well (max 0.21 deg); with 100, 120 and 250
 * the map rebuilt at 35 (from 33) is lost again at 55. KITTI 06 and 07 trajectories are
 * bit-identical in both modes, mvod-synth's KITTI 00 gives the same figures (BENCHMARKS.md).
 */
static int keep_overlap(const struct mvod_vo *vo)
{
	return ROTATION_KEEP_OVERLAP * (vo->mapvo ? MVOD_MAPVO_INIT_MIN_POINTS : vo->p.min_matches);
}
/*
 * --scale height: a step's height measurement moves the scale by this fraction (in log
 * space), and one more than 25 % off the prediction is refused. On mvod-synth's street at
 * 0.2 m a step, structure shrinks the step by 5-10 % a step in places: gains 0.2, 0.35 and
 * 0.5 gave SE(3) ATE 1.6 m (14 %), 0.11 m (1.0 %) and 0.07 m (0.6 %) over 11.8 m.
 */
#define HEIGHT_GAIN 0.5
#define HEIGHT_GATE 0.22 /* log(1.25) */
/*
 * --scale height: the first scale is the median of this many measurements (the output held
 * until then). 3 while heights were the fit's own plane's distance: one measurement on KITTI
 * 07's opening creep scattered 30 % and, taken whole, set the unit of all that came before.
 * Along the learnt normal (scale.h) the first measurement alone is the better start: SE(3)
 * ATE at 3 and 1, --camera-height 1.65: 06 two-view 0.642 / 0.408 m, map 0.543 / 0.410 m;
 * 07 two-view 0.409 / 0.394 m, map 0.348 / 0.342 m (drift 1.126 / 1.119).
 */
#define HEIGHT_FIRST 1

const char *const mvod_stage_names[MVOD_STAGE_COUNT] = {"capture", "preprocess", "detect", "match",
							 "pose"};

const char *mvod_frame_status_name(enum mvod_frame_status s)
{
	static const char *const names[] = {"motion",      "first",        "rotation",
					    "few-features", "few-matches", "ransac-failed",
					    "few-inliers"};
	return (unsigned)s < sizeof(names) / sizeof(names[0]) ? names[s] : "unknown";
}

const char *mvod_scale_source_name(enum mvod_scale_source s)
{
	static const char *const names[] = {"none", "structure", "constant-speed", "ground-truth",
					    "unit", "map", "height", "external"};
	return (unsigned)s < sizeof(names) / sizeof(names[0]) ? names[s] : "unknown";
}

const char *const mvod_frontend_names[] = {"orb", "klt", "auto", NULL};
const char *const mvod_detector_names[] = {"orb", "sift", NULL};
const char *const mvod_matcher_names[MVOD_MATCHER_COUNT + 1] = {"bf", "bf-cross", "bf-ratio",
								"flann", "flann-ratio", NULL};
const char *const mvod_robust_names[] = {"magsac", "ransac", NULL};
const char *const mvod_vo_mode_names[] = {"twoview", "map", NULL};
#define DETECTORS ((int)(sizeof(mvod_detector_names) / sizeof(mvod_detector_names[0])) - 1)

const char *mvod_detector_name(enum mvod_detector d)
{
	return (unsigned)d < DETECTORS ? mvod_detector_names[d] : "unknown";
}

const char *mvod_matcher_kind_name(enum mvod_matcher_kind m)
{
	return (unsigned)m < MVOD_MATCHER_COUNT ? mvod_matcher_names[m] : "unknown";
}

bool mvod_vo_map_available(void)
{
	return mvod_ba_present;
}

/*
 * Map mode is the default (issue 12): on KLT tracks it beats two-view on the KITTI clips with
 * --scale gt, free scale and the camera's height, and on mvod-synth's KITTI 00 drive with the
 * camera's height (t_rel 2.05-2.76 % against 9.01 %; BENCHMARKS.md, the eighth merge). Where it cannot run (no Ceres, --scale
 * external) two-view does: mvod_vo_map_missing.
 */
void mvod_vo_params_default(struct mvod_vo_params *p)
{
	*p = (struct mvod_vo_params){
		.mode = MVOD_VO_MAP,
		.resize = 1.0,
		.blur_ksize = 0,
		.frontend = MVOD_FRONTEND_AUTO,
		.detector = MVOD_DETECTOR_ORB,
		.max_features = 2000,
		.max_tracks = 500,
		.matcher = MVOD_MATCHER_BF,
		.ratio = 0.8,
		.best_n = 200,
		.robust = MVOD_ROBUST_MAGSAC,
		.ransac_px = 1.0,
		.ransac_conf = 0.999,
		.min_matches = 30,
		.min_inliers = 20,
		.min_parallax_px = 1.0,
		.scale_mode = MVOD_SCALE_MODE_AUTO,
	};
}

const char *const mvod_vo_descriptor_flags[] = {"detector", "matcher", "features", "ratio",
						 "best", NULL};

const char *mvod_vo_descriptor_option(const struct mvod_vo_params *p)
{
	struct mvod_vo_params d;
	mvod_vo_params_default(&d);
	/* In the order of mvod_vo_descriptor_flags. */
	bool differs[] = {p->detector != d.detector, p->matcher != d.matcher,
			  p->max_features != d.max_features, p->ratio != d.ratio,
			  p->best_n != d.best_n};
	for (int i = 0; mvod_vo_descriptor_flags[i]; i++)
		if (differs[i])
			return mvod_vo_descriptor_flags[i];
	return NULL;
}

/*
 * The one place auto is decided: klt in both modes (map mode on KLT tracks beat it on ORB
 * descriptors in every figure on KITTI 06/07: free-scale drift 1.007/1.035 against
 * 1.066/1.384; BENCHMARKS.md), orb when the user tunes the descriptor front end.
 */
enum mvod_frontend mvod_vo_frontend(const struct mvod_vo_params *p)
{
	if (p->frontend != MVOD_FRONTEND_AUTO)
		return p->frontend;
	if (mvod_vo_descriptor_option(p))
		return MVOD_FRONTEND_ORB;
	return MVOD_FRONTEND_KLT;
}

/*
 * A build without Ceres must run the default and an installed config that says map, and map
 * mode without bundle adjustment is not the map mode BENCHMARKS.md measured: two-view runs
 * instead, and the run loop says why.
 */
const char *mvod_vo_map_missing(const struct mvod_vo_params *p)
{
	if (p->mode != MVOD_VO_MAP)
		return NULL;
	if (!mvod_vo_map_available())
		return "map mode needs Ceres (bundle adjustment), which this mvod was built without "
		       "(install libceres-dev and rebuild for map mode)";
	return NULL;
}

enum mvod_vo_mode mvod_vo_run_mode(const struct mvod_vo_params *p)
{
	return mvod_vo_map_missing(p) ? MVOD_VO_TWOVIEW : p->mode;
}

int mvod_vo_check_frontend(const struct mvod_vo_params *p, char *err, size_t errlen)
{
	struct mvod_vo_params d;
	mvod_vo_params_default(&d);
	const char *opt = mvod_vo_descriptor_option(p);
	if (mvod_vo_run_mode(p) == MVOD_VO_MAP && p->detector != MVOD_DETECTOR_ORB)
		return mvod_errf(err, errlen, -EINVAL, "--mode map keeps ORB descriptors in its map, "
				 "not %s: use --detector orb or --mode twoview",
				 mvod_detector_name(p->detector));
	if (p->frontend == MVOD_FRONTEND_KLT && opt)
		return mvod_errf(err, errlen, -EINVAL, "--%s is an option of the descriptor front "
				 "end, which --frontend klt does not run: drop --%s, or use "
				 "--frontend orb (or auto, which then picks orb)", opt, opt);
	if (mvod_vo_frontend(p) != MVOD_FRONTEND_ORB || p->max_tracks == d.max_tracks)
		return 0;
	if (p->frontend == MVOD_FRONTEND_ORB)
		return mvod_errf(err, errlen, -EINVAL, "--tracks is an option of the KLT front end, "
				 "which --frontend orb does not run: drop --tracks, or use "
				 "--frontend klt (or auto)");
	return mvod_errf(err, errlen, -EINVAL, "--tracks is an option of the KLT front end and "
			 "--%s one of the descriptor front end: drop one of them", opt);
}

bool mvod_vo_tracked(const struct mvod_vo_result *res)
{
	return res->state == MVOD_STATE_TRACKING &&
	       (res->status == MVOD_FRAME_MOTION || res->status == MVOD_FRAME_ROTATION);
}

double mvod_vo_quality(const struct mvod_vo_params *p, const struct mvod_vo_result *res)
{
	if (!mvod_vo_tracked(res))
		return 0;
	double q = res->inliers / (double)(MVOD_QUALITY_INLIERS * p->min_inliers);
	return q < 1 ? q : 1;
}

static int slot_init(struct frame_slot *k, int cap, int desc_bytes)
{
	k->f.cap = cap;
	k->f.desc_bytes = desc_bytes;
	k->f.kp = calloc((size_t)cap, sizeof(*k->f.kp));
	k->f.desc = calloc((size_t)cap, (size_t)desc_bytes);
	k->pts = calloc((size_t)cap * 3, sizeof(double));
	k->has_pt = calloc((size_t)cap, 1);
	k->par = calloc((size_t)cap, sizeof(float));
	return k->f.kp && k->f.desc && k->pts && k->has_pt && k->par ? 0 : -ENOMEM;
}

static void slot_fini(struct frame_slot *k)
{
	free(k->f.kp);
	free(k->f.desc);
	free(k->pts);
	free(k->has_pt);
	free(k->par);
}

static int alloc_buffers(struct mvod_vo *vo)
{
	size_t n = (size_t)vo->cap;
	vo->matches = calloc(n, sizeof(*vo->matches));
	vo->x1 = calloc(n * 2, sizeof(double));
	vo->x2 = calloc(n * 2, sizeof(double));
	vo->depth = calloc(n, sizeof(double));
	vo->prev_pts = calloc(n * 3, sizeof(double));
	vo->cur_pts = calloc(n * 3, sizeof(double));
	vo->scratch = calloc(n, sizeof(double));
	vo->mask = calloc(n, 1);
	if (!vo->matches || !vo->x1 || !vo->x2 || !vo->depth || !vo->prev_pts || !vo->cur_pts ||
	    !vo->scratch || !vo->mask)
		return -ENOMEM;
	for (int i = 0; i < 2; i++)
		if (slot_init(&vo->slot[i], vo->cap, mvod_cv_desc_bytes(vo->p.detector)))
			return -ENOMEM;
	return 0;
}

int mvod_vo_check_size(const struct mvod_vo_params *params, const struct mvod_camera *cam,
		       char *err, size_t errlen)
{
	int ret = mvod_vo_check_frontend(params, err, errlen);
	if (ret)
		return ret;
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

/* The descriptor front end: detector and matcher. */
static int descriptors_create(struct mvod_vo *vo)
{
	const struct mvod_vo_params *p = &vo->p;
	int ret = mvod_cv_detector_create(p->detector, p->max_features, vo->cam.width,
					  vo->cam.height, &vo->det);
	if (ret)
		return ret;
	struct mvod_match_params mp = {p->matcher, p->detector, p->ratio, p->best_n};
	return mvod_matcher_create(&mp, vo->cap, &vo->matcher);
}

static int klt_create(struct mvod_vo *vo)
{
	struct mvod_klt_params kp;
	mvod_klt_params_default(&kp);
	kp.max_tracks = vo->p.max_tracks;
	return mvod_klt_create(&kp, vo->cam.width, vo->cam.height, &vo->klt);
}

/*
 * --scale height: the camera file's mount gives the height when no --camera-height does, and
 * the ground normal's first estimate (the fit searches +-4 deg about it).
 */
static void mount(struct mvod_vo *vo, const struct mvod_camera *cam)
{
	if (vo->p.scale_mode != MVOD_SCALE_MODE_HEIGHT || !cam->has_mount)
		return;
	if (!(vo->p.camera_height_m > 0))
		vo->p.camera_height_m = cam->mount_height_m;
	mvod_ground_normal(cam->mount_pitch_deg, cam->mount_roll_deg, vo->scale.ground_n);
	vo->scale.normal_fits = MVOD_GROUND_MOUNT_FITS;
}

int mvod_vo_create(const struct mvod_vo_params *params, const struct mvod_camera *cam,
		   struct mvod_vo **out)
{
	struct mvod_vo *vo = calloc(1, sizeof(*vo));
	if (!vo)
		return -ENOMEM;
	vo->p = *params;
	vo->p.frontend = mvod_vo_frontend(params);
	vo->p.mode = mvod_vo_run_mode(params);
	/* ORB and SIFT may return a few more than asked for (ties); the cap leaves room. */
	bool klt = vo->p.frontend == MVOD_FRONTEND_KLT;
	int n = klt ? params->max_tracks : params->max_features;
	vo->cap = n + n / 4 + 16;
	int ret = mvod_cv_preproc_create(cam, params->resize, params->blur_ksize, &vo->cam, &vo->pre);
	if (ret)
		goto fail;
	ret = klt ? klt_create(vo) : descriptors_create(vo);
	if (ret)
		goto fail;
	ret = alloc_buffers(vo);
	if (ret)
		goto fail;
	if (vo->p.mode == MVOD_VO_MAP) {
		ret = mvod_mapvo_create(vo, &vo->mapvo);
		if (ret)
			goto fail;
	}
	vo->ref = &vo->slot[0];
	vo->cur = &vo->slot[1];
	mvod_pose_identity(&vo->pose);
	vo->state = MVOD_STATE_INITIALIZING;
	vo->slot[0].odo = vo->slot[1].odo = NAN;
	/*
	 * The odometer is metric already: two-view's steps take it whole, never refused (map
	 * mode's keyframe ratios have a gate of their own: mapscale.c).
	 */
	if (params->scale_mode == MVOD_SCALE_MODE_EXTERNAL)
		mvod_scale_filter_init(&vo->scale, 1.0, INFINITY);
	else
		mvod_scale_filter_init(&vo->scale, HEIGHT_GAIN, HEIGHT_GATE);
	vo->scale.first_n = params->scale_mode == MVOD_SCALE_MODE_HEIGHT ? HEIGHT_FIRST : 1;
	/* Map mode: no tilt gate (scale.h, MVOD_GROUND_MAX_TILT_DEG). */
	if (vo->p.mode == MVOD_VO_MAP)
		vo->scale.max_tilt_deg = 180;
	mount(vo, cam);
	*out = vo;
	return 0;
fail:
	mvod_vo_destroy(vo);
	return ret;
}

void mvod_vo_destroy(struct mvod_vo *vo)
{
	if (!vo)
		return;
	mvod_cv_preproc_destroy(vo->pre);
	mvod_cv_detector_destroy(vo->det);
	mvod_matcher_destroy(vo->matcher);
	mvod_klt_destroy(vo->klt);
	mvod_mapvo_destroy(vo->mapvo);
	for (int i = 0; i < 2; i++)
		slot_fini(&vo->slot[i]);
	free(vo->matches);
	free(vo->x1);
	free(vo->x2);
	free(vo->depth);
	free(vo->prev_pts);
	free(vo->cur_pts);
	free(vo->scratch);
	free(vo->mask);
	free(vo);
}

void mvod_vo_promote(struct mvod_vo *vo, const double *gt, bool with_structure)
{
	if (!with_structure) {
		memset(vo->cur->has_pt, 0, (size_t)vo->cur->f.n);
		vo->cur->has_par = 0;
	}
	struct frame_slot *k = vo->ref;
	vo->ref = vo->cur;
	vo->cur = k;
	vo->ref->pose = vo->pose;
	if (gt)
		memcpy(vo->ref->gt, gt, sizeof(vo->ref->gt));
	vo->have_ref = 1;
}

/*
 * After a frame: the tracking state, and whether the frame becomes the reference.
 *
 *   frame status           state                        becomes the reference
 *   MOTION                 TRACKING                     yes, with its structure (next scale)
 *   ROTATION               unchanged                    when it shares fewer than
 *                                                       keep_overlap() matches with the
 *                                                       reference
 *   FIRST, FEW_MATCHES,    TRACKING -> LOST, else same  yes, without structure: rich enough to
 *   RANSAC_FAILED,                                      start again from
 *   FEW_INLIERS
 *   FEW_FEATURES           TRACKING -> LOST, else same  no: nothing to start from
 */
static void settle(struct mvod_vo *vo, const double *gt, struct mvod_vo_result *res)
{
	enum mvod_frame_status st = res->status;
	if (st == MVOD_FRAME_MOTION) {
		vo->state = MVOD_STATE_TRACKING;
		mvod_vo_promote(vo, gt, true);
		return;
	}
	if (st == MVOD_FRAME_ROTATION) {
		if (res->matches < keep_overlap(vo))
			mvod_vo_promote(vo, gt, false);
		return;
	}
	if (vo->state == MVOD_STATE_TRACKING)
		vo->state = MVOD_STATE_LOST;
	if (st != MVOD_FRAME_FEW_FEATURES)
		mvod_vo_promote(vo, gt, false);
}

void mvod_vo_set_odometer(struct mvod_vo *vo, double metres)
{
	vo->cur->odo = metres;
}

bool mvod_scale_mode_metric(enum mvod_scale_mode m)
{
	return m == MVOD_SCALE_MODE_GT || m == MVOD_SCALE_MODE_HEIGHT ||
	       m == MVOD_SCALE_MODE_EXTERNAL;
}

/*
 * The output's metres per unit (1 once metric, 0 while unknown) and its confidence. With
 * --scale height or external, until the first measurement the position is held at the origin
 * (source NONE, scale 0): the steps so far have no known unit (KITTI 07 creeps 8 frames at
 * 0.1 m a step as 1.0 "m" steps before the road is measured). The chain goes on unpublished
 * and the first measurement rescales it (twoview.c, mapscale.c): published poses are never
 * rewritten (the output policy), the position jumps once, to the metric one.
 */
static void report_scale(const struct mvod_vo *vo, struct mvod_vo_result *res)
{
	if (vo->p.scale_mode == MVOD_SCALE_MODE_GT) {
		res->scale = res->scale_confidence = 1.0;
	} else if (vo->p.scale_mode != MVOD_SCALE_MODE_AUTO) {
		bool metric = mvod_scale_filter_metric(&vo->scale);
		res->scale = metric ? 1.0 : 0.0;
		res->scale_confidence = mvod_scale_filter_confidence(&vo->scale);
		if (metric)
			return;
		memset(res->pose.t, 0, sizeof(res->pose.t));
		res->scale_source = MVOD_SCALE_NONE;
		res->step_m = 0;
	}
}

void mvod_vo_restart(struct mvod_vo *vo)
{
	vo->have_ref = 0;
	vo->state = MVOD_STATE_INITIALIZING;
	mvod_klt_reset(vo->klt);
	mvod_mapvo_reset(vo->mapvo);
}

/* Map mode's counts, which every frame reports. */
static void map_counts(const struct mvod_vo *vo, struct mvod_vo_result *res)
{
	res->map_points = mvod_map_n_points(vo->mapvo->map);
	res->keyframes = mvod_map_n_keyframes(vo->mapvo->map);
}

/*
 * Map mode's tracking against the map: 1 when it took the frame (res filled), 0 when the
 * two-view algorithm is to (no map yet, or just lost), -errno.
 */
static int map_track(struct mvod_vo *vo, const double *gt, struct mvod_vo_result *res,
		     double t0)
{
	int ret = mvod_mapvo_track(vo, gt, res);
	if (ret <= 0)
		return ret;
	map_counts(vo, res);
	res->pose = vo->pose;
	res->state = vo->state;
	report_scale(vo, res);
	res->ms[MVOD_STAGE_POSE] = 1e3 * mvod_now_s() - t0;
	return 1;
}

/*
 * The current slot's features against the reference: match, estimate, settle. Fills the
 * result's match and pose stage times, pose and state.
 */
static int track(struct mvod_vo *vo, const double *gt, struct mvod_vo_result *res)
{
	double t0 = 1e3 * mvod_now_s();
	if (vo->mapvo) {
		int handled = map_track(vo, gt, res, t0);
		if (handled)
			return handled < 0 ? handled : 0;
	}
	int n = vo->cur->f.n;
	const struct frame_slot *tracked = vo->cur;
	bool matched = false; /* enough matches against the reference to estimate motion */
	res->features = n;
	if (!vo->have_ref) {
		res->status = n >= vo->p.min_matches ? MVOD_FRAME_FIRST : MVOD_FRAME_FEW_FEATURES;
	} else if (n < vo->p.min_matches) {
		res->status = MVOD_FRAME_FEW_FEATURES;
	} else {
		/* KLT matched while tracking: its matches are in vo->matches already. */
		int ret = vo->klt ? (res->matches = vo->klt_matches, 0)
				  : mvod_match(vo->matcher, &vo->ref->f, &vo->cur->f, vo->matches,
					       vo->cap, &res->matches);
		if (ret)
			return ret;
		matched = res->matches >= vo->p.min_matches;
		res->status = MVOD_FRAME_FEW_MATCHES;
	}
	double t1 = 1e3 * mvod_now_s();
	if (matched)
		res->status = mvod_twoview_estimate(vo, gt, res);
	int made_map = vo->mapvo ? mvod_mapvo_init(vo, res) : 0;
	if (made_map < 0)
		return made_map;
	settle(vo, gt, res);
	if (vo->klt && vo->ref == tracked)
		mvod_klt_promote(vo->klt);
	/* Map mode: TRACKING means against a map; two-view frames only keep the pose going. */
	if (vo->mapvo) {
		vo->state = made_map	      ? MVOD_STATE_TRACKING
			    : vo->mapvo->lost ? MVOD_STATE_LOST
					      : MVOD_STATE_INITIALIZING;
		map_counts(vo, res);
	}
	res->pose = vo->pose;
	res->state = vo->state;
	report_scale(vo, res);
	res->ms[MVOD_STAGE_MATCH] = t1 - t0;
	res->ms[MVOD_STAGE_POSE] = 1e3 * mvod_now_s() - t1;
	return 0;
}

/* What both entry points check and clear first. */
static int begin(struct mvod_vo *vo, const double *gt, struct mvod_vo_result *res)
{
	if (vo->p.scale_mode == MVOD_SCALE_MODE_GT && !gt)
		return -EINVAL;
	memset(res, 0, sizeof(*res));
	vo->cur->seq = vo->frames++;
	vo->cur->has_par = 0; /* until a two-view step writes its parallax (twoview.c) */
	return 0;
}

int mvod_vo_band_quad(const struct mvod_vo *vo, float quad[8])
{
	return mvod_ground_band_quad(vo->scale.ground_n, vo->cam.fx, vo->cam.fy, vo->cam.cx,
				     vo->cam.cy, quad);
}

/*
 * --scale height with KLT: a share of the tracks on the road band (scale.h), whose smooth
 * asphalt the tracker's own detection leaves almost bare (KITTI 06: one step in 50 found
 * 20 ground points).
 */
#define BAND_SHARE 3     /* a third of max_tracks (see BENCHMARKS.md, issue 14) */
#define BAND_FAST 10     /* FAST contrast on the band, grey levels */
static int klt_track(struct mvod_vo *vo, const struct mvod_image *grey)
{
	int ret = mvod_klt_track(vo->klt, grey, &vo->cur->f, vo->matches, &vo->klt_matches);
	float quad[8];
	if (ret || vo->p.scale_mode != MVOD_SCALE_MODE_HEIGHT || mvod_vo_band_quad(vo, quad) != 0)
		return ret;
	return mvod_klt_reserve(vo->klt, grey, quad, vo->p.max_tracks / BAND_SHARE, BAND_FAST,
				&vo->cur->f);
}

/*
 * ORB, every scale mode: as klt_track's share, detected on the road band with FAST's contrast
 * lowered. --scale height needs it: ORB's own 2000 features found no ground on KITTI 06, whose
 * steps then stayed held for want of a first scale (the whole clip at the origin). The others
 * too: ORB's strongest corners cluster on buildings and cars, mostly far, whose flow hardly
 * depends on the translation; the road's near points, with the largest parallax, pin its
 * direction (with twoview.c's refinement, KITTI 07's direction error per frame 3.22 -> 1.19
 * deg; BENCHMARKS.md, issue 12's "ORB's two-view pose refined").
 */
static int orb_detect(struct mvod_vo *vo, const struct mvod_image *grey)
{
	float quad[8];
	if (mvod_vo_band_quad(vo, quad) != 0)
		return mvod_cv_detect(vo->det, grey, &vo->cur->f);
	return mvod_cv_detect_band(vo->det, grey, quad, vo->p.max_features / BAND_SHARE,
				   BAND_FAST, &vo->cur->f);
}

int mvod_vo_process(struct mvod_vo *vo, const struct mvod_image *img, const double *gt_position,
		    struct mvod_vo_result *res)
{
	int ret = begin(vo, gt_position, res);
	if (ret)
		return ret;
	double t0 = 1e3 * mvod_now_s();
	struct mvod_image grey;
	ret = mvod_cv_preproc_run(vo->pre, img, &grey);
	if (ret)
		return ret;
	double t1 = 1e3 * mvod_now_s();
	ret = vo->klt ? klt_track(vo, &grey) : orb_detect(vo, &grey);
	if (ret)
		return ret;
	res->ms[MVOD_STAGE_PREPROCESS] = t1 - t0;
	res->ms[MVOD_STAGE_DETECT] = 1e3 * mvod_now_s() - t1;
	return track(vo, gt_position, res);
}

int mvod_vo_process_features(struct mvod_vo *vo, const struct mvod_features *f,
			     const double *gt_position, struct mvod_vo_result *res)
{
	struct mvod_features *cur = &vo->cur->f;
	if (vo->klt || f->n < 0 || f->n > cur->cap || f->desc_bytes != cur->desc_bytes)
		return -EINVAL;
	int ret = begin(vo, gt_position, res);
	if (ret)
		return ret;
	memcpy(cur->kp, f->kp, (size_t)f->n * sizeof(*f->kp));
	memcpy(cur->desc, f->desc, (size_t)f->n * (size_t)f->desc_bytes);
	cur->n = f->n;
	return track(vo, gt_position, res);
}
