/*
 * Map mode's tracking: the map built from a two-view step, then per frame a constant-velocity
 * prediction, matching of the map's points by projection, a pose-only refinement, and, when
 * the prediction fails, PnP-RANSAC on descriptor matches against the reference frame.
 */
#include "mapvo.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vo/frontend/klt.h"
#include "vo/geom/posefit.h"
#include "util/linalg.h"

/*
 * A frame becomes a keyframe when it tracks fewer than this share of the points the last
 * keyframe observes: ORB-SLAM's monocular thRefRatio. A camera standing still keeps tracking
 * them all, so it makes no keyframes (and triangulates nothing from a zero baseline).
 */
#define KF_SHARE 0.9
/*
 * KLT's keyframes with a given scale (--scale gt, height; issue 12). Its tracks die slowly,
 * so below KF_SHARE alone it made a keyframe on 95 % of KITTI's frames and bundle adjustment
 * ran on almost every one. There a frame under KF_SHARE becomes one when it also tracks fewer
 * than KLT_KF_SHARE of them (a turn, or a lot lost), or when the camera has moved
 * KLT_KF_BASELINE of the median depth of its tracked points since the last keyframe (SVO's
 * criterion: parallax the new keyframe can triangulate with): KITTI 06 map klt height SE(3)
 * ATE 0.565 -> 0.295 m, scale drift 1.024 -> 1.001 (two-view's 0.408 m, 1.001), 07 0.372 ->
 * 0.214 m, 1.089 -> 1.049; keyframes on 06 / 07 48 / 136 -> 38 / 78. With free scale, where
 * the gauge alone carries the unit, keyframes stay at KF_SHARE: the same rule (0.75 there,
 * two held) kept the clips (07 drift 1.150 -> 1.130) but cost mvod-synth's KITTI 00 t_rel
 * 3.81 -> 10.53 % at 480 tracks, 3.06 -> 4.61 % at 500. Other variants (BENCHMARKS.md,
 * "Sparser KLT keyframes"): share alone at 0.8 / 0.7, 07 free drift 1.209 / 1.163; a
 * minimum gap of 2 frames, 1.253; the baseline at 0.07 / 0.15 with 0.5 below it, 1.307 /
 * 1.318.
 */
#define KLT_KF_SHARE 0.7
#define KLT_KF_BASELINE 0.1
/*
 * Keyframes bundle adjustment holds at the old end of the window (the gauge: mapping_ba.c).
 * Two fix position, orientation and scale; the scale one window hands to the next is then
 * the distance between its two oldest keyframes, as the windows before estimated it. KLT
 * makes a keyframe every frame on KITTI (about 1 m apart), so that unit is one frame's step
 * and its error a random walk over the whole run: on mvod-synth's KITTI 00 drive (free scale)
 * 100-frame windows' path ratio went 0.80 ... 1.12 ... 0.91 ... 1.15. Holding three (four
 * free of seven) hands on a 2-frame baseline that the points seen from all three agree on:
 * t_rel 4.49 / 5.85 / 5.31 % -> 3.12 / 4.67 / 4.13 % with --tracks 500 / 480 / 520, KITTI 06
 * and 07 map klt height drift 1.035 -> 1.008 and 1.119 -> 1.100. ORB's keyframes are sparser
 * (a window spans more motion) and three cost it (07 map orb auto Sim(3) ATE 0.515 -> 1.413 m,
 * 06 map orb gt direction 1.29 -> 1.53 deg): two. Four of seven gave 2.89 / 3.43 / 3.39 %
 * but KITTI 07 map klt free-scale drift 1.148 -> 1.202 and height 1.119 -> 1.191; a window
 * of 10 holding 5, 3.57 / 3.15 / 5.75 %; 12 holding 6, 8.81 % at 500 tracks; 10 holding 2,
 * 6.95 %.
 */
