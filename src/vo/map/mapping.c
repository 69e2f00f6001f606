/*
 * Map mode's mapping: the first map from a two-view step, and on each keyframe: its
 * observations, new points triangulated against the window, culling, windowed bundle
 * adjustment.
 */
#include "mapvo.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "vo/geom/motion.h"
#include "util/linalg.h"

/* See mapvo.c: a two-view step builds the map from at least this many well-placed points. */
#define INIT_MIN_POINTS MVOD_MAPVO_INIT_MIN_POINTS
/*
 * ... and only when their median triangulation angle, in pixels (the angle times the focal
 * length: a point's depth error over its depth is about the pixel noise over this), is at
 * least this. Measured (median over each pair's well-triangulated points): every map KITTI 06
 * and 07 built, first or rebuilt, had 5.8-15 px; mvod-synth's turn (320x240, 0.1 m and 3.75
 * deg a frame) rebuilt mid-turn from 2-frame pairs at 2.4 and 2.9 px, maps lost again within
 * 4 and 11 frames, and its first map came from 2.4 px. 3 px refuses those and changes no
 * KITTI run.
 */
#define INIT_MIN_PARALLAX_PX 3.0
/*
 * ... and not more than this many times the median flow left after the rotation-only fit
 * (twoview.c's free_parallax_px). A rotation fitted to the flow leaves less of it than the
 * true one (it absorbs part of a translation's flow), but a wrong rotation adds a whole
 * parallax of its own: while the car pulls away (KITTI 07, ORB, frames 0-3, 9 cm a frame) the
 * essential matrix took a rotation 3.25 deg wrong and a sideways translation, triangulated at
 * 37.7 px where the rotation-only fit left 2.4 (15.8 times), and that map was tracked 35
 * frames at 40-120 deg of direction error (dir_deg_mean 16.5, err_avg 0.359). Every map
 * KITTI 06 and 07 built otherwise, either front end, had 0.95-3.9 times.
 */
#define INIT_MAX_PARALLAX_RATIO 6.0
/* Chi-square gate (2 dof, 95 %) on a reprojection error in sigma units, as the shims use. */
#define CHI2_GATE 5.991
/*
 * A new point needs its two rays at least this far apart: cos 0.9998 = 1.15 deg, ORB-SLAM's
 * cosParallaxRays gate; smaller angles put the depth anywhere along the ray.
 */
#define MAX_COS_PARALLAX 0.9998
/*
 * With KLT a point lives only as long as its track (nothing finds it again), so a badly placed
 * one is never outvoted by later keyframes: new points need 3 deg (cos 0.99863). Measured on
 * KITTI 07, free scale: 1.15 deg drifted 1.194 (Sim(3) ATE 0.479 m), 2 deg 1.156 (0.361 m),
 * 2.5 deg 1.098 (0.389 m), 3 deg 1.035 (0.303 m); 06: 1.014, 1.013, -, 1.007.
 */
#define KLT_MAX_COS_PARALLAX 0.99863
/* Keyframes before the new one that it triangulates against (the descriptor table each). */
#define TRIANGULATE_WITH 3

/* World point X seen by keypoint kp from camera-from-world R, t: within the gate, in front. */
static bool reprojects(const double K[4], const double R[9], const double t[3],
		       const double X[3], const struct mvod_map_kp *kp)
{
	double c[3], uv[2];
	mvod_rigid_apply(R, t, X, c);
	if (!mvod_pinhole_pixel(K, c, uv))
		return false;
	double s = mvod_mapvo_sigma(kp->octave);
	double du = (uv[0] - kp->x) / s;
	double dv = (uv[1] - kp->y) / s;
	return du * du + dv * dv <= CHI2_GATE;
}

