#include "twoview.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/linalg.h"
#include "vo/core/camera.h"
#include "vo/geom/essential_shim.h"
#include "vo/geom/ground.h"
#include "vo/geom/motion.h"

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

struct mvod_twoview {
	const struct mvod_vo_ctx *c;
	/* Per match of the step: normalised points (reference, current), depth, inlier mask. */
	double *x1, *x2, *depth;
	uint8_t *mask;
	double *prev_pts, *cur_pts, *scratch; /* structures to compare, per-match values */
};

int mvod_twoview_create(const struct mvod_vo_ctx *c, struct mvod_twoview **out)
{
	*out = NULL;
	struct mvod_twoview *tv = calloc(1, sizeof(*tv));
	if (!tv)
		return -ENOMEM;
	size_t n = (size_t)c->cap;
	tv->c = c;
	tv->x1 = calloc(n * 2, sizeof(double));
	tv->x2 = calloc(n * 2, sizeof(double));
	tv->depth = calloc(n, sizeof(double));
	tv->mask = calloc(n, 1);
	tv->prev_pts = calloc(n * 3, sizeof(double));
	tv->cur_pts = calloc(n * 3, sizeof(double));
	tv->scratch = calloc(n, sizeof(double));
	if (!tv->x1 || !tv->x2 || !tv->depth || !tv->mask || !tv->prev_pts || !tv->cur_pts ||
	    !tv->scratch) {
		mvod_twoview_destroy(tv);
		return -ENOMEM;
	}
	*out = tv;
	return 0;
}

void mvod_twoview_destroy(struct mvod_twoview *tv)
{
	if (!tv)
		return;
	free(tv->x1);
	free(tv->x2);
	free(tv->depth);
	free(tv->mask);
	free(tv->prev_pts);
	free(tv->cur_pts);
	free(tv->scratch);
	free(tv);
}

/* Match i's flow that the rotation R does not explain, pixels: the parallax translation made. */
static double parallax_px(const struct mvod_twoview *tv, const double R[9], int i)
{
	double f = 0.5 * (tv->c->cam->fx + tv->c->cam->fy);
	return mvod_motion_rotation_residual(R, tv->x1 + 2 * i, tv->x2 + 2 * i) * f;
}

/* Median parallax over all matches: a median, so that up to half the matches may be wrong. */
static double rotation_free_parallax(struct mvod_twoview *tv, const double R[9], int n)
{
	for (int i = 0; i < n; i++)
		tv->scratch[i] = parallax_px(tv, R, i);
	return n ? mvod_median(tv->scratch, n) : 0.0;
}

/* Correspondence i is an inlier in front of both cameras, near enough to carry scale. */
static bool well_triangulated(const struct mvod_twoview *tv, int i)
{
	return tv->mask[i] && tv->depth[i] > 0 && tv->depth[i] <= MVOD_MOTION_SCALE_DEPTH;
}

/*
 * Step length from the structure both steps share: points the reference saw from its own
 * previous step (absolute units) against the same points from this step (unit baseline).
 */