#define KLT_HELD 3
#define HELD 2
/*
 * KLT's pose refinement with the epipolar tracks (epipolar_refine): a track farther than
 * EPI_GATE_PX from its epipolar line at PnP's pose is left out (two-view's --ransac-px on KLT
 * tracks), the residuals are Huber's beyond EPI_HUBER_PX, a Sampson pixel weighs as much as a
 * reprojection pixel, and EPI_ITERATIONS Levenberg-Marquardt steps (PnP's start is close).
 * Measured on KITTI 07, map, --scale gt err_avg: 0.0378 with these; weight 0.5 / 2: 0.0403 /
 * 0.0354; gate 0.5 / 2 px: 0.0380 / 0.0381; Huber 0.5 / 2 px: 0.0360 / 0.0387; 10
 * iterations: 0.0378 (BENCHMARKS.md, issue 12's "Map mode's pose on every track").
 */
#define EPI_GATE_PX 1.0
#define EPI_HUBER_PX 1.0
#define EPI_WEIGHT 1.0
#define EPI_ITERATIONS 5
/*
 * ORB's refinement (track_orb) on the same problem: the map points it matched by projection
 * and its descriptor matches with the last frame (the two-view matcher's, ratio test and
 * cross-check) whose keypoint there tracked no point, each residual in its keypoints' sigma
 * (1.2^octave; a match's both keypoints', as twoview.c's refinement weighs them). ORB's
 * points sit at up to 7 octaves, so KLT's pixel terms let its coarse keypoints pull as hard
 * as its fine ones. The gate and Huber's threshold are in sigmas, a Sampson sigma weighs half
 * a reprojection sigma. Measured on KITTI, map, --scale gt, err_avg / dir_deg_mean, 06 and 07
 * (main: 0.121 / 1.29, 0.109 / 2.52): KLT's pixel terms 0.104 / 1.01, 0.076 / 1.81; in
 * sigmas 0.086 / 0.73, 0.065 / 1.42; gate 3 sigma 0.071 / 0.45, 0.060 / 1.24 but 07's free
 * scale Sim(3) ATE 0.515 -> 1.090 m; gate 2, weight 0.5 (these) 0.079 / 0.55, 0.057 / 1.10,
 * 07 free 0.554 m (BENCHMARKS.md, issue 12's "ORB's map pose on every match").
 */
#define ORB_EPI_GATE_SIGMA 2.0
#define ORB_EPI_HUBER_SIGMA 1.0
#define ORB_EPI_WEIGHT 0.5
/*
 * A tracked rotation farther than this from orthonormal (the Frobenius norm of R^T R - I) is
 * brought back before it is published or predicts the next frame. The constant-velocity
 * prediction multiplies the last two rotations (vR Rcw, vR = Rcw Rprev^T), so a departure
 * grows about threefold a frame unless the refinement re-projects it, as OpenCV's
 * solvePnPRefineLM does through Rodrigues. A refinement that updates R exp(d) without it
 * (mapspeed2's PnP patch) grew it from 4e-15 to 3e-11 over KITTI 07's frames 3-12 and to 0.23
 * by frame 41: the published pose was then no rotation (its inverse no longer its transpose),
 * and after the loss at frame 41, of the 105 two-view steps that passed the new map's gates
 * not one of their 106-291 well-triangulated points reprojected into its first keyframe
 * (mapping.c, init_points): frames without a map 121 of 160 (--scale gt; auto 130), 2 with
 * this. Without that patch the rotations stay within 2e-15 (KITTI 06, 07 clips, both front
 * ends; mvod-synth paths), which this leaves bit for bit.
 */
#define ROT_ORTHO_TOL 1e-9
/* Chi-square gate (2 dof, 95 %) on a reprojection error in sigma units, as the shims use. */
double mvod_mapvo_sigma(int octave)
{
	return pow(1.2, octave);
}