/* Adds the frame of slot k, at camera-to-world pose c2w, as a keyframe. */
static int add_frame_kf(struct mvod_mapvo *mv, const struct frame_slot *k,
			const struct mvod_pose *c2w, mvod_map_id *out)
{
	struct mvod_pose w2c;
	mvod_pose_inverse(c2w, &w2c);
	for (int i = 0; i < k->f.n; i++)
		mv->kp[i] = (struct mvod_map_kp){k->f.kp[i].x, k->f.kp[i].y, k->f.kp[i].response,
						 k->f.kp[i].octave};
	struct mvod_map_kf_in in = {0};
	memcpy(in.Rcw, w2c.R, sizeof(in.Rcw));
	memcpy(in.tcw, w2c.t, sizeof(in.tcw));
	in.n = k->f.n;
	in.kp = mv->kp;
	in.desc = k->f.desc;
	return mvod_map_add_keyframe(mv->map, &in, out, NULL);
}

/*
 * A new point at world X seen by keypoint ja of keyframe a and jb of b; -EEXIST, and no point,
 * when either keypoint observes one already: matchers without the cross-check (bf-ratio,
 * flann, flann-ratio) pair a keypoint with two, which stopped the whole run at the first map.
 */
static int add_point(struct mvod_mapvo *mv, const double X[3], mvod_map_id a, int ja,
		     mvod_map_id b, int jb, mvod_map_id *out)
{
	const struct mvod_map_keyframe *ka = mvod_map_keyframe(mv->map, a);
	const struct mvod_map_keyframe *kb = mvod_map_keyframe(mv->map, b);
	if (ka->pt[ja] != MVOD_MAP_NONE || kb->pt[jb] != MVOD_MAP_NONE)
		return -EEXIST;
	int ret = mvod_map_add_point(mv->map, X, kb->desc + (size_t)jb * MVOD_MAP_DESC_BYTES, b,
				     out);
	if (!ret)
		ret = mvod_map_add_obs(mv->map, *out, a, ja);
	if (!ret)
		ret = mvod_map_add_obs(mv->map, *out, b, jb);
	return ret;
}

/* The two-view step's structure (in vo->cur's camera) as points of keyframes a and b. */
static int init_points(struct mvod_vo *vo, int n, mvod_map_id a, mvod_map_id b)
{
	struct mvod_mapvo *mv = vo->mapvo;
	const struct mvod_map_keyframe *ka = mvod_map_keyframe(mv->map, a);
	const struct mvod_map_keyframe *kb = mvod_map_keyframe(mv->map, b);
	int made = 0;
	for (int j = 0; j < vo->cur->f.n; j++)
		mv->ref_pt[j] = MVOD_MAP_NONE; /* the current frame is about to be the reference */
	for (int i = 0; i < n; i++) {
		int ia = vo->matches[i].a, ib = vo->matches[i].b;
		if (!vo->cur->has_pt[ib])
			continue;
		double X[3];
		mvod_rigid_apply(vo->pose.R, vo->pose.t, vo->cur->pts + 3 * ib, X);
		if (!reprojects(mv->K, ka->Rcw, ka->tcw, X, &ka->kp[ia]) ||
		    !reprojects(mv->K, kb->Rcw, kb->tcw, X, &kb->kp[ib]))
			continue;
		int ret = add_point(mv, X, a, ia, b, ib, &mv->ref_pt[ib]);
		if (ret == -ENOSPC)
			break;
		if (ret && ret != -EEXIST)
			return ret;
		made += !ret;
	}
	return made;
}

/*
 * --frontend klt: the first keyframe of each track of b (the frame about to be the reference)
 * that got no point: a for the step's matches (the widest baseline they have), else b.
 */
static void init_first(struct mvod_vo *vo, int n, mvod_map_id a, mvod_map_id b)
{
	struct mvod_mapvo *mv = vo->mapvo;
	for (int j = 0; j < vo->cur->f.n; j++)
		mv->ref_first[j] = (struct mvod_map_obs){b, j};
	for (int i = 0; i < n; i++)
		if (mv->ref_pt[vo->matches[i].b] == MVOD_MAP_NONE)
			mv->ref_first[vo->matches[i].b] = (struct mvod_map_obs){a, vo->matches[i].a};
}

