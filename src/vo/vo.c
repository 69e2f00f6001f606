#include "mvod/vo.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cv_shim.h"
#include "match.h"
#include "motion.h"
#include "util/clock.h"
#include "util/linalg.h"
#include "vo_seam.h"

/*
 * A rotation-only frame keeps the reference while it shares at least this many times
 * min_matches with it, so parallax can build up over the next frames; the margin of 2 leaves
 * the next frame, which overlaps the reference a little less again, above min_matches.
 */
#define ROTATION_KEEP_OVERLAP 2
/*
 * The best essential-matrix decomposition must have at least this many times the points in
 * front of both cameras that the runner-up has: with fewer, the structure is too close to
 * infinity for the direction of translation to be known.
 */
#define CHEIRALITY_MARGIN 2

const char *const mvod_stage_names[MVOD_STAGE_COUNT] = {"capture", "preprocess", "detect", "match",
							 "pose"};

const char *mvod_frame_status_name(enum mvod_frame_status s)
{
	static const char *const names[] = {"motion",      "first",        "rotation",
					    "few-features", "few-matches", "ransac-failed",
					    "few-inliers"};
	return (unsigned)s < sizeof(names) / sizeof(names[0]) ? names[s] : "unknown";
}

const char *mvod_track_state_name(enum mvod_track_state s)
{
	static const char *const names[] = {"STARTING", "INITIALIZING", "TRACKING",
					    "LOST",     "SOURCE_DOWN",  "STOPPING"};
	return (unsigned)s < sizeof(names) / sizeof(names[0]) ? names[s] : "UNKNOWN";
}

const char *mvod_scale_source_name(enum mvod_scale_source s)
{
	static const char *const names[] = {"none", "structure", "constant-speed", "ground-truth",
					    "unit"};
	return (unsigned)s < sizeof(names) / sizeof(names[0]) ? names[s] : "unknown";
}

const char *const mvod_detector_names[] = {"orb", "sift", NULL};
const char *const mvod_matcher_names[MVOD_MATCHER_COUNT + 1] = {"bf", "bf-cross", "bf-ratio",
								"flann", "flann-ratio", NULL};
const char *const mvod_robust_names[] = {"magsac", "ransac", NULL};
#define DETECTORS ((int)(sizeof(mvod_detector_names) / sizeof(mvod_detector_names[0])) - 1)

const char *mvod_detector_name(enum mvod_detector d)
{
	return (unsigned)d < DETECTORS ? mvod_detector_names[d] : "unknown";
}

const char *mvod_matcher_kind_name(enum mvod_matcher_kind m)
{
	return (unsigned)m < MVOD_MATCHER_COUNT ? mvod_matcher_names[m] : "unknown";
}