static int alloc_arrays(struct mvod_mapvo *mv)
{
	size_t c = (size_t)mv->cap, np = (size_t)mv->mp.point_cap, nk = (size_t)mv->mp.kf_cap;
	mv->kp = calloc(c, sizeof(*mv->kp));
	mv->cur_pt = calloc(c, sizeof(*mv->cur_pt));
	mv->ref_pt = calloc(c, sizeof(*mv->ref_pt));
	mv->ids = calloc(np, sizeof(*mv->ids));
	mv->pos = calloc(np * 3, sizeof(double));
	mv->desc = calloc(np, MVOD_MAP_DESC_BYTES);
	mv->match = calloc(np, sizeof(int));
	mv->X = calloc(c * 3, sizeof(double));
	mv->uv = calloc(c * 2, sizeof(double));
	mv->sigma = calloc(c, sizeof(double));
	mv->pidx = calloc(c, sizeof(int));
	mv->inlier = calloc(c, 1);
	mv->fa.kp = calloc(c, sizeof(*mv->fa.kp));
	mv->fb.kp = calloc(c, sizeof(*mv->fb.kp));
	mv->fa.desc = calloc(c, MVOD_MAP_DESC_BYTES);
	mv->fb.desc = calloc(c, MVOD_MAP_DESC_BYTES);
	mv->ia = calloc(c, sizeof(int));
	mv->ib = calloc(c, sizeof(int));
	mv->kfs = calloc(nk, sizeof(*mv->kfs));
	mv->cur_first = calloc(c, sizeof(*mv->cur_first));
	mv->ref_first = calloc(c, sizeof(*mv->ref_first));
	mv->fa.cap = mv->fb.cap = mv->cap;
	mv->fa.desc_bytes = mv->fb.desc_bytes = MVOD_MAP_DESC_BYTES;
	bool ok = mv->kp && mv->cur_pt && mv->ref_pt && mv->ids && mv->pos && mv->desc &&
		  mv->match && mv->X && mv->uv && mv->sigma && mv->pidx && mv->inlier &&
		  mv->fa.kp && mv->fb.kp && mv->fa.desc && mv->fb.desc && mv->ia && mv->ib &&
		  mv->kfs && mv->cur_first && mv->ref_first;
	return ok ? 0 : -ENOMEM;
}

/* The shims' own parameters for map mode. */
static int create_parts(const struct mvod_vo *vo, struct mvod_mapvo *mv)
{
	struct mvod_pm_params pp;
	mvod_pm_params_default(&pp);
	int ret = mvod_pm_create(&pp, vo->cam.width, vo->cam.height, vo->cap, &mv->pm);
	if (ret)
		return ret;
	struct mvod_pnp_params np;
	mvod_pnp_params_default(&np);
	np.min_inliers = vo->p.min_inliers;
	ret = mvod_pnp_create(&np, vo->cap, &mv->pnp);
	if (ret)
		return ret;
	/* Without Ceres map mode does not run (vo.c, mvod_vo_run_mode). */
	return mvod_ba_thread_create(mv->mp.kf_cap, mv->mp.point_cap, &mv->bat);
}

int mvod_mapvo_create(const struct mvod_vo *vo, struct mvod_mapvo **out)
{
	*out = NULL;
	if (vo->p.detector != MVOD_DETECTOR_ORB)
		return -EINVAL;
	struct mvod_mapvo *mv = calloc(1, sizeof(*mv));
	if (!mv)
		return -ENOMEM;
	mv->cap = vo->cap;
	mv->ba_sync = vo->p.ba_sync;
	mv->free_scale = vo->p.scale_mode == MVOD_SCALE_MODE_AUTO;
	mv->n_held = vo->klt ? KLT_HELD : HELD;
	mvod_map_params_default(&mv->mp);
	mv->mp.kp_cap = vo->cap;
	mv->K[0] = vo->cam.fx, mv->K[1] = vo->cam.fy, mv->K[2] = vo->cam.cx, mv->K[3] = vo->cam.cy;
	int ret = mvod_map_create(&mv->map, &mv->mp);
	if (!ret)
		ret = create_parts(vo, mv);
	if (!ret)
		ret = alloc_arrays(mv);
	if (ret) {
		mvod_mapvo_destroy(mv);
		return ret;
	}
	*out = mv;
	return 0;
}