/* The tracking state once a map exists: the last frame b and the step that led to it. */
static void start_tracking(struct mvod_mapvo *mv, mvod_map_id a, mvod_map_id b)
{
	const struct mvod_map_keyframe *ka = mvod_map_keyframe(mv->map, a);
	const struct mvod_map_keyframe *kb = mvod_map_keyframe(mv->map, b);
	memcpy(mv->Rcw, kb->Rcw, sizeof(mv->Rcw));
	memcpy(mv->tcw, kb->tcw, sizeof(mv->tcw));
	mvod_motion_between(ka->Rcw, ka->tcw, kb->Rcw, kb->tcw, mv->vR, mv->vt);
	mv->since_kf = 0;
	mv->kf_tracked = mvod_map_n_points(mv->map);
	mv->active = true;
}

/*
 * A map waits for parallax: a step with too few well-triangulated points, or too little parallax
 * between them (INIT_MIN_PARALLAX_PX), keeps only its rotation (as a rotation-only frame does), so
 * the reference stays and the baseline grows.
 * After a loss too (in the VO seam test ORB's one-frame pairs after a loss never had enough, and
 * two-view steps chained on): the reference is the last tracked frame, whose old map points
 * scale the step.
 * With --scale gt the step's length is the truth's, so there is no unit to wait for: the
 * translation stays (the reference is kept all the same). Held, KITTI 07 published a zero
 * step and then a double one twice (frames 1-2, the map's start, and 13-14, a loss), each
 * pair costing err_avg 0.3 twice: map klt gt 0.0558 -> 0.0508, err_max 0.319 -> 0.171.
 * After a loss the camera was moving when the map was lost: the step keeps its length (the
 * last speed times the frames it spans, or the old map's structure) along the direction the
 * camera last travelled in (the last tracked frame's velocity, in its own axes), not two-view's
 * direction at this low parallax (KITTI 07, ORB, --scale height, frame 31: 62 degrees off the
 * truth; the last travel 2.3) and not zero. Held at zero, a step whose reference then moved
 * on (fewer than keep_overlap() matches, as in every fast frame) was lost for good: mvod-synth
 * forward at 14.5 m/s in KITTI's field of view (640x192, fx 369), --scale height, lost its map
 * 7 times and 11 frames' travel, 5.4 % of the path (SE(3) ATE 4.07 -> 1.93 m); the drive along
 * KITTI 06's ground truth held 62 frames at zero, t_rel 6.89 -> 2.05 % (KITTI 00: 2.44 ->
 * 2.78 % over three track caps, each under 3 %).
 */
static void hold_translation(struct mvod_vo *vo, struct mvod_vo_result *res)
{
	res->status = MVOD_FRAME_ROTATION;
	if (vo->p.scale_mode == MVOD_SCALE_MODE_GT)
		return;
	struct mvod_mapvo *mv = vo->mapvo;
	struct mvod_pose inv, rel;
	mvod_pose_inverse(&vo->ref->pose, &inv);
	mvod_pose_compose(&inv, &vo->pose, &rel); /* the reference camera from this one */
	double len = mvod_vec3_norm(rel.t), d[3];
	mvod_mat3_tvec(mv->vR, mv->vt, d); /* minus the last tracked frame's centre in the one before */
	double dn = mvod_vec3_norm(d);
	bool travel = mv->had_map && dn > 0 && isfinite(len);
	for (int k = 0; k < 3; k++)
		rel.t[k] = travel ? -d[k] * len / dn : 0;
	mvod_pose_compose(&vo->ref->pose, &rel, &vo->pose);
	if (travel)
		return;
	res->scale_source = MVOD_SCALE_NONE;
	res->step_m = 0;
	if (!mv->had_map)
		vo->have_step = 0; /* the map's first step is still to define the unit */
}

/*
 * After a loss the reference may lie several frames back (held while the baseline grows, or
 * frames between that were not tracked); a step without structure to scale by is the last
 * speed times the frames it spans, not one frame's step (which made a rebuilt map 3 times too
 * small after a 3-frame hold in the seam test). Scales the step's pose and structure by that.
 */
