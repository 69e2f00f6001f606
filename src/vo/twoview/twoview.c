/*
 * The two-view algorithm: the motion between the reference frame and the current one from
 * their matches (a rotation-only model first, then the essential matrix, its decomposition by
 * cheirality, and the step length), applied to the pose chain. A map mode will sit beside it.
 */
#include "vo/vo_internal.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "vo/frontend/cv_shim.h"
#include "vo/map/mapvo.h"
#include "vo/geom/motion.h"
#include "util/linalg.h"

/*
 * The best essential-matrix decomposition must have at least this many times the points in
 * front of both cameras that the runner-up has: with fewer, the structure is too close to
 * infinity for the direction of translation to be known.
 */
#define CHEIRALITY_MARGIN 2
/*
 * depth_scale: a shared point counts when its parallax is at least DEPTH_MIN_PX pixels on both
 * steps (tracks are localised to 0.05-0.1 px: each depth within 20 %), and a step needs
 * DEPTH_MIN_POINTS such points, as structure_scale's 10 pairs.
 */
#define DEPTH_MIN_PX 0.5f
#define DEPTH_MIN_POINTS 20

static void normalise(const struct mvod_camera *c, const struct mvod_keypoint *k, double *x)
{
	x[0] = (k->x - c->cx) / c->fx;
	x[1] = (k->y - c->cy) / c->fy;
}

/* Match i's flow that the rotation R does not explain, pixels: the parallax translation made. */
static double parallax_px(const struct mvod_vo *vo, const double R[9], int i)
{
	double f = 0.5 * (vo->cam.fx + vo->cam.fy);
	return mvod_motion_rotation_residual(R, vo->x1 + 2 * i, vo->x2 + 2 * i) * f;
}