void mvod_mapvo_destroy(struct mvod_mapvo *mv)
{
	if (!mv)
		return;
	mvod_map_destroy(mv->map);
	mvod_pm_destroy(mv->pm);
	mvod_pnp_destroy(mv->pnp);
	mvod_ba_thread_destroy(mv->bat);
	void *arrays[] = {mv->kp, mv->cur_pt, mv->ref_pt, mv->ids, mv->pos, mv->desc, mv->match,
			  mv->X, mv->uv, mv->sigma, mv->pidx, mv->inlier, mv->fa.kp, mv->fb.kp,
			  mv->fa.desc, mv->fb.desc, mv->ia, mv->ib, mv->kfs, mv->cur_first,
			  mv->ref_first};
	for (size_t i = 0; i < sizeof(arrays) / sizeof(arrays[0]); i++)
		free(arrays[i]);
	free(mv);
}

void mvod_mapvo_reset(struct mvod_mapvo *mv)
{
	if (!mv)
		return;
	mvod_map_reset(mv->map);
	mv->active = false;
	mv->lost = false;
	mv->unit_log = 0;
	mv->odo_path = mv->map_path = 0;
}

/* The VO's keypoints in the map's form. */
static void to_map_kp(const struct mvod_features *f, struct mvod_map_kp *out)
{
	for (int i = 0; i < f->n; i++)
		out[i] = (struct mvod_map_kp){f->kp[i].x, f->kp[i].y, f->kp[i].response,
					      f->kp[i].octave};
}

/* Every point of the map (all are the window's): ids, positions, descriptors. */
static int gather(struct mvod_mapvo *mv)
{
	int n = mvod_map_points(mv->map, mv->ids, mv->mp.point_cap);
	for (int i = 0; i < n; i++) {
		const struct mvod_map_point *p = mvod_map_point(mv->map, mv->ids[i]);
		memcpy(mv->pos + 3 * i, p->pos, sizeof(p->pos));
		memcpy(mv->desc + (size_t)i * MVOD_MAP_DESC_BYTES, p->desc, MVOD_MAP_DESC_BYTES);
	}
	return n;
}

/* One 2D-3D pair for PnP: world point X, keypoint kp; returns the new count. */
static int add_pair(struct mvod_mapvo *mv, int k, const double X[3], const struct mvod_map_kp *kp,
		    int local)
{
	memcpy(mv->X + 3 * k, X, 3 * sizeof(double));
	mv->uv[2 * k] = kp->x;
	mv->uv[2 * k + 1] = kp->y;
	mv->sigma[k] = mvod_mapvo_sigma(kp->octave);
	mv->pidx[k] = local;
	return k + 1;
}

/*
 * The np gathered points matched by projection from pose R, t, then the pose refined on them
 * (R, t in and out). Returns the inliers, or a negative errno when too few.
 */
static int track_projection(struct mvod_mapvo *mv, int np, double R[9], double t[3])
{
	int m = mvod_pm_match(mv->pm, R, t, mv->K, mv->pos, mv->desc, np, mv->match, NULL);
	if (m < 4)
		return -ENODATA;
	int k = 0;
	for (int i = 0; i < np; i++)
		if (mv->match[i] >= 0)
			k = add_pair(mv, k, mv->pos + 3 * i, &mv->kp[mv->match[i]], i);
	mv->n_pairs = k;
	return mvod_pnp_refine(mv->pnp, mv->X, mv->uv, mv->sigma, k, mv->K, R, t, mv->inlier);
}

/*
 * Re-finding: the current frame's descriptors against the reference frame's, whose keypoints
 * know their map points; PnP-RANSAC on those pairs, then tracking by projection from there.
 */
static int refind(struct mvod_vo *vo, int np, double R[9], double t[3],
		  struct mvod_vo_result *res)
{
	struct mvod_mapvo *mv = vo->mapvo;
	int ret = mvod_match(vo->matcher, &vo->ref->f, &vo->cur->f, vo->matches, vo->cap,
			     &res->matches);
	if (ret)
		return ret;
	int k = 0;
	for (int i = 0; i < res->matches; i++) {
		const struct mvod_map_point *p = mvod_map_point(mv->map, mv->ref_pt[vo->matches[i].a]);
		if (p)
			k = add_pair(mv, k, p->pos, &mv->kp[vo->matches[i].b], -1);
	}
	if (k < vo->p.min_inliers)
		return -ENODATA;
	ret = mvod_pnp_solve(mv->pnp, mv->X, mv->uv, mv->sigma, k, mv->K, R, t, mv->inlier);
	return ret < 0 ? ret : track_projection(mv, np, R, t);
}