static void speed_over_frames(struct mvod_vo *vo, struct mvod_vo_result *res)
{
	double k = (double)(vo->cur->seq - vo->ref->seq);
	if (!vo->mapvo->had_map || res->scale_source != MVOD_SCALE_CONSTANT_SPEED || !(k > 1))
		return;
	struct mvod_pose inv, rel;
	mvod_pose_inverse(&vo->ref->pose, &inv);
	mvod_pose_compose(&inv, &vo->pose, &rel);
	for (int i = 0; i < 3; i++)
		rel.t[i] *= k;
	mvod_pose_compose(&vo->ref->pose, &rel, &vo->pose);
	for (int j = 0; j < vo->cur->f.n * 3; j++)
		vo->cur->pts[j] *= k;
	res->step_m *= k;
}

/*
 * The pair's parallax: the median angle under which the step's well-triangulated points (has_pt
 * of vo->cur, in its camera) see the reference's and the current camera's centres, times the
 * focal length, in pixels. 0 without points.
 */
static double init_parallax_px(struct mvod_vo *vo, int n)
{
	double d[3], c[3]; /* the reference camera's centre in the current camera */
	for (int k = 0; k < 3; k++)
		d[k] = vo->ref->pose.t[k] - vo->pose.t[k];
	mvod_mat3_tvec(vo->pose.R, d, c);
	int m = 0;
	for (int i = 0; i < n; i++) {
		int b = vo->matches[i].b;
		if (!vo->cur->has_pt[b])
			continue;
		const double *X = vo->cur->pts + 3 * b;
		double r[3] = {X[0] - c[0], X[1] - c[1], X[2] - c[2]};
		vo->scratch[m++] = mvod_vec3_angle(X, r);
	}
	return m ? mvod_median(vo->scratch, m) * 0.5 * (vo->cam.fx + vo->cam.fy) : 0;
}

int mvod_mapvo_init(struct mvod_vo *vo, struct mvod_vo_result *res)
{
	struct mvod_mapvo *mv = vo->mapvo;
	int n = res->matches, good = 0;
	if (res->status != MVOD_FRAME_MOTION)
		return 0;
	speed_over_frames(vo, res);
	for (int i = 0; i < n; i++)
		good += vo->cur->has_pt[vo->matches[i].b];
	double par = good ? init_parallax_px(vo, n) : 0;
	if (good < INIT_MIN_POINTS || par < INIT_MIN_PARALLAX_PX ||
	    par > INIT_MAX_PARALLAX_RATIO * vo->free_parallax_px) {
		hold_translation(vo, res);
		return 0;
	}
	mvod_map_reset(mv->map);
	mvod_map_id a, b;
	int ret = add_frame_kf(mv, vo->ref, &vo->ref->pose, &a);
	if (!ret)
		ret = add_frame_kf(mv, vo->cur, &vo->pose, &b);
	if (!ret)
		ret = init_points(vo, n, a, b);
	if (ret < INIT_MIN_POINTS) {
		mvod_map_reset(mv->map);
		return ret < 0 ? ret : 0;
	}
	if (vo->klt)
		init_first(vo, n, a, b);
	ret = mvod_mapping_ba(mv);
	if (ret)
		return ret;
	start_tracking(mv, a, b);
	mv->had_map = true;
	mv->lost = false;
	res->keyframe = true;
	return 1;
}

static void unmatched(const struct mvod_map_keyframe *k, struct mvod_features *f, int *idx)
{
	f->n = 0;
	for (int j = 0; j < k->n; j++) {
		if (k->pt[j] != MVOD_MAP_NONE)
			continue;
		f->kp[f->n] = (struct mvod_keypoint){k->kp[j].x, k->kp[j].y, k->kp[j].octave,
						     k->kp[j].response};
		memcpy(f->desc + (size_t)f->n * MVOD_MAP_DESC_BYTES,
		       k->desc + (size_t)j * MVOD_MAP_DESC_BYTES, MVOD_MAP_DESC_BYTES);
		idx[f->n++] = j;
	}
}

/* World ray (unnormalised) of keypoint kp in camera-from-world R. */
static void ray(const double K[4], const double R[9], const struct mvod_map_kp *kp, double r[3],
		double x[2])
{
	x[0] = (kp->x - K[2]) / K[0];
	x[1] = (kp->y - K[3]) / K[1];
	double c[3] = {x[0], x[1], 1};
	mvod_mat3_tvec(R, c, r);
}