void mvod_vo_params_default(struct mvod_vo_params *p)
{
	*p = (struct mvod_vo_params){
		.resize = 1.0,
		.blur_ksize = 0,
		.detector = MVOD_DETECTOR_ORB,
		.max_features = 2000,
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

/*
 * A frame slot: one frame's features and, for the reference frame, the structure seen from it.
 * Two slots hold the reference frame and the current one; promote() swaps them.
 */
struct frame_slot {
	struct mvod_features f;
	double *pts; /* cap * 3: point in this camera's frame, absolute units */
	uint8_t *has_pt;
	struct mvod_pose pose; /* camera-to-world */
	double gt[3]; /* ground-truth position, with --scale gt */
};

struct mvod_vo {
	struct mvod_vo_params p;
	struct mvod_camera cam; /* after preprocessing: pinhole, no distortion */
	struct mvod_cv_preproc *pre;
	struct mvod_cv_detector *det;
	struct mvod_matcher *matcher;
	int cap;
	struct frame_slot slot[2]; /* storage behind ref and cur */
	struct frame_slot *ref, *cur;
	int have_ref;
	struct mvod_match *matches;
	double *x1, *x2, *depth, *prev_pts, *cur_pts, *scratch;
	uint8_t *mask;
	struct mvod_pose pose; /* last published pose */
	enum mvod_track_state state;
	double last_step;   /* length of the last translation step, for constant speed */
	int have_step;
};

static int slot_init(struct frame_slot *k, int cap, int desc_bytes)
{
	k->f.cap = cap;
	k->f.desc_bytes = desc_bytes;
	k->f.kp = calloc((size_t)cap, sizeof(*k->f.kp));
	k->f.desc = calloc((size_t)cap, (size_t)desc_bytes);
	k->pts = calloc((size_t)cap * 3, sizeof(double));
	k->has_pt = calloc((size_t)cap, 1);
	return k->f.kp && k->f.desc && k->pts && k->has_pt ? 0 : -ENOMEM;
}

static void slot_fini(struct frame_slot *k)
{
	free(k->f.kp);
	free(k->f.desc);
	free(k->pts);
	free(k->has_pt);
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

int mvod_vo_create(const struct mvod_vo_params *params, const struct mvod_camera *cam,
		   struct mvod_vo **out)
{
	struct mvod_vo *vo = calloc(1, sizeof(*vo));
	if (!vo)
		return -ENOMEM;
	vo->p = *params;
	/* ORB and SIFT may return a few more than asked for (ties); the cap leaves room. */
	vo->cap = params->max_features + params->max_features / 4 + 16;
	int ret = mvod_cv_preproc_create(cam, params->resize, params->blur_ksize, &vo->cam, &vo->pre);
	if (ret)
		goto fail;
	ret = mvod_cv_detector_create(params->detector, params->max_features, vo->cam.width,
				      vo->cam.height, &vo->det);
	if (ret)
		goto fail;
	struct mvod_match_params mp = {params->matcher, params->detector, params->ratio,
				       params->best_n};
	ret = mvod_matcher_create(&mp, vo->cap, &vo->matcher);
	if (ret)
		goto fail;
	ret = alloc_buffers(vo);
	if (ret)
		goto fail;
	vo->ref = &vo->slot[0];
	vo->cur = &vo->slot[1];
	mvod_pose_identity(&vo->pose);
	vo->state = MVOD_STATE_INITIALIZING;
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

/*
 * The current frame becomes the reference. Its structure (from a motion step) is what the next
 * step scales against; without one, the next step falls back to constant speed.
 */
static void promote(struct mvod_vo *vo, const double *gt, bool with_structure)
{
	if (!with_structure)
		memset(vo->cur->has_pt, 0, (size_t)vo->cur->f.n);
	struct frame_slot *k = vo->ref;
	vo->ref = vo->cur;
	vo->cur = k;
	vo->ref->pose = vo->pose;
	if (gt)
		memcpy(vo->ref->gt, gt, sizeof(vo->ref->gt));
	vo->have_ref = 1;
}

static void normalise(const struct mvod_camera *c, const struct mvod_keypoint *k, double *x)
{
	x[0] = (k->x - c->cx) / c->fx;
	x[1] = (k->y - c->cy) / c->fy;
}

/*
 * Median over all matches of the flow rotation alone does not explain, in pixels: the parallax
 * that translation made. A median, so that up to half the matches may be wrong.
 */
static double rotation_free_parallax(struct mvod_vo *vo, const double R[9], int n)
{
	double f = 0.5 * (vo->cam.fx + vo->cam.fy);
	for (int i = 0; i < n; i++)
		vo->scratch[i] = mvod_motion_rotation_residual(R, vo->x1 + 2 * i, vo->x2 + 2 * i) * f;
	return n ? mvod_median(vo->scratch, n) : 0.0;
}

/* Correspondence i is an inlier in front of both cameras, near enough to carry scale. */
static bool well_triangulated(const struct mvod_vo *vo, int i)
{
	return vo->mask[i] && vo->depth[i] > 0 && vo->depth[i] <= MVOD_MOTION_SCALE_DEPTH;
}

/*
 * Step length from the structure both steps share: points the reference saw from its own
 * previous step (absolute units) against the same points from this step (unit baseline).
 */
static int structure_scale(struct mvod_vo *vo, int n, double *s)
{
	int m = 0;
	for (int i = 0; i < n; i++) {
		int a = vo->matches[i].a;
		if (!well_triangulated(vo, i) || !vo->ref->has_pt[a])
			continue;
		memcpy(vo->prev_pts + 3 * m, vo->ref->pts + 3 * a, 3 * sizeof(double));
		double *c = vo->cur_pts + 3 * m;
		c[0] = vo->x1[2 * i] * vo->depth[i];
		c[1] = vo->x1[2 * i + 1] * vo->depth[i];
		c[2] = vo->depth[i];
		m++;
	}
	return mvod_motion_relative_scale(vo->prev_pts, vo->cur_pts, m, 10, vo->scratch, s);
}

static double step_length(struct mvod_vo *vo, int n, const double *gt,
			  enum mvod_scale_source *src)
{
	if (vo->p.scale_mode == MVOD_SCALE_MODE_GT) {
		*src = MVOD_SCALE_GROUND_TRUTH;
		return mvod_vec3_dist(gt, vo->ref->gt);
	}
	double s;
	if (structure_scale(vo, n, &s) == 0 && isfinite(s) && s > 0) {
		*src = MVOD_SCALE_STRUCTURE;
		return s;
	}
	*src = vo->have_step ? MVOD_SCALE_CONSTANT_SPEED : MVOD_SCALE_UNIT;
	return vo->have_step ? vo->last_step : 1.0;
}

/* Structure of this step in the new reference's frame (X2 = R X1 + t s), for the next scale. */
static void store_structure(struct mvod_vo *vo, const double R[9], const double t[3], double s,
			    int n)
{
	memset(vo->cur->has_pt, 0, (size_t)vo->cur->f.n);
	for (int i = 0; i < n; i++) {
		if (!well_triangulated(vo, i))
			continue;
		double X1[3] = {vo->x1[2 * i] * vo->depth[i] * s, vo->x1[2 * i + 1] * vo->depth[i] * s,
				vo->depth[i] * s};
		double *X2 = vo->cur->pts + 3 * vo->matches[i].b;
		mvod_mat3_vec(R, X1, X2);
		for (int k = 0; k < 3; k++)
			X2[k] += t[k] * s;
		vo->cur->has_pt[vo->matches[i].b] = 1;
	}
}

/* pose = ref_pose * inverse([R | t s]) for the motion X_cur = R X_ref + t s. */
static void apply_motion(struct mvod_vo *vo, const double R[9], const double t[3], double s)
{
	struct mvod_pose rel = {0}, inv;
	memcpy(rel.R, R, sizeof(rel.R));
	for (int k = 0; k < 3; k++)
		rel.t[k] = t[k] * s;
	mvod_pose_inverse(&rel, &inv);
	mvod_pose_compose(&vo->ref->pose, &inv, &vo->pose);
}

/* The rotation-only model of this frame's matches: how many inliers it has, and R. */
struct rotation {
	double R[9];
	int inliers;
};

static void fit_rotation(struct mvod_vo *vo, int n, struct rotation *rot)
{
	double f = 0.5 * (vo->cam.fx + vo->cam.fy);
	double thresh = (vo->p.min_parallax_px + vo->p.ransac_px) / f;
	rot->inliers = mvod_motion_rotation_ransac(vo->x1, vo->x2, n, thresh, 64, vo->mask, rot->R);
}

static enum mvod_frame_status apply_rotation(struct mvod_vo *vo, const struct rotation *rot,
					     struct mvod_vo_result *res)
{
	double t0[3] = {0, 0, 0};
	apply_motion(vo, rot->R, t0, 0.0);
	res->inliers = rot->inliers;
	res->scale_source = MVOD_SCALE_NONE;
	return MVOD_FRAME_ROTATION;
}

/*
 * A camera that only rotates (or stands still) gives a degenerate essential matrix: any t
 * fits. So the rotation-only model is fitted first; if it explains the flow to within
 * min_parallax_px, the frame is a rotation and translation is left alone. The same fit serves
 * a frame whose translation turns out unknowable (a near tie below).
 */
static enum mvod_frame_status estimate(struct mvod_vo *vo, const double *gt,
				       struct mvod_vo_result *res)
{
	int n = res->matches;
	for (int i = 0; i < n; i++) {
		normalise(&vo->cam, &vo->ref->f.kp[vo->matches[i].a], vo->x1 + 2 * i);
		normalise(&vo->cam, &vo->cur->f.kp[vo->matches[i].b], vo->x2 + 2 * i);
	}
	struct rotation rot;
	fit_rotation(vo, n, &rot);
	bool rot_ok = rot.inliers >= vo->p.min_inliers;
	if (rot_ok && rotation_free_parallax(vo, rot.R, n) < vo->p.min_parallax_px)
		return apply_rotation(vo, &rot, res);
	/* The estimator runs on normalised points; its pixel threshold is scaled to match. */
	double E[9], R1[9], R2[9], tu[3], R[9], t[3];
	int inl = 0;
	double f = 0.5 * (vo->cam.fx + vo->cam.fy);
	bool magsac = vo->p.robust == MVOD_ROBUST_MAGSAC;
	if (mvod_cv_find_essential(vo->x1, vo->x2, n, magsac, vo->p.ransac_px / f, vo->p.ransac_conf,
				   E, vo->mask, &inl) != 0 ||
	    inl < vo->p.min_inliers || mvod_cv_decompose_essential(E, R1, R2, tu) != 0)
		return MVOD_FRAME_RANSAC_FAILED;
	int runner_up;
	res->inliers = mvod_motion_cheirality(R1, R2, tu, vo->x1, vo->x2, vo->mask, n, R, t, vo->depth,
					      &runner_up);
	if (res->inliers < vo->p.min_inliers)
		return MVOD_FRAME_FEW_INLIERS;
	/*
	 * Two decompositions with nearly as many points in front: the structure is too close to
	 * infinity for the direction to be known. Keep the rotation, wait for more parallax.
	 */
	if (res->inliers < CHEIRALITY_MARGIN * runner_up)
		return rot_ok ? apply_rotation(vo, &rot, res) : MVOD_FRAME_FEW_INLIERS;
	double s = step_length(vo, n, gt, &res->scale_source);
	apply_motion(vo, R, t, s);
	store_structure(vo, R, t, s, n);
	res->step_m = s;
	vo->last_step = s;
	vo->have_step = 1;
	return MVOD_FRAME_MOTION;
}

/*
 * After a frame: the tracking state, and whether the frame becomes the reference.
 *
 *   frame status           state                        becomes the reference
 *   MOTION                 TRACKING                     yes, with its structure (next scale)
 *   ROTATION               unchanged                    when it shares fewer than
 *                                                       ROTATION_KEEP_OVERLAP * min_matches
 *                                                       matches with the reference
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
		promote(vo, gt, true);
		return;
	}
	if (st == MVOD_FRAME_ROTATION) {
		if (res->matches < ROTATION_KEEP_OVERLAP * vo->p.min_matches)
			promote(vo, gt, false);
		return;
	}
	if (vo->state == MVOD_STATE_TRACKING)
		vo->state = MVOD_STATE_LOST;
	if (st != MVOD_FRAME_FEW_FEATURES)
		promote(vo, gt, false);
}

void mvod_vo_restart(struct mvod_vo *vo)
{
	vo->have_ref = 0;
	vo->state = MVOD_STATE_INITIALIZING;
}

/*
 * The current slot's features against the reference: match, estimate, settle. Fills the
 * result's match and pose stage times, pose and state.
 */
static int track(struct mvod_vo *vo, const double *gt, struct mvod_vo_result *res)
{
	double t0 = 1e3 * mvod_now_s();
	int n = vo->cur->f.n;
	bool matched = false; /* enough matches against the reference to estimate motion */
	res->features = n;
	if (!vo->have_ref) {
		res->status = n >= vo->p.min_matches ? MVOD_FRAME_FIRST : MVOD_FRAME_FEW_FEATURES;
	} else if (n < vo->p.min_matches) {
		res->status = MVOD_FRAME_FEW_FEATURES;
	} else {
		int ret = mvod_match(vo->matcher, &vo->ref->f, &vo->cur->f, vo->matches, vo->cap,
				     &res->matches);
		if (ret)
			return ret;
		matched = res->matches >= vo->p.min_matches;
		res->status = MVOD_FRAME_FEW_MATCHES;
	}
	double t1 = 1e3 * mvod_now_s();
	if (matched)
		res->status = estimate(vo, gt, res);
	settle(vo, gt, res);
	res->pose = vo->pose;
	res->state = vo->state;
	res->ms[MVOD_STAGE_MATCH] = t1 - t0;
	res->ms[MVOD_STAGE_POSE] = 1e3 * mvod_now_s() - t1;
	return 0;
}

/* What both entry points check and clear first. */
static int begin(const struct mvod_vo *vo, const double *gt, struct mvod_vo_result *res)
{
	if (vo->p.scale_mode == MVOD_SCALE_MODE_GT && !gt)
		return -EINVAL;
	memset(res, 0, sizeof(*res));
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
	ret = mvod_cv_detect(vo->det, &grey, &vo->cur->f);
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
	if (f->n < 0 || f->n > cur->cap || f->desc_bytes != cur->desc_bytes)
		return -EINVAL;
	int ret = begin(vo, gt_position, res);
	if (ret)
		return ret;
	memcpy(cur->kp, f->kp, (size_t)f->n * sizeof(*f->kp));
	memcpy(cur->desc, f->desc, (size_t)f->n * (size_t)f->desc_bytes);
	cur->n = f->n;
	return track(vo, gt_position, res);
}