/* The frame's tracked points (PnP inliers) and the culling counters of the np gathered. */
static void mark_tracked(struct mvod_mapvo *mv, int n_kp, int np, int k)
{
	for (int j = 0; j < n_kp; j++)
		mv->cur_pt[j] = MVOD_MAP_NONE;
	for (int i = 0; i < np; i++)
		if (mv->match[i] != MVOD_PM_OUT_OF_VIEW)
			mvod_map_count(mv->map, mv->ids[i], 1, 0);
	for (int i = 0; i < k; i++) {
		if (!mv->inlier[i])
			continue;
		int local = mv->pidx[i];
		mv->cur_pt[mv->match[local]] = mv->ids[local];
		mvod_map_count(mv->map, mv->ids[local], 0, 1);
	}
}

/*
 * The published pose from the map's camera-from-world R, t: its inverse (measured on KITTI 07:
 * scale drift 1.38, where composing the map's steps instead, which hides a keyframe's
 * correction by bundle adjustment, drifted 1.88). With --scale gt, the map's step from the
 * last frame (Rcw, tcw) with its length from the ground truth, as the two-view steps are (what
 * the reference implementation's evaluation compares).
 */
static void publish(struct mvod_vo *vo, const double R[9], const double t[3], const double *gt)
{
	struct mvod_mapvo *mv = vo->mapvo;
	struct mvod_pose cur = {0}, prev = {0}, rel;
	memcpy(cur.R, R, sizeof(cur.R));
	memcpy(cur.t, t, sizeof(cur.t));
	mvod_pose_inverse(&cur, &cur);
	if (vo->p.scale_mode != MVOD_SCALE_MODE_GT) {
		vo->pose = cur;
		return;
	}
	memcpy(prev.R, mv->Rcw, sizeof(prev.R));
	memcpy(prev.t, mv->tcw, sizeof(prev.t));
	mvod_pose_compose(&prev, &cur, &rel); /* previous camera from current camera */
	double len = mvod_vec3_norm(rel.t), want = mvod_vec3_dist(gt, vo->ref->gt);
	for (int k = 0; k < 3; k++)
		rel.t[k] = len > 0 ? rel.t[k] * want / len : 0;
	mvod_pose_compose(&vo->pose, &rel, &vo->pose);
}

/* Velocity (the motion from the last frame to this one), then this frame's pose. */
static void set_pose(struct mvod_mapvo *mv, const double R[9], const double t[3])
{
	mvod_motion_between(mv->Rcw, mv->tcw, R, t, mv->vR, mv->vt);
	memcpy(mv->Rcw, R, sizeof(mv->Rcw));
	memcpy(mv->tcw, t, sizeof(mv->tcw));
}

/*
 * The map's points the frame tracks, in its camera (map units), as the two-view algorithm's
 * structure: a step after a loss takes its length from them (the old map's scale), not from
 * the last speed.
 */
static void keep_structure(struct mvod_vo *vo)
{
	struct mvod_mapvo *mv = vo->mapvo;
	struct frame_slot *cur = vo->cur;
	for (int j = 0; j < cur->f.n; j++) {
		const struct mvod_map_point *p = mvod_map_point(mv->map, mv->cur_pt[j]);
		cur->has_pt[j] = p != NULL;
		if (!p)
			continue;
		mvod_rigid_apply(mv->Rcw, mv->tcw, p->pos, cur->pts + 3 * j);
	}
}

/* The tracked frame becomes the reference; the point ids of its keypoints go with it. */
static void promote_tracked(struct mvod_vo *vo, const double *gt)
{
	struct mvod_mapvo *mv = vo->mapvo;
	keep_structure(vo);
	mvod_map_id *k = mv->ref_pt;
	mv->ref_pt = mv->cur_pt;
	mv->cur_pt = k;
	struct mvod_map_obs *first = mv->ref_first;
	mv->ref_first = mv->cur_first;
	mv->cur_first = first;
	mvod_vo_promote(vo, gt, true);
	if (vo->klt)
		mvod_klt_promote(vo->klt);
}