/* Median parallax over all matches: a median, so that up to half the matches may be wrong. */
static double rotation_free_parallax(struct mvod_vo *vo, const double R[9], int n)
{
	for (int i = 0; i < n; i++)
		vo->scratch[i] = parallax_px(vo, R, i);
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

/*
 * Step length from the depths of the points both steps triangulated with some parallax, when
 * those within MVOD_MOTION_SCALE_DEPTH are too few for structure_scale. Constant speed, the
 * fallback before, gave a step over a held reference one frame's length, which halved every
 * later step on mvod-synth's forward path (0.1 m a frame: 19 near points shared after one
 * held frame, where 20 are needed), and kept a braking camera at full speed (stop-go). Both
 * depths are along the reference's rays, in its frame: the reference's in absolute units,
 * this step's in baselines, so each point's ratio is a step length, whatever frames the step
 * spans, and no step is invented over a standstill. Measured: stop-go's Sim(3) ATE 0.168 m
 * -> 0.008 m; KITTI 07's opening steps within 1.5 % of the truth (constant speed: up to 40 %
 * short), though its ATE ends 0.379 m against 0.370 m (BENCHMARKS.md, "Held reference").
 */
static int depth_scale(struct mvod_vo *vo, const double R[9], int n, double *s)
{
	if (!vo->ref->has_par)
		return -ENODATA;
	int m = 0;
	for (int i = 0; i < n; i++) {
		int a = vo->matches[i].a;
		if (vo->mask[i] && vo->depth[i] > 0 && vo->ref->par[a] >= DEPTH_MIN_PX &&
		    parallax_px(vo, R, i) >= DEPTH_MIN_PX)
			vo->scratch[m++] = vo->ref->pts[3 * a + 2] / vo->depth[i];
	}
	if (m < DEPTH_MIN_POINTS)
		return -ENODATA;
	*s = mvod_median(vo->scratch, m);
	return 0;
}

/* This step's length in metres, NAN when not measured; *q its quality (0-1). */
static double measured_step(struct mvod_vo *vo, int n, double *q)
{
	*q = 1.0;
	if (vo->p.scale_mode == MVOD_SCALE_MODE_EXTERNAL)
		return fabs(vo->cur->odo - vo->ref->odo);
	/* The road band's structure in the reference's frame, unit baseline: h in baselines. */
	float quad[8];
	if (mvod_vo_band_quad(vo, quad) != 0)
		return NAN;
	int m = 0;
	for (int i = 0; i < n; i++) {
		const struct mvod_keypoint *kp = &vo->ref->f.kp[vo->matches[i].a];
		if (!well_triangulated(vo, i) || !mvod_quad_contains(quad, kp->x, kp->y))
			continue;
		double *X = vo->prev_pts + 3 * m++;
		X[0] = vo->x1[2 * i] * vo->depth[i];
		X[1] = vo->x1[2 * i + 1] * vo->depth[i];
		X[2] = vo->depth[i];
	}
	return mvod_scale_height_ratio(&vo->scale, vo->prev_pts, m, vo->p.camera_height_m,
				       vo->scratch, q);
}

/*
 * --scale height, external: the prediction s corrected by this step's measurement. The first
 * measurement also rescales the chain so far about the world's origin (the first camera): its
 * steps were in the unit s is in, and none of its positions was published (vo.c holds them).
 */
static double metric_step(struct mvod_vo *vo, int n, double s, enum mvod_scale_source *src)
{
	double q, m = measured_step(vo, n, &q);
	bool used, was_metric = mvod_scale_filter_metric(&vo->scale);
	double f = mvod_scale_filter_step(&vo->scale, m / s, q, &used);
	if (used)
		*src = vo->p.scale_mode == MVOD_SCALE_MODE_EXTERNAL ? MVOD_SCALE_EXTERNAL
								   : MVOD_SCALE_HEIGHT;
	for (int k = 0; k < 3 && used && !was_metric; k++)
		vo->ref->pose.t[k] *= f;
	return s * f;
}

/*
 * Map mode, --scale height, from a loss until the new map is built: the last speed the map
 * tracked at, exactly (mapping.c multiplies it by the frames a step spans), neither the lost
 * map's structure nor a height measurement. The new map's unit is that step's. On
 * mvod-synth's KITTI 00 drive KLT loses the map 104 times, every time with too few tracks on
 * map points (17-29 where tracking needs 30; the map holds 110-250), most in the sharp turns
 * of frames 3590-3840, where 80-110 of 500 tracks survive a frame; the lost frame's few old
 * points then scaled the steps that built the new maps at 0.9-1.5 times the speed before
 * (1.36 -> 2.07 of the truth at 3814), and no height fit corrected that unit over the
 * straight 4000-4340 (100-frame path ratios 1.19-1.42). Carried exactly: t_rel 4.88 -> 2.69 %,
 * 100-frame windows 3600-4400 within 0.96-1.04 of the truth. A height measurement on top (one
 * two-view pair's road band): 3.64 %; the structure's step kept but clamped to within 10 %
 * of the speed: 4.54 %. --scale external the same, with the odometer's step on top when there
 * is speed (metric_step: the step is the odometer's, as in two-view mode); without speed the
 * lost frame's points rebuilt KITTI 07's ORB map 1.93 times too large (speed stopping at
 * frame 80, map lost at 111): SE(3) ATE 6.45 m, at the last speed 0.54 m (06 KLT: 0.32 ->
 * 0.05 m).
 */
static bool map_rebuild_speed(const struct mvod_vo *vo)
{
	return (vo->p.scale_mode == MVOD_SCALE_MODE_HEIGHT ||
		vo->p.scale_mode == MVOD_SCALE_MODE_EXTERNAL) &&
	       vo->mapvo && vo->mapvo->lost && vo->have_step;
}

/*
 * Free scale's step: from the structure both steps share (near points' distances), else from
 * the depths of all the points they share, else constant speed.
 */
static double step_length(struct mvod_vo *vo, const double R[9], int n, const double *gt,
			  enum mvod_scale_source *src)
{
	if (vo->p.scale_mode == MVOD_SCALE_MODE_GT) {
		*src = MVOD_SCALE_GROUND_TRUTH;
		return mvod_vec3_dist(gt, vo->ref->gt);
	}
	if (map_rebuild_speed(vo)) {
		*src = MVOD_SCALE_CONSTANT_SPEED;
		if (vo->p.scale_mode == MVOD_SCALE_MODE_HEIGHT)
			return vo->last_step;
		return metric_step(vo, n, vo->last_step, src);
	}
	double s;
	if ((structure_scale(vo, n, &s) == 0 && isfinite(s) && s > 0) ||
	    (depth_scale(vo, R, n, &s) == 0 && isfinite(s) && s > 0)) {
		*src = MVOD_SCALE_STRUCTURE;
	} else {
		*src = vo->have_step ? MVOD_SCALE_CONSTANT_SPEED : MVOD_SCALE_UNIT;
		s = vo->have_step ? vo->last_step : 1.0;
	}
	if (vo->p.scale_mode == MVOD_SCALE_MODE_AUTO)
		return s;
	return metric_step(vo, n, s, src);
}

/*
 * Structure of this step in the new reference's frame (X2 = R X1 + t s), every inlier's (the
 * near ones marked in has_pt), and their parallax, for the next step's scale.
 */
static void store_structure(struct mvod_vo *vo, const double R[9], const double t[3], double s,
			    int n)
{
	memset(vo->cur->has_pt, 0, (size_t)vo->cur->f.n);
	memset(vo->cur->par, 0, (size_t)vo->cur->f.n * sizeof(float));
	vo->cur->has_par = 1;
	for (int i = 0; i < n; i++) {
		if (!vo->mask[i] || !(vo->depth[i] > 0))
			continue;
		int b = vo->matches[i].b;
		double X1[3] = {vo->x1[2 * i] * vo->depth[i] * s, vo->x1[2 * i + 1] * vo->depth[i] * s,
				vo->depth[i] * s};
		mvod_mat3_vec(R, X1, vo->cur->pts + 3 * b);
		for (int k = 0; k < 3; k++)
			vo->cur->pts[3 * b + k] += t[k] * s;
		vo->cur->par[b] = (float)parallax_px(vo, R, i);
		vo->cur->has_pt[b] = well_triangulated(vo, i);
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

/*
 * ORB's motion after MAGSAC++: Levenberg-Marquardt on the Sampson distances of its inliers,
 * each in its keypoints' sigma (1.2^octave, both frames'), the inliers chosen again under the
 * refined motion (all matches within ransac_px sigma), and refined once more on those. MAGSAC's
 * own motion is its best minimal sample's, its mask that sample's support. KITTI, ORB's
 * direction error per frame: 07 4.02 -> 3.22 deg, 06 1.75 -> 0.82; with vo.c's road band
 * 2.01 -> 1.19 and 0.88 -> 0.41; without the second selection (one fit on MAGSAC's mask)
 * only 2.01 -> 1.92 and 0.88 -> 0.75 (BENCHMARKS.md, issue 12's "ORB's two-view pose
 * refined"). KLT tracks, at one pyramid level and localised to 0.1 px, are left as MAGSAC
 * gives them: refined, their free and height scales drifted more on 07 (map, --scale auto:
 * 1.16 -> 1.25).
 */
#define REFINE_ITERATIONS 10 /* KITTI: converged within 10 (30 gave the same poses to 1e-3) */
static int refine_motion(struct mvod_vo *vo, int n, double R[9], double t[3])
{
	double *w = vo->scratch, k = vo->p.ransac_px / (0.5 * (vo->cam.fx + vo->cam.fy));
	for (int i = 0; i < n; i++) {
		double sa = mvod_mapvo_sigma(vo->ref->f.kp[vo->matches[i].a].octave);
		double sb = mvod_mapvo_sigma(vo->cur->f.kp[vo->matches[i].b].octave);
		w[i] = 1.0 / sqrt(0.5 * (sa * sa + sb * sb));
	}
	mvod_motion_refine(R, t, vo->x1, vo->x2, w, vo->mask, n, k, REFINE_ITERATIONS);
	mvod_motion_epipolar_inliers(R, t, vo->x1, vo->x2, w, n, k, vo->mask);
	mvod_motion_refine(R, t, vo->x1, vo->x2, w, vo->mask, n, k, REFINE_ITERATIONS);
	return mvod_motion_depths(R, t, vo->x1, vo->x2, vo->mask, n, vo->depth);
}

/* The rotation-only model of this frame's matches: how many inliers it has, and R. */
struct rotation {
	double R[9];
	int inliers;
};

/*
 * The median parallax below which a frame is a rotation, pixels. min_parallax_px is sized for
 * ORB keypoints, localised to about 0.3 px; KLT tracks are to 0.1 px (tests/integration/
 * test_klt.c), so they take half of it: 0.5 px by default is still 5 times their error, and
 * mvod-synth's forward path at 0.1 m a frame (median parallax 0.98-1.01 px) no longer
 * straddles it. A held frame keeps its reference's position: one step off until the next.
 */
static double min_parallax(const struct mvod_vo *vo)
{
	return vo->klt ? 0.5 * vo->p.min_parallax_px : vo->p.min_parallax_px;
}

static void fit_rotation(struct mvod_vo *vo, int n, struct rotation *rot)
{
	double f = 0.5 * (vo->cam.fx + vo->cam.fy);
	double thresh = (min_parallax(vo) + vo->p.ransac_px) / f;
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
 * min_parallax(), the frame is a rotation and translation is left alone. The same fit serves
 * a frame whose translation turns out unknowable (a near tie below).
 */
enum mvod_frame_status mvod_twoview_estimate(struct mvod_vo *vo, const double *gt,
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
	vo->free_parallax_px = rot_ok ? rotation_free_parallax(vo, rot.R, n) : HUGE_VAL;
	if (rot_ok && vo->free_parallax_px < min_parallax(vo))
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
	if (!vo->klt && (res->inliers = refine_motion(vo, n, R, t)) < vo->p.min_inliers)
		return MVOD_FRAME_FEW_INLIERS;
	double s = step_length(vo, R, n, gt, &res->scale_source);
	apply_motion(vo, R, t, s);
	store_structure(vo, R, t, s, n);
	res->step_m = s;
	/*
	 * Per frame: a step over a held reference spans several, and taken whole as the next
	 * one-frame step's length it doubled every step after the next fallback to constant
	 * speed (mvod-synth forward with 5 held frames: Sim(3) ATE 0.319 m, 0.029 m per frame).
	 * A constant-speed step is that speed already, whatever it spans (mapping.c multiplies).
	 */
	if (res->scale_source != MVOD_SCALE_CONSTANT_SPEED)
		vo->last_step = s / (double)(vo->cur->seq - vo->ref->seq);
	vo->have_step = 1;
	return MVOD_FRAME_MOTION;
}
