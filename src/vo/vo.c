/*
 * The VO's facade: it owns the one VO state (the frames, the scale, the front end, the
 * published pose and the tracking state), runs a frame through the front end and a mode, and
 * applies what the mode answers (the pose, and from the frame's status the state and the
 * reference: settle). The modes (twoview/, map/) read and change the shared state only through
 * the context it hands them (core/ctx.h).
 */
#include "mvod/vo.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/clock.h"
#include "vo/core/camera.h"
#include "vo/core/ctx.h"
#include "vo/frontend/cv_shim.h"
#include "vo/frontend/fe.h"
#include "vo/map/mapmode.h"
#include "vo/twoview/twoview.h"
#include "vo_seam.h"

struct mvod_vo {
	struct mvod_vo_params p; /* resolved: the front end and the mode that run */
	struct mvod_camera cam;  /* after preprocessing: pinhole, no distortion */
	struct mvod_cv_preproc *pre;
	struct mvod_fe *fe;
	struct mvod_frames fr;
	struct mvod_scale scale;
	struct mvod_vo_ctx ctx;    /* the modes' view of the above */
	struct mvod_twoview *tv;
	struct mvod_mapmode *map;  /* --mode map, else NULL */
	struct mvod_pose pose;     /* the last published pose */
	enum mvod_track_state state;
};

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
	return ROTATION_KEEP_OVERLAP * (vo->map ? MVOD_MAPMODE_INIT_MIN_POINTS : vo->p.min_matches);
}

/* The front end, the frames and the modes of a VO whose p and cam are set. */
static int create_parts(struct mvod_vo *vo, const struct mvod_camera *cam)
{
	/* ORB and SIFT may return a few more than asked for (ties); the cap leaves room. */
	bool klt = vo->p.frontend == MVOD_FRONTEND_KLT;
	int n = klt ? vo->p.max_tracks : vo->p.max_features;
	int cap = n + n / 4 + 16;
	int ret = mvod_cv_preproc_create(cam, vo->p.resize, vo->p.blur_ksize, &vo->cam, &vo->pre);
	if (!ret)
		ret = mvod_fe_create(&vo->p, &vo->cam, cap, &vo->fe);
	if (!ret)
		ret = mvod_frames_init(&vo->fr, cap, mvod_fe_desc_bytes(vo->fe));
	if (ret)
		return ret;
	vo->ctx = (struct mvod_vo_ctx){&vo->p, &vo->cam, &vo->fr, &vo->scale, vo->fe, klt, cap};
	ret = mvod_twoview_create(&vo->ctx, &vo->tv);
	if (!ret && vo->p.mode == MVOD_VO_MAP)
		ret = mvod_mapmode_create(&vo->ctx, &vo->map);
	return ret;
}

int mvod_vo_create(const struct mvod_vo_params *params, const struct mvod_camera *cam,
		   struct mvod_vo **out)
{
	struct mvod_vo *vo = calloc(1, sizeof(*vo));
	if (!vo)
		return -ENOMEM;
	vo->p = *params;
	vo->p.frontend = mvod_vo_frontend(params);
	int ret = create_parts(vo, cam);
	if (ret) {
		mvod_vo_destroy(vo);
		return ret;
	}
	mvod_pose_identity(&vo->pose);
	vo->state = MVOD_STATE_INITIALIZING;
	mvod_scale_init(&vo->scale, &vo->p, cam);
	*out = vo;
	return 0;
}

void mvod_vo_destroy(struct mvod_vo *vo)
{
	if (!vo)
		return;
	mvod_mapmode_destroy(vo->map);
	mvod_twoview_destroy(vo->tv);
	mvod_frames_fini(&vo->fr);
	mvod_fe_destroy(vo->fe);
	mvod_cv_preproc_destroy(vo->pre);
	free(vo);
}

void mvod_vo_set_odometer(struct mvod_vo *vo, double metres)
{
	vo->fr.cur->odo = metres;
}

void mvod_vo_restart(struct mvod_vo *vo)
{
	vo->fr.have_ref = false;
	vo->state = MVOD_STATE_INITIALIZING;
	mvod_fe_reset(vo->fe);
	mvod_mapmode_reset(vo->map);
}