/*
 * Distance of camera R, t from the newest keyframe's centre over the median depth of the
 * frame's k pairs' inlier points (SVO's keyframe criterion); infinite without either. The
 * depths go into vo->scratch (cap doubles; k <= cap).
 */
static double baseline(struct mvod_vo *vo, int k, const double R[9], const double t[3])
{
	struct mvod_mapvo *mv = vo->mapvo;
	int nk = mvod_map_keyframes(mv->map, mv->kfs, mv->mp.kf_cap), n = 0;
	const struct mvod_map_keyframe *kf =
		nk > 0 ? mvod_map_keyframe(mv->map, mv->kfs[nk - 1]) : NULL;
	if (!kf)
		return INFINITY;
	double ck[3], cc[3], Xc[3]; /* the centres' negatives, -R^T t: their distance is the same */
	mvod_mat3_tvec(kf->Rcw, kf->tcw, ck);
	mvod_mat3_tvec(R, t, cc);
	for (int i = 0; i < k; i++) {
		if (!mv->inlier[i])
			continue;
		mvod_rigid_apply(R, t, mv->X + 3 * i, Xc);
		if (Xc[2] > 0)
			vo->scratch[n++] = Xc[2];
	}
	if (n == 0)
		return INFINITY;
	/* Quickselect, not qsort: glibc's qsort mallocs its buffer beyond 1 KiB (128 depths). */
	return mvod_vec3_dist(ck, cc) / mvod_median(vo->scratch, n);
}

/* Whether the frame (k PnP pairs, inliers of them, at R, t) becomes a keyframe. */
static bool kf_due(struct mvod_vo *vo, int k, int inliers, const double R[9], const double t[3])
{
	struct mvod_mapvo *mv = vo->mapvo;
	if (inliers >= KF_SHARE * mv->kf_tracked)
		return false;
	if (!vo->klt || mv->free_scale)
		return true;
	return inliers < KLT_KF_SHARE * mv->kf_tracked || baseline(vo, k, R, t) >= KLT_KF_BASELINE;
}

/* A frame tracked with k PnP pairs (inlier[] set): counters, pose, keyframe, result. */
static int accept(struct mvod_vo *vo, int np, int k, const double R[9], const double t[3],
		  const double *gt, struct mvod_vo_result *res)
{
	struct mvod_mapvo *mv = vo->mapvo;
	int inliers = 0;
	for (int i = 0; i < k; i++)
		inliers += mv->inlier[i];
	mark_tracked(mv, vo->cur->f.n, np, k);
	struct mvod_pose before = vo->pose;
	publish(vo, R, t, gt);
	set_pose(mv, R, t);
	enum mvod_scale_source src = mvod_mapscale_frame(vo);
	mv->since_kf++;
	if (kf_due(vo, k, inliers, R, t)) {
		int ret = mvod_mapping_keyframe(vo, &res->keyframe);
		if (ret)
			return ret;
	}
	res->status = MVOD_FRAME_MOTION;
	if (!res->matches) /* re-finding reports its descriptor matches */
		res->matches = k;
	res->inliers = inliers;
	res->scale_source = src;
	res->step_m = mvod_vec3_dist(before.t, vo->pose.t);
	if (res->step_m > 0) {
		vo->last_step = res->step_m; /* the scale a re-initialisation carries */
		vo->have_step = 1;
	}
	vo->state = MVOD_STATE_TRACKING;
	promote_tracked(vo, gt);
	return 0;
}

/* Constant velocity: this frame's camera-from-world predicted from the last two. */
static void predict(const struct mvod_mapvo *mv, double R[9], double t[3])
{
	mvod_mat3_mul(mv->vR, mv->Rcw, R);
	mvod_rigid_apply(mv->vR, mv->vt, mv->tcw, t);
}