/*
 * Triangulates keypoint ja of A with jb of B (midpoint, A to B motion R, t): true with world
 * X when the rays are far enough apart (cosine of their angle at most max_cos), the point in
 * front of both and within the gate in both.
 */
static bool triangulate(const struct mvod_mapvo *mv, const struct mvod_map_keyframe *A,
			const struct mvod_map_keyframe *B, const double R[9], const double t[3],
			int ja, int jb, double max_cos, double X[3])
{
	double ra[3], rb[3], x1[2], x2[2], d1, d2;
	ray(mv->K, A->Rcw, &A->kp[ja], ra, x1);
	ray(mv->K, B->Rcw, &B->kp[jb], rb, x2);
	if (cos(mvod_vec3_angle(ra, rb)) > max_cos ||
	    !mvod_triangulate_midpoint(R, t, x1, x2, &d1, &d2) || !(d1 > 0) || !(d2 > 0))
		return false;
	/* The midpoint of the two rays' closest points, in the world. */
	double ca[3] = {x1[0] * d1 - A->tcw[0], x1[1] * d1 - A->tcw[1], d1 - A->tcw[2]};
	double cb[3] = {x2[0] * d2 - B->tcw[0], x2[1] * d2 - B->tcw[1], d2 - B->tcw[2]}, Xb[3];
	mvod_mat3_tvec(A->Rcw, ca, X);
	mvod_mat3_tvec(B->Rcw, cb, Xb);
	for (int k = 0; k < 3; k++)
		X[k] = 0.5 * (X[k] + Xb[k]);
	return reprojects(mv->K, A->Rcw, A->tcw, X, &A->kp[ja]) &&
	       reprojects(mv->K, B->Rcw, B->tcw, X, &B->kp[jb]);
}

/*
 * Keypoint ja of keyframe A (id a) with jb of B (id b), R, t the motion from A to B: a new point
 * when they triangulate with rays at most max_cos apart. 0 also when they do not or a keypoint
 * observes a point already (add_point), -ENOSPC when the map is full, or -errno.
 */
static int new_point(struct mvod_mapvo *mv, mvod_map_id a, const struct mvod_map_keyframe *A,
		     int ja, mvod_map_id b, const struct mvod_map_keyframe *B, int jb,
		     const double R[9], const double t[3], double max_cos)
{
	double X[3];
	mvod_map_id id;
	if (!triangulate(mv, A, B, R, t, ja, jb, max_cos, X))
		return 0;
	int ret = add_point(mv, X, a, ja, b, jb, &id);
	return ret == -EEXIST ? 0 : ret;
}

/* New points from the unmatched keypoints of keyframes a (older) and b (the new one). */
static int triangulate_pair(struct mvod_vo *vo, mvod_map_id a, mvod_map_id b)
{
	struct mvod_mapvo *mv = vo->mapvo;
	const struct mvod_map_keyframe *A = mvod_map_keyframe(mv->map, a);
	const struct mvod_map_keyframe *B = mvod_map_keyframe(mv->map, b);
	unmatched(A, &mv->fa, mv->ia);
	unmatched(B, &mv->fb, mv->ib);
	int nm, ret = mvod_match(vo->matcher, &mv->fa, &mv->fb, vo->matches, vo->cap, &nm);
	if (ret)
		return ret;
	double R[9], t[3];
	mvod_motion_between(A->Rcw, A->tcw, B->Rcw, B->tcw, R, t);
	for (int i = 0; i < nm; i++) {
		int ja = mv->ia[vo->matches[i].a], jb = mv->ib[vo->matches[i].b];
		ret = new_point(mv, a, A, ja, b, B, jb, R, t, MAX_COS_PARALLAX);
		if (ret == -ENOSPC)
			return 0;
		if (ret)
			return ret;
	}
	return 0;
}

/*
 * --frontend klt: each track of the new keyframe b without a point, triangulated against the
 * keyframe it was first seen on (its widest baseline). A track whose first keyframe left the
 * window, or whose keypoint there observes a point since (the track lost it as an outlier),
 * starts again from b; one with too little parallax yet waits for a later keyframe.
 */