static void promote(struct mvod_vo *vo, const double *gt, bool with_structure)
{
	mvod_frames_promote(&vo->fr, &vo->pose, gt, with_structure);
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
static void settle(struct mvod_vo *vo, const double *gt, const struct mvod_step *st,
		   struct mvod_vo_result *res)
{
	enum mvod_frame_status s = res->status;
	vo->pose = st->pose;
	if (s == MVOD_FRAME_MOTION) {
		vo->state = MVOD_STATE_TRACKING;
		promote(vo, gt, true);
		return;
	}
	if (s == MVOD_FRAME_ROTATION) {
		if (res->matches < keep_overlap(vo))
			promote(vo, gt, false);
		return;
	}
	if (vo->state == MVOD_STATE_TRACKING)
		vo->state = MVOD_STATE_LOST;
	if (s != MVOD_FRAME_FEW_FEATURES)
		promote(vo, gt, false);
}

/* What every frame reports last: its pose and state, the map's counts, the scale. */
static void report(struct mvod_vo *vo, struct mvod_vo_result *res)
{
	if (vo->map)
		mvod_mapmode_counts(vo->map, res);
	res->pose = vo->pose;
	res->state = vo->state;
	mvod_scale_report(&vo->scale, res);
}

/*
 * The frame's status before the two-view algorithm: FIRST, FEW_FEATURES, FEW_MATCHES; MOTION
 * when it has enough matches against the reference to estimate from (res->matches).
 */
static int match_status(struct mvod_vo *vo, struct mvod_vo_result *res)
{
	int n = vo->fr.cur->f.n;
	res->features = n;
	if (!vo->fr.have_ref) {
		res->status = n >= vo->p.min_matches ? MVOD_FRAME_FIRST : MVOD_FRAME_FEW_FEATURES;
		return 0;
	}
	if (n < vo->p.min_matches) {
		res->status = MVOD_FRAME_FEW_FEATURES;
		return 0;
	}
	int ret = mvod_fe_match_ref(vo->fe, &vo->fr);
	if (ret)
		return ret;
	res->matches = vo->fr.n_matches;
	res->status = res->matches >= vo->p.min_matches ? MVOD_FRAME_MOTION
							: MVOD_FRAME_FEW_MATCHES;
	return 0;
}

/*
 * The two-view algorithm on the current frame (two-view mode, map mode without a map), then
 * map mode's first map from it. Returns 1 when a map was built, 0, or -errno.
 */
static int twoview(struct mvod_vo *vo, const double *gt, struct mvod_vo_result *res,
		   struct mvod_step *st, double *t_match)
{
	int ret = match_status(vo, res);
	if (ret)
		return ret;
	*t_match = 1e3 * mvod_now_s();
	if (res->status == MVOD_FRAME_MOTION) {
		bool rebuild = vo->map && mvod_mapmode_lost(vo->map);
		res->status = mvod_twoview_estimate(vo->tv, gt, rebuild, res, st);
	}
	return vo->map ? mvod_mapmode_init(vo->map, res, st) : 0;
}

/*
 * The current frame against the map (map mode, when it has one), else against the reference
 * by the two-view algorithm; settled. Fills the result's match and pose stage times.
 */
static int track(struct mvod_vo *vo, const double *gt, struct mvod_vo_result *res)
{
	double t0 = 1e3 * mvod_now_s(), t1 = t0;
	const struct mvod_vo_frame *tracked = vo->fr.cur;
	struct mvod_step st = {.pose = vo->pose};
	int handled = vo->map ? mvod_mapmode_track(vo->map, gt, res, &st) : 0;
	int made_map = handled ? 0 : twoview(vo, gt, res, &st, &t1);
	if (handled < 0 || made_map < 0)
		return handled < 0 ? handled : made_map;
	settle(vo, gt, &st, res);
	if (vo->p.frontend == MVOD_FRONTEND_KLT && vo->fr.ref == tracked)
		mvod_fe_promote(vo->fe);
	/* Map mode: TRACKING means against a map; two-view frames only keep the pose going. */
	if (vo->map && !handled)
		vo->state = made_map		       ? MVOD_STATE_TRACKING
			    : mvod_mapmode_lost(vo->map) ? MVOD_STATE_LOST
							 : MVOD_STATE_INITIALIZING;
	report(vo, res);
	res->ms[MVOD_STAGE_MATCH] = t1 - t0;
	res->ms[MVOD_STAGE_POSE] = 1e3 * mvod_now_s() - t1;
	return 0;
}

/* What both entry points check and clear first. */
static int begin(struct mvod_vo *vo, const double *gt, struct mvod_vo_result *res)
{
	if (vo->scale.mode == MVOD_SCALE_MODE_GT && !gt)
		return -EINVAL;
	memset(res, 0, sizeof(*res));
	mvod_frames_begin(&vo->fr);
	return 0;
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
	float band[8];
	bool in_view = mvod_camera_band_quad(&vo->cam, vo->scale.filter.ground_n, band) == 0;
	ret = mvod_fe_run(vo->fe, &grey, in_view ? band : NULL, &vo->fr);
	if (ret)
		return ret;
	res->ms[MVOD_STAGE_PREPROCESS] = t1 - t0;
	res->ms[MVOD_STAGE_DETECT] = 1e3 * mvod_now_s() - t1;
	return track(vo, gt_position, res);
}

int mvod_vo_process_features(struct mvod_vo *vo, const struct mvod_features *f,
			     const double *gt_position, struct mvod_vo_result *res)
{
	struct mvod_features *cur = &vo->fr.cur->f;
	if (vo->p.frontend == MVOD_FRONTEND_KLT || f->n < 0 || f->n > cur->cap ||
	    f->desc_bytes != cur->desc_bytes)
		return -EINVAL;
	int ret = begin(vo, gt_position, res);
	if (ret)
		return ret;
	memcpy(cur->kp, f->kp, (size_t)f->n * sizeof(*f->kp));
	memcpy(cur->desc, f->desc, (size_t)f->n * (size_t)f->desc_bytes);
	cur->n = f->n;
	return track(vo, gt_position, res);
}

const struct mvod_pose *mvod_vo_seam_pose(const struct mvod_vo *vo)
{
	return &vo->pose;
}

bool mvod_vo_seam_has_map(const struct mvod_vo *vo)
{
	return vo->map != NULL;
}
