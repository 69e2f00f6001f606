/*
 * Map mode's tracking: per frame a constant-velocity prediction, matching of the map's points
 * (KLT: the point ids the tracks carry; ORB: by projection), a pose-only refinement, and, when
 * the prediction fails, PnP-RANSAC (ORB: on descriptor matches against the reference frame);
 * then the pose refined once more on every other track, and the keyframe decision.
 */
#include <errno.h>
#include <math.h>
#include <string.h>

#include "internal.h"
#include "mapmode.h"
#include "util/linalg.h"
#include "vo/core/camera.h"
#include "vo/frontend/fe.h"
#include "vo/geom/posefit.h"

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
 * (1.2^octave; a match's both keypoints', as two-view's refinement weighs them). ORB's
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
 * (init.c, init_points): frames without a map 121 of 160 (--scale gt; auto 130), 2 with
 * this. Without that patch the rotations stay within 2e-15 (KITTI 06, 07 clips, both front
 * ends; mvod-synth paths), which this leaves bit for bit.
 */
#define ROT_ORTHO_TOL 1e-9

/* The frame's keypoints in the map's form. */
static void to_map_kp(const struct mvod_features *f, struct mvod_map_kp *out)
{
	for (int i = 0; i < f->n; i++)
		out[i] = (struct mvod_map_kp){f->kp[i].x, f->kp[i].y, f->kp[i].response,
					      f->kp[i].octave};
}

/* Every point of the map (all are the window's): ids, positions, descriptors. */
static int gather(struct mvod_mapmode *m)
{
	int n = mvod_map_points(m->map, m->ids, m->mp.point_cap);
	for (int i = 0; i < n; i++) {
		const struct mvod_map_point *p = mvod_map_point(m->map, m->ids[i]);
		memcpy(m->pos + 3 * i, p->pos, sizeof(p->pos));
		memcpy(m->desc + (size_t)i * MVOD_MAP_DESC_BYTES, p->desc, MVOD_MAP_DESC_BYTES);
	}
	return n;
}

/* One 2D-3D pair for PnP: world point X, keypoint kp; returns the new count. */
static int add_pair(struct mvod_mapmode *m, int k, const double X[3],
		    const struct mvod_map_kp *kp, int local)
{
	memcpy(m->X + 3 * k, X, 3 * sizeof(double));
	m->uv[2 * k] = kp->x;
	m->uv[2 * k + 1] = kp->y;
	m->sigma[k] = mvod_orb_sigma(kp->octave);
	m->pidx[k] = local;
	return k + 1;
}

/*
 * The np gathered points matched by projection from pose R, t, then the pose refined on them
 * (R, t in and out). Returns the inliers, or a negative errno when too few.
 */
static int track_projection(struct mvod_mapmode *m, int np, double R[9], double t[3])
{
	int n = mvod_pm_match(m->pm, R, t, m->K, m->pos, m->desc, np, m->match, NULL);
	if (n < 4)
		return -ENODATA;
	int k = 0;
	for (int i = 0; i < np; i++)
		if (m->match[i] >= 0)
			k = add_pair(m, k, m->pos + 3 * i, &m->kp[m->match[i]], i);
	m->n_pairs = k;
	return mvod_pnp_refine(m->pnp, m->X, m->uv, m->sigma, k, m->K, R, t, m->inlier);
}

/*
 * Re-finding: the current frame's descriptors against the reference frame's, whose keypoints
 * know their map points; PnP-RANSAC on those pairs, then tracking by projection from there.
 */
static int refind(struct mvod_mapmode *m, int np, double R[9], double t[3],
		  struct mvod_vo_result *res)
{
	struct mvod_frames *fr = m->c->fr;
	int ret = mvod_fe_match_ref(m->c->fe, fr);
	if (ret)
		return ret;
	res->matches = fr->n_matches;
	int k = 0;
	for (int i = 0; i < res->matches; i++) {
		const struct mvod_map_point *p =
			mvod_map_point(m->map, fr->ref->pt[fr->matches[i].a]);
		if (p)
			k = add_pair(m, k, p->pos, &m->kp[fr->matches[i].b], -1);
	}
	if (k < m->c->p->min_inliers)
		return -ENODATA;
	ret = mvod_pnp_solve(m->pnp, m->X, m->uv, m->sigma, k, m->K, R, t, m->inlier);
	return ret < 0 ? ret : track_projection(m, np, R, t);
}

/* The frame's tracked points (PnP inliers) and the culling counters of the np gathered. */
static void mark_tracked(struct mvod_mapmode *m, int np, int k)
{
	struct mvod_vo_frame *cur = m->c->fr->cur;
	for (int j = 0; j < cur->f.n; j++)
		cur->pt[j] = MVOD_MAP_NONE;
	for (int i = 0; i < np; i++)
		if (m->match[i] != MVOD_PM_OUT_OF_VIEW)
			mvod_map_count(m->map, m->ids[i], 1, 0);
	for (int i = 0; i < k; i++) {
		if (!m->inlier[i])
			continue;
		int local = m->pidx[i];
		cur->pt[m->match[local]] = m->ids[local];
		mvod_map_count(m->map, m->ids[local], 0, 1);
	}
}

/*
 * The published pose from the map's camera-from-world R, t: its inverse (measured on KITTI 07:
 * scale drift 1.38, where composing the map's steps instead, which hides a keyframe's
 * correction by bundle adjustment, drifted 1.88). With --scale gt, the map's step from the
 * last frame (m->cam, not yet moved) with its length from the ground truth, as the two-view
 * steps are (what the reference implementation's evaluation compares).
 */
static void publish(struct mvod_mapmode *m, const double R[9], const double t[3],
		    const double *gt, struct mvod_step *st)
{
	struct mvod_pose cur = {0}, prev = {0}, rel;
	memcpy(cur.R, R, sizeof(cur.R));
	memcpy(cur.t, t, sizeof(cur.t));
	mvod_pose_inverse(&cur, &cur);
	if (m->c->scale->mode != MVOD_SCALE_MODE_GT) {
		st->pose = cur;
		return;
	}
	memcpy(prev.R, m->cam.Rcw, sizeof(prev.R));
	memcpy(prev.t, m->cam.tcw, sizeof(prev.t));
	mvod_pose_compose(&prev, &cur, &rel); /* previous camera from current camera */
	double len = mvod_vec3_norm(rel.t), want = mvod_frames_gt_step(m->c->fr, gt);
	for (int k = 0; k < 3; k++)
		rel.t[k] = len > 0 ? rel.t[k] * want / len : 0;
	mvod_pose_compose(&st->pose, &rel, &st->pose);
}

/*
 * The map's points the frame tracks, in its camera (map units), as the two-view algorithm's
 * structure: a step after a loss takes its length from them (the old map's scale), not from
 * the last speed.
 */
static void keep_structure(struct mvod_mapmode *m)
{
	struct mvod_vo_frame *cur = m->c->fr->cur;
	for (int j = 0; j < cur->f.n; j++) {
		const struct mvod_map_point *p = mvod_map_point(m->map, cur->pt[j]);
		cur->has_pt[j] = p != NULL;
		if (!p)
			continue;
		mvod_rigid_apply(m->cam.Rcw, m->cam.tcw, p->pos, cur->pts + 3 * j);
	}
}

/*
 * Distance of camera R, t from the newest keyframe's centre over the median depth of the
 * frame's k pairs' inlier points (SVO's keyframe criterion); infinite without either. The
 * depths go into m->scratch (cap doubles; k <= cap).
 */
static double baseline(struct mvod_mapmode *m, int k, const double R[9], const double t[3])
{
	int nk = mvod_map_keyframes(m->map, m->kfs, m->mp.kf_cap), n = 0;
	const struct mvod_map_keyframe *kf =
		nk > 0 ? mvod_map_keyframe(m->map, m->kfs[nk - 1]) : NULL;
	if (!kf)
		return INFINITY;
	double ck[3], cc[3], Xc[3]; /* the centres' negatives, -R^T t: their distance is the same */
	mvod_mat3_tvec(kf->Rcw, kf->tcw, ck);
	mvod_mat3_tvec(R, t, cc);
	for (int i = 0; i < k; i++) {
		if (!m->inlier[i])
			continue;
		mvod_rigid_apply(R, t, m->X + 3 * i, Xc);
		if (Xc[2] > 0)
			m->scratch[n++] = Xc[2];
	}
	if (n == 0)
		return INFINITY;
	/* Quickselect, not qsort: glibc's qsort mallocs its buffer beyond 1 KiB (128 depths). */
	return mvod_vec3_dist(ck, cc) / mvod_median(m->scratch, n);
}

/* Whether the frame (k PnP pairs, inliers of them, at R, t) becomes a keyframe. */
static bool kf_due(struct mvod_mapmode *m, int k, int inliers, const double R[9],
		   const double t[3])
{
	if (inliers >= KF_SHARE * m->kf_tracked)
		return false;
	if (!m->c->klt || m->free_scale)
		return true;
	return inliers < KLT_KF_SHARE * m->kf_tracked || baseline(m, k, R, t) >= KLT_KF_BASELINE;
}

/*
 * A frame tracked with k PnP pairs (inlier[] set) of np gathered points: counters, pose,
 * keyframe, result, and the map's points it sees as its structure.
 */
static int accept(struct mvod_mapmode *m, int np, int k, const double R[9], const double t[3],
		  const double *gt, struct mvod_vo_result *res, struct mvod_step *st)
{
	int inliers = 0;
	for (int i = 0; i < k; i++)
		inliers += m->inlier[i];
	mark_tracked(m, np, k);
	struct mvod_pose before = st->pose;
	publish(m, R, t, gt, st);
	mvod_tracked_set(&m->cam, R, t);
	enum mvod_scale_source src = mvod_mapscale_frame(m);
	m->since_kf++;
	if (kf_due(m, k, inliers, R, t)) {
		int ret = mvod_mapping_keyframe(m, st, &res->keyframe);
		if (ret)
			return ret;
	}
	res->status = MVOD_FRAME_MOTION;
	if (!res->matches) /* re-finding reports its descriptor matches */
		res->matches = k;
	res->inliers = inliers;
	res->scale_source = src;
	res->step_m = mvod_vec3_dist(before.t, st->pose.t);
	if (res->step_m > 0) /* the scale a re-initialisation carries */
		mvod_scale_step(m->c->scale, res->step_m, 1.0);
	keep_structure(m);
	return 0;
}

/*
 * --frontend klt: the 2D-3D pairs are the tracks the KLT carried from the reference frame whose
 * keypoint there observes a live point, laid out as mark_tracked reads them (ids[k], match[k] =
 * keypoint, pidx[k] = k); each track's first keyframe comes along. Returns the pairs.
 */
static int klt_pairs(struct mvod_mapmode *m)
{
	struct mvod_frames *fr = m->c->fr;
	int k = 0;
	for (int j = 0; j < fr->cur->f.n; j++)
		fr->cur->first[j] = (struct mvod_map_obs){MVOD_MAP_NONE, 0};
	for (int i = 0; i < fr->n_matches; i++) {
		int a = fr->matches[i].a, b = fr->matches[i].b;
		fr->cur->first[b] = fr->ref->first[a];
		const struct mvod_map_point *p = mvod_map_point(m->map, fr->ref->pt[a]);
		if (!p)
			continue;
		m->ids[k] = p->id;
		m->match[k] = b;
		k = add_pair(m, k, p->pos, &m->kp[b], k);
	}
	return k;
}

/*
 * The first n_matches of the frames' matches (KLT's tracks, or ORB's descriptor matches with
 * the last frame) whose keypoint in the last frame observes no live map point (most of them:
 * far ones never reach the 3 deg a point needs), normalised into m->x1 (last frame) and m->x2
 * (this one), for their epipolar distances, and with ORB each one's sigma into m->scratch
 * (its weights). Returns how many.
 */
static int epipolar_tracks(struct mvod_mapmode *m, int n_matches)
{
	const struct mvod_frames *fr = m->c->fr;
	int n = 0;
	for (int i = 0; i < n_matches; i++) {
		int a = fr->matches[i].a, b = fr->matches[i].b;
		if (mvod_map_point(m->map, fr->ref->pt[a]))
			continue;
		const struct mvod_keypoint *ka = &fr->ref->f.kp[a], *kb = &fr->cur->f.kp[b];
		mvod_camera_normalise(m->c->cam, ka->x, ka->y, m->x1 + 2 * n);
		mvod_camera_normalise(m->c->cam, kb->x, kb->y, m->x2 + 2 * n);
		if (!m->c->klt) {
			double sa = mvod_orb_sigma(ka->octave), sb = mvod_orb_sigma(kb->octave);
			m->scratch[n] = sqrt(0.5 * (sa * sa + sb * sb));
		}
		n++;
	}
	return n;
}

/*
 * The pose (R, t in and out) refined once more on the n map points PnP kept (m->inlier) and
 * every other track's (of the first n_matches of the frames' matches) distance to its
 * epipolar line from the last frame (posefit.h). A few dozen near points alone leave a yaw and
 * a sideways shift that trade against each other (KITTI 07: map mode's yaw error per frame
 * 0.021 deg against two-view's 0.016, biased through whole turns); the far tracks pin the
 * rotation, as they do two-view's: 0.014.
 */
static void epipolar_refine(struct mvod_mapmode *m, int n, int n_matches, double R[9],
			    double t[3])
{
	struct mvod_posefit p = {.X = m->X, .uv = m->uv, .use = m->inlier, .n_pts = n,
				 .x1 = m->x1, .x2 = m->x2, .epi_use = m->epi_use,
				 .n_epi = epipolar_tracks(m, n_matches), .epi_weight = EPI_WEIGHT,
				 .epi_gate_px = EPI_GATE_PX, .huber_px = EPI_HUBER_PX,
				 .iterations = EPI_ITERATIONS};
	memcpy(p.Rp, m->cam.Rcw, sizeof(p.Rp));
	memcpy(p.tp, m->cam.tcw, sizeof(p.tp));
	memcpy(p.K, m->K, sizeof(p.K));
	if (!m->c->klt) { /* in sigmas: ORB_EPI_* */
		p.pt_sigma = m->sigma;
		p.epi_sigma = m->scratch;
		p.epi_weight = ORB_EPI_WEIGHT;
		p.epi_gate_px = ORB_EPI_GATE_SIGMA;
		p.huber_px = ORB_EPI_HUBER_SIGMA;
	}
	mvod_posefit_refine(&p, R, t);
}

/*
 * KLT tracking: the pose refined from the prediction (R, t in and out) on the tracked points;
 * PnP-RANSAC on the same pairs only when that fails; then once more with the other tracks'
 * epipolar distances (epipolar_refine). Returns the inliers or -errno; *np the pairs, as
 * mark_tracked counts them.
 */
static int track_klt(struct mvod_mapmode *m, double R[9], double t[3], int *np)
{
	int n = klt_pairs(m), need = m->c->p->min_matches;
	*np = m->n_pairs = n;
	if (n < need)
		return -ENODATA;
	int k = mvod_pnp_refine(m->pnp, m->X, m->uv, m->sigma, n, m->K, R, t, m->inlier);
	if (k < need)
		k = mvod_pnp_solve(m->pnp, m->X, m->uv, m->sigma, n, m->K, R, t, m->inlier);
	if (k >= need)
		epipolar_refine(m, n, m->c->fr->n_matches, R, t);
	return k;
}

/*
 * ORB: the map's points matched by projection from the prediction, else re-found; then the
 * pose refined once more with the other descriptor matches' epipolar distances from the last
 * frame (epipolar_refine; re-finding has matched them already). Costs the two-view matcher's
 * distance table every frame: 400e6 -> 486e6 instructions a frame (callgrind, KITTI 06).
 */
static int track_orb(struct mvod_mapmode *m, double R[9], double t[3], int *np,
		     struct mvod_vo_result *res)
{
	const struct mvod_features *f = &m->c->fr->cur->f;
	int need = m->c->p->min_matches;
	int ret = mvod_pm_set_frame(m->pm, m->kp, f->desc, f->n);
	if (ret)
		return ret;
	*np = gather(m);
	int k = track_projection(m, *np, R, t);
	bool refound = false;
	if (k < need) {
		k = refind(m, *np, R, t, res);
		refound = true;
	}
	if (k < need)
		return k;
	if (!refound) {
		ret = mvod_fe_match_ref(m->c->fe, m->c->fr);
		if (ret)
			return ret;
	}
	epipolar_refine(m, m->n_pairs, m->c->fr->n_matches, R, t);
	return k;
}

/* The frame could not be tracked with k (-1: no pose tried) of the need points: reset. */
static int lose(struct mvod_mapmode *m, int k, struct mvod_vo_result *res)
{
	res->map_lost = true;
	res->map_lost_inliers = k >= 0 ? k : -1;
	res->map_lost_need = m->c->p->min_matches;
	mvod_mapmode_reset(m);
	m->lost = true;
	return 0;
}

int mvod_mapmode_track(struct mvod_mapmode *m, const double *gt, struct mvod_vo_result *res,
		       struct mvod_step *st)
{
	const struct mvod_features *f = &m->c->fr->cur->f;
	int ret = mvod_mapping_ba_poll(m); /* a frame boundary: bundle adjustment lands here */
	if (ret)
		return ret;
	if (!m->active)
		return 0;
	res->features = f->n;
	if (f->n < m->c->p->min_matches) { /* black or textureless: hold the pose and the map */
		res->status = MVOD_FRAME_FEW_FEATURES;
		return 1;
	}
	to_map_kp(f, m->kp);
	double R[9], t[3];
	mvod_tracked_predict(&m->cam, R, t);
	int np = 0;
	int k = m->c->klt ? track_klt(m, R, t, &np) : track_orb(m, R, t, &np, res);
	if (k < m->c->p->min_matches) /* the two-view algorithm takes this frame */
		return lose(m, k, res);
	mvod_rot_reorthonormalise(R, ROT_ORTHO_TOL);
	ret = accept(m, np, m->n_pairs, R, t, gt, res, st);
	return ret ? ret : 1;
}