static int structure_scale(struct mvod_twoview *tv, int n, double *s)
{
	const struct mvod_frames *fr = tv->c->fr;
	int m = 0;
	for (int i = 0; i < n; i++) {
		int a = fr->matches[i].a;
		if (!well_triangulated(tv, i) || !fr->ref->has_pt[a])
			continue;
		memcpy(tv->prev_pts + 3 * m, fr->ref->pts + 3 * a, 3 * sizeof(double));
		double *c = tv->cur_pts + 3 * m;
		c[0] = tv->x1[2 * i] * tv->depth[i];
		c[1] = tv->x1[2 * i + 1] * tv->depth[i];
		c[2] = tv->depth[i];
		m++;
	}
	return mvod_motion_relative_scale(tv->prev_pts, tv->cur_pts, m, 10, tv->scratch, s);
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
static int depth_scale(struct mvod_twoview *tv, const double R[9], int n, double *s)
{
	const struct mvod_vo_frame *ref = tv->c->fr->ref;
	if (!ref->has_par)
		return -ENODATA;
	int m = 0;
	for (int i = 0; i < n; i++) {
		int a = tv->c->fr->matches[i].a;
		if (tv->mask[i] && tv->depth[i] > 0 && ref->par[a] >= DEPTH_MIN_PX &&
		    parallax_px(tv, R, i) >= DEPTH_MIN_PX)
			tv->scratch[m++] = ref->pts[3 * a + 2] / tv->depth[i];
	}
	if (m < DEPTH_MIN_POINTS)
		return -ENODATA;
	*s = mvod_median(tv->scratch, m);
	return 0;
}

/* This step's length in metres, NAN when not measured; *q its quality (0-1). */
static double measured_step(struct mvod_twoview *tv, int n, double *q)
{
	const struct mvod_vo_ctx *c = tv->c;
	*q = 1.0;
	if (c->scale->mode == MVOD_SCALE_MODE_EXTERNAL)
		return fabs(c->fr->cur->odo - c->fr->ref->odo);
	/* The road band's structure in the reference's frame, unit baseline: h in baselines. */
	float quad[8];
	if (mvod_camera_band_quad(c->cam, c->scale->filter.ground_n, quad) != 0)
		return NAN;
	int m = 0;
	for (int i = 0; i < n; i++) {
		const struct mvod_keypoint *kp = &c->fr->ref->f.kp[c->fr->matches[i].a];
		if (!well_triangulated(tv, i) || !mvod_quad_contains(quad, kp->x, kp->y))
			continue;
		double *X = tv->prev_pts + 3 * m++;
		X[0] = tv->x1[2 * i] * tv->depth[i];
		X[1] = tv->x1[2 * i + 1] * tv->depth[i];
		X[2] = tv->depth[i];
	}
	return mvod_ground_height_ratio(&c->scale->filter, tv->prev_pts, m, c->scale->height_m,
					tv->scratch, q);
}

/*
 * --scale height, external: the prediction s corrected by this step's measurement. The first
 * measurement also rescales the chain so far about the world's origin (the first camera): its
 * steps were in the unit s is in, and none of its positions was published (the facade holds
 * them: core/scale.h, mvod_scale_report).
 */
static double metric_step(struct mvod_twoview *tv, int n, double s, enum mvod_scale_source *src)
{
	struct mvod_scale *sc = tv->c->scale;
	double q, m = measured_step(tv, n, &q);
	bool used, was_metric = mvod_scale_filter_metric(&sc->filter);
	double f = mvod_scale_filter_step(&sc->filter, m / s, q, &used);
	if (used)
		*src = sc->mode == MVOD_SCALE_MODE_EXTERNAL ? MVOD_SCALE_EXTERNAL : MVOD_SCALE_HEIGHT;
	if (used && !was_metric)
		mvod_frames_scale_ref(tv->c->fr, f);
	return s * f;
}

/*
 * Free scale's step: from the structure both steps share (near points' distances), else from
 * the depths of all the points they share, else constant speed. A map rebuilt after a loss
 * (rebuild) with --scale height or external takes the lost map's last speed: see twoview.h.
 */
static double step_length(struct mvod_twoview *tv, const double R[9], int n, const double *gt,
			  bool rebuild, enum mvod_scale_source *src)
{
	struct mvod_scale *sc = tv->c->scale;
	if (sc->mode == MVOD_SCALE_MODE_GT) {
		*src = MVOD_SCALE_GROUND_TRUTH;
		return mvod_frames_gt_step(tv->c->fr, gt);
	}
	if (rebuild && mvod_scale_measured(sc) && sc->have_step) {
		*src = MVOD_SCALE_CONSTANT_SPEED;
		if (sc->mode == MVOD_SCALE_MODE_HEIGHT)
			return sc->last_step;
		return metric_step(tv, n, sc->last_step, src);
	}
	double s;
	if ((structure_scale(tv, n, &s) == 0 && isfinite(s) && s > 0) ||
	    (depth_scale(tv, R, n, &s) == 0 && isfinite(s) && s > 0)) {
		*src = MVOD_SCALE_STRUCTURE;
	} else {
		*src = sc->have_step ? MVOD_SCALE_CONSTANT_SPEED : MVOD_SCALE_UNIT;
		s = sc->have_step ? sc->last_step : 1.0;
	}
	if (sc->mode == MVOD_SCALE_MODE_AUTO)
		return s;
	return metric_step(tv, n, s, src);
}

/*
 * Structure of this step in the new reference's frame (X2 = R X1 + t s), every inlier's (the
 * near ones marked in has_pt), and their parallax, for the next step's scale.
 */
static void store_structure(struct mvod_twoview *tv, const double R[9], const double t[3],
			    double s, int n)
{
	struct mvod_vo_frame *cur = tv->c->fr->cur;
	memset(cur->has_pt, 0, (size_t)cur->f.n);
	memset(cur->par, 0, (size_t)cur->f.n * sizeof(float));
	cur->has_par = 1;
	for (int i = 0; i < n; i++) {
		if (!tv->mask[i] || !(tv->depth[i] > 0))
			continue;
		int b = tv->c->fr->matches[i].b;
		double X1[3] = {tv->x1[2 * i] * tv->depth[i] * s, tv->x1[2 * i + 1] * tv->depth[i] * s,
				tv->depth[i] * s};
		mvod_mat3_vec(R, X1, cur->pts + 3 * b);
		for (int k = 0; k < 3; k++)
			cur->pts[3 * b + k] += t[k] * s;
		cur->par[b] = (float)parallax_px(tv, R, i);
		cur->has_pt[b] = well_triangulated(tv, i);
	}
}

/* The pose: the reference's times inverse([R | t s]), for the motion X_cur = R X_ref + t s. */
static void apply_motion(struct mvod_twoview *tv, const double R[9], const double t[3], double s,
			 struct mvod_step *st)
{
	struct mvod_pose rel = {0}, inv;
	memcpy(rel.R, R, sizeof(rel.R));
	for (int k = 0; k < 3; k++)
		rel.t[k] = t[k] * s;
	mvod_pose_inverse(&rel, &inv);
	mvod_pose_compose(&tv->c->fr->ref->pose, &inv, &st->pose);
}

/*
 * ORB's motion after MAGSAC++: Levenberg-Marquardt on the Sampson distances of its inliers,
 * each in its keypoints' sigma (1.2^octave, both frames'), the inliers chosen again under the
 * refined motion (all matches within ransac_px sigma), and refined once more on those. MAGSAC's
 * own motion is its best minimal sample's, its mask that sample's support. KITTI, ORB's
 * direction error per frame: 07 4.02 -> 3.22 deg, 06 1.75 -> 0.82; with the road band
 * (frontend.c) 2.01 -> 1.19 and 0.88 -> 0.41; without the second selection (one fit on
 * MAGSAC's mask) only 2.01 -> 1.92 and 0.88 -> 0.75 (BENCHMARKS.md, issue 12's "ORB's
 * two-view pose refined"). KLT tracks, at one pyramid level and localised to 0.1 px, are left
 * as MAGSAC gives them: refined, their free and height scales drifted more on 07 (map, --scale
 * auto: 1.16 -> 1.25).
 */
#define REFINE_ITERATIONS 10 /* KITTI: converged within 10 (30 gave the same poses to 1e-3) */
static int refine_motion(struct mvod_twoview *tv, int n, double R[9], double t[3])
{
	const struct mvod_vo_ctx *c = tv->c;
	double *w = tv->scratch, k = c->p->ransac_px / (0.5 * (c->cam->fx + c->cam->fy));
	for (int i = 0; i < n; i++) {
		double sa = mvod_orb_sigma(c->fr->ref->f.kp[c->fr->matches[i].a].octave);
		double sb = mvod_orb_sigma(c->fr->cur->f.kp[c->fr->matches[i].b].octave);
		w[i] = 1.0 / sqrt(0.5 * (sa * sa + sb * sb));
	}
	mvod_motion_refine(R, t, tv->x1, tv->x2, w, tv->mask, n, k, REFINE_ITERATIONS);
	mvod_motion_epipolar_inliers(R, t, tv->x1, tv->x2, w, n, k, tv->mask);
	mvod_motion_refine(R, t, tv->x1, tv->x2, w, tv->mask, n, k, REFINE_ITERATIONS);
	return mvod_motion_depths(R, t, tv->x1, tv->x2, tv->mask, n, tv->depth);
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
static double min_parallax(const struct mvod_twoview *tv)
{
	return tv->c->klt ? 0.5 * tv->c->p->min_parallax_px : tv->c->p->min_parallax_px;
}

static void fit_rotation(struct mvod_twoview *tv, int n, struct rotation *rot)
{
	double f = 0.5 * (tv->c->cam->fx + tv->c->cam->fy);
	double thresh = (min_parallax(tv) + tv->c->p->ransac_px) / f;
	rot->inliers = mvod_motion_rotation_ransac(tv->x1, tv->x2, n, thresh, 64, tv->mask, rot->R);
}

static enum mvod_frame_status apply_rotation(struct mvod_twoview *tv, const struct rotation *rot,
					     struct mvod_vo_result *res, struct mvod_step *st)
{
	double t0[3] = {0, 0, 0};
	apply_motion(tv, rot->R, t0, 0.0, st);
	res->inliers = rot->inliers;
	res->scale_source = MVOD_SCALE_NONE;
	return MVOD_FRAME_ROTATION;
}

/*
 * The essential matrix of the n matches, decomposed by cheirality into R, t (depths into
 * tv->depth); res->inliers those in front. MVOD_FRAME_MOTION when it stands, else the status
 * that says why not; *tie when two decompositions have nearly as many points in front.
 */
static enum mvod_frame_status essential(struct mvod_twoview *tv, int n, double R[9],
					double t[3], struct mvod_vo_result *res, bool *tie)
{
	const struct mvod_vo_params *p = tv->c->p;
	/* The estimator runs on normalised points; its pixel threshold is scaled to match. */
	double E[9], R1[9], R2[9], tu[3];
	int inl = 0, runner_up;
	double f = 0.5 * (tv->c->cam->fx + tv->c->cam->fy);
	bool magsac = p->robust == MVOD_ROBUST_MAGSAC;
	*tie = false;
	if (mvod_essential_find(tv->x1, tv->x2, n, magsac, p->ransac_px / f, p->ransac_conf, E,
				   tv->mask, &inl) != 0 ||
	    inl < p->min_inliers || mvod_essential_decompose(E, R1, R2, tu) != 0)
		return MVOD_FRAME_RANSAC_FAILED;
	res->inliers = mvod_motion_cheirality(R1, R2, tu, tv->x1, tv->x2, tv->mask, n, R, t,
					      tv->depth, &runner_up);
	if (res->inliers < p->min_inliers)
		return MVOD_FRAME_FEW_INLIERS;
	*tie = res->inliers < CHEIRALITY_MARGIN * runner_up;
	return MVOD_FRAME_MOTION;
}

/*
 * A camera that only rotates (or stands still) gives a degenerate essential matrix: any t
 * fits. So the rotation-only model is fitted first; if it explains the flow to within
 * min_parallax(), the frame is a rotation and translation is left alone. The same fit serves
 * a frame whose translation turns out unknowable (a near tie of the decompositions).
 */
enum mvod_frame_status mvod_twoview_estimate(struct mvod_twoview *tv, const double *gt,
					     bool rebuild, struct mvod_vo_result *res,
					     struct mvod_step *st)
{
	const struct mvod_vo_ctx *c = tv->c;
	int n = res->matches;
	for (int i = 0; i < n; i++) {
		const struct mvod_keypoint *ka = &c->fr->ref->f.kp[c->fr->matches[i].a];
		const struct mvod_keypoint *kb = &c->fr->cur->f.kp[c->fr->matches[i].b];
		mvod_camera_normalise(c->cam, ka->x, ka->y, tv->x1 + 2 * i);
		mvod_camera_normalise(c->cam, kb->x, kb->y, tv->x2 + 2 * i);
	}
	struct rotation rot;
	fit_rotation(tv, n, &rot);
	bool rot_ok = rot.inliers >= c->p->min_inliers, tie;
	st->free_parallax_px = rot_ok ? rotation_free_parallax(tv, rot.R, n) : HUGE_VAL;
	if (rot_ok && st->free_parallax_px < min_parallax(tv))
		return apply_rotation(tv, &rot, res, st);
	double R[9], t[3];
	enum mvod_frame_status status = essential(tv, n, R, t, res, &tie);
	if (status != MVOD_FRAME_MOTION)
		return status;
	/*
	 * Two decompositions with nearly as many points in front: the structure is too close to
	 * infinity for the direction to be known. Keep the rotation, wait for more parallax.
	 */
	if (tie)
		return rot_ok ? apply_rotation(tv, &rot, res, st) : MVOD_FRAME_FEW_INLIERS;
	if (!c->klt && (res->inliers = refine_motion(tv, n, R, t)) < c->p->min_inliers)
		return MVOD_FRAME_FEW_INLIERS;
	double s = step_length(tv, R, n, gt, rebuild, &res->scale_source);
	apply_motion(tv, R, t, s, st);
	store_structure(tv, R, t, s, n);
	res->step_m = s;
	/*
	 * Per frame: a step over a held reference spans several, and taken whole as the next
	 * one-frame step's length it doubled every step after the next fallback to constant
	 * speed (mvod-synth forward with 5 held frames: Sim(3) ATE 0.319 m, 0.029 m per frame).
	 * A constant-speed step is that speed already, whatever it spans (map/init.c multiplies).
	 */
	if (res->scale_source != MVOD_SCALE_CONSTANT_SPEED)
		mvod_scale_step(c->scale, s, (double)(c->fr->cur->seq - c->fr->ref->seq));
	return MVOD_FRAME_MOTION;
}