static int triangulate_tracks(struct mvod_mapvo *mv, mvod_map_id b)
{
	const struct mvod_map_keyframe *B = mvod_map_keyframe(mv->map, b);
	for (int j = 0; j < B->n; j++) {
		struct mvod_map_obs *first = &mv->cur_first[j];
		const struct mvod_map_keyframe *A = mvod_map_keyframe(mv->map, first->kf);
		if (B->pt[j] != MVOD_MAP_NONE)
			continue;
		if (!A || first->kf == b || A->pt[first->kp] != MVOD_MAP_NONE) {
			*first = (struct mvod_map_obs){b, j};
			continue;
		}
		double R[9], t[3];
		mvod_motion_between(A->Rcw, A->tcw, B->Rcw, B->tcw, R, t);
		int ret = new_point(mv, first->kf, A, first->kp, b, B, j, R, t, KLT_MAX_COS_PARALLAX);
		if (ret == -ENOSPC)
			return 0;
		if (ret)
			return ret;
	}
	return 0;
}

/* Descriptors: the new keyframe b's unmatched keypoints against the window's last ones. */
static int triangulate_window(struct mvod_vo *vo, mvod_map_id b)
{
	struct mvod_mapvo *mv = vo->mapvo;
	int nk = mvod_map_keyframes(mv->map, mv->kfs, mv->mp.kf_cap);
	/* The widest baseline first: its points are the best placed; nearer ones fill in. */
	for (int i = nk - 1 - TRIANGULATE_WITH < 0 ? 0 : nk - 1 - TRIANGULATE_WITH; i < nk - 1; i++) {
		int ret = triangulate_pair(vo, mv->kfs[i], b);
		if (ret)
			return ret;
	}
	return 0;
}

/* The current frame's tracked points become the new keyframe's observations. */
static int observe(struct mvod_mapvo *mv, mvod_map_id kf, int n)
{
	int k = 0;
	for (int j = 0; j < n; j++) {
		/* A point the eviction just erased is stale: its add_obs fails, nothing changes. */
		if (mvod_map_add_obs(mv->map, mv->cur_pt[j], kf, j) == 0)
			k += mvod_map_update_desc(mv->map, mv->cur_pt[j]) == 0;
		else
			mv->cur_pt[j] = MVOD_MAP_NONE;
	}
	return k;
}

int mvod_mapping_keyframe(struct mvod_vo *vo, bool *added)
{
	struct mvod_mapvo *mv = vo->mapvo;
	struct mvod_pose c2w = {0};
	memcpy(c2w.R, mv->Rcw, sizeof(c2w.R));
	memcpy(c2w.t, mv->tcw, sizeof(c2w.t));
	mvod_pose_inverse(&c2w, &c2w);
	mvod_map_id kf;
	int ret = add_frame_kf(mv, vo->cur, &c2w, &kf);
	if (ret)
		return ret;
	mv->kf_tracked = observe(mv, kf, vo->cur->f.n);
	ret = vo->klt ? triangulate_tracks(mv, kf) : triangulate_window(vo, kf);
	if (ret)
		return ret;
	mvod_map_cull(mv->map, NULL);
	ret = mvod_mapscale_keyframe(vo, kf);
	if (!ret)
		ret = mvod_mapping_ba(mv);
	if (ret)
		return ret;
	const struct mvod_map_keyframe *k = mvod_map_keyframe(mv->map, kf);
	memcpy(mv->Rcw, k->Rcw, sizeof(mv->Rcw));
	memcpy(mv->tcw, k->tcw, sizeof(mv->tcw));
	int observed = 0;
	for (int j = 0; j < k->n; j++) {
		mv->cur_pt[j] = k->pt[j];
		observed += k->pt[j] != MVOD_MAP_NONE;
	}
	/*
	 * KLT finds no point again once its track is gone, so the next keyframe is due when the
	 * tracks of all this keyframe's points, the new ones too, run low.
	 */
	if (vo->klt)
		mv->kf_tracked = observed;
	mv->since_kf = 0;
	*added = true;
	return 0;
}