/*
 * --frontend klt: the 2D-3D pairs are the tracks the KLT carried from the reference frame whose
 * keypoint there observes a live point, laid out as mark_tracked reads them (ids[k], match[k] =
 * keypoint, pidx[k] = k); each track's first keyframe comes along. Returns the pairs.
 */
static int klt_pairs(struct mvod_vo *vo)
{
	struct mvod_mapvo *mv = vo->mapvo;
	int k = 0;
	for (int j = 0; j < vo->cur->f.n; j++)
		mv->cur_first[j] = (struct mvod_map_obs){MVOD_MAP_NONE, 0};
	for (int i = 0; i < vo->klt_matches; i++) {
		int a = vo->matches[i].a, b = vo->matches[i].b;
		mv->cur_first[b] = mv->ref_first[a];
		const struct mvod_map_point *p = mvod_map_point(mv->map, mv->ref_pt[a]);
		if (!p)
			continue;
		mv->ids[k] = p->id;
		mv->match[k] = b;
		k = add_pair(mv, k, p->pos, &mv->kp[b], k);
	}
	return k;
}

/*
 * The first n_matches of vo->matches (KLT's tracks, or ORB's descriptor matches with the last
 * frame) whose keypoint in the last frame observes no live map point (most of them: far ones
 * never reach the 3 deg a point needs), normalised into vo->x1 (last frame) and vo->x2 (this
 * one), for their epipolar distances, and with ORB each one's sigma into vo->scratch (its
 * weights). Returns how many.
 */
static int epipolar_tracks(struct mvod_vo *vo, int n_matches)
{
	struct mvod_mapvo *mv = vo->mapvo;
	const struct mvod_camera *c = &vo->cam;
	int m = 0;
	for (int i = 0; i < n_matches; i++) {
		int a = vo->matches[i].a, b = vo->matches[i].b;
		if (mvod_map_point(mv->map, mv->ref_pt[a]))
			continue;
		const struct mvod_keypoint *ka = &vo->ref->f.kp[a], *kb = &vo->cur->f.kp[b];
		vo->x1[2 * m] = (ka->x - c->cx) / c->fx;
		vo->x1[2 * m + 1] = (ka->y - c->cy) / c->fy;
		vo->x2[2 * m] = (kb->x - c->cx) / c->fx;
		vo->x2[2 * m + 1] = (kb->y - c->cy) / c->fy;
		if (!vo->klt) {
			double sa = mvod_mapvo_sigma(ka->octave), sb = mvod_mapvo_sigma(kb->octave);
			vo->scratch[m] = sqrt(0.5 * (sa * sa + sb * sb));
		}
		m++;
	}
	return m;
}

/*
 * The pose (R, t in and out) refined once more on the n map points PnP kept (mv->inlier) and
 * every other track's (of the first n_matches of vo->matches) distance to its epipolar line
 * from the last frame (posefit.h). A few
 * dozen near points alone leave a yaw and a sideways shift that trade against each other
 * (KITTI 07: map mode's yaw error per frame 0.021 deg against two-view's 0.016, biased
 * through whole turns); the far tracks pin the rotation, as they do two-view's: 0.014.
 */
static void epipolar_refine(struct mvod_vo *vo, int n, int n_matches, double R[9], double t[3])
{
	struct mvod_mapvo *mv = vo->mapvo;
	struct mvod_posefit p = {.X = mv->X, .uv = mv->uv, .use = mv->inlier, .n_pts = n,
				 .x1 = vo->x1, .x2 = vo->x2, .epi_use = vo->mask,
				 .n_epi = epipolar_tracks(vo, n_matches), .epi_weight = EPI_WEIGHT,
				 .epi_gate_px = EPI_GATE_PX, .huber_px = EPI_HUBER_PX,
				 .iterations = EPI_ITERATIONS};
	memcpy(p.Rp, mv->Rcw, sizeof(p.Rp));
	memcpy(p.tp, mv->tcw, sizeof(p.tp));
	memcpy(p.K, mv->K, sizeof(p.K));
	if (!vo->klt) { /* in sigmas: ORB_EPI_* */
		p.pt_sigma = mv->sigma;
		p.epi_sigma = vo->scratch;
		p.epi_weight = ORB_EPI_WEIGHT;
		p.epi_gate_px = ORB_EPI_GATE_SIGMA;
		p.huber_px = ORB_EPI_HUBER_SIGMA;
	}
	mvod_posefit_refine(&p, R, t);
}

/*
 * KLT tracking: the pose refined from the prediction (R, t in and out) on the tracked points;
 * PnP-RANSAC on the same pairs only when that fails; then once more with the other tracks'
 * epipolar distances (epipolar_refine). Returns the inliers or -errno; *np the
 * pairs, as mark_tracked counts them.
 */
static int track_klt(struct mvod_vo *vo, double R[9], double t[3], int *np)
{
	struct mvod_mapvo *mv = vo->mapvo;
	int n = klt_pairs(vo);
	*np = mv->n_pairs = n;
	if (n < vo->p.min_matches)
		return -ENODATA;
	int k = mvod_pnp_refine(mv->pnp, mv->X, mv->uv, mv->sigma, n, mv->K, R, t, mv->inlier);
	if (k < vo->p.min_matches)
		k = mvod_pnp_solve(mv->pnp, mv->X, mv->uv, mv->sigma, n, mv->K, R, t, mv->inlier);
	if (k >= vo->p.min_matches)
		epipolar_refine(vo, n, vo->klt_matches, R, t);
	return k;
}

/*
 * ORB: the map's points matched by projection from the prediction, else re-found; then the
 * pose refined once more with the other descriptor matches' epipolar distances from the last
 * frame (epipolar_refine; re-finding has matched them already). Costs the two-view matcher's
 * distance table every frame: 400e6 -> 486e6 instructions a frame (callgrind, KITTI 06).
 */
static int track_orb(struct mvod_vo *vo, double R[9], double t[3], int *np,
		     struct mvod_vo_result *res)
{
	struct mvod_mapvo *mv = vo->mapvo;
	const struct mvod_features *f = &vo->cur->f;
	int ret = mvod_pm_set_frame(mv->pm, mv->kp, f->desc, f->n);
	if (ret)
		return ret;
	*np = gather(mv);
	int k = track_projection(mv, *np, R, t);
	bool refound = false;
	if (k < vo->p.min_matches) {
		k = refind(vo, *np, R, t, res);
		refound = true;
	}
	if (k < vo->p.min_matches)
		return k;
	int nm = res->matches;
	if (!refound) {
		ret = mvod_match(vo->matcher, &vo->ref->f, &vo->cur->f, vo->matches, vo->cap, &nm);
		if (ret)
			return ret;
	}
	epipolar_refine(vo, mv->n_pairs, nm, R, t);
	return k;
}

int mvod_mapvo_track(struct mvod_vo *vo, const double *gt, struct mvod_vo_result *res)
{
	struct mvod_mapvo *mv = vo->mapvo;
	const struct mvod_features *f = &vo->cur->f;
	int ret = mvod_mapping_ba_poll(mv); /* a frame boundary: bundle adjustment lands here */
	if (ret)
		return ret;
	if (!mv->active)
		return 0;
	res->features = f->n;
	if (f->n < vo->p.min_matches) { /* black or textureless: hold the pose and the map */
		res->status = MVOD_FRAME_FEW_FEATURES;
		vo->state = MVOD_STATE_LOST;
		return 1;
	}
	to_map_kp(f, mv->kp);
	double R[9], t[3];
	predict(mv, R, t);
	int np = 0;
	int k = vo->klt ? track_klt(vo, R, t, &np) : track_orb(vo, R, t, &np, res);
	if (k < vo->p.min_matches) {
		/* Lost: the two-view algorithm takes this frame from the reference. */
		res->map_lost = true;
		res->map_lost_inliers = k >= 0 ? k : -1;
		res->map_lost_need = vo->p.min_matches;
		mvod_mapvo_reset(mv);
		mv->lost = true;
		return 0;
	}
	mvod_rot_reorthonormalise(R, ROT_ORTHO_TOL);
	ret = accept(vo, np, mv->n_pairs, R, t, gt, res);
	return ret ? ret : 1;
}
