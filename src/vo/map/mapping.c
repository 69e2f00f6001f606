/*
 * Map mode's mapping, on each keyframe: its observations, new points triangulated against the
 * window (descriptors: matched with the window's last keyframes; KLT: each track from its
 * first keyframe), culling, the metric scale (mapscale.c), windowed bundle adjustment
 * (mapping_ba.c).
 */
#include <errno.h>
#include <math.h>
#include <string.h>

#include "internal.h"
#include "vo/core/camera.h"
#include "vo/frontend/fe.h"
#include "vo/geom/motion.h"

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

bool mvod_mapping_reprojects(const double K[4], const double R[9], const double t[3],
			     const double X[3], const struct mvod_map_kp *kp)
{
	double c[3], uv[2];
	mvod_rigid_apply(R, t, X, c);
	if (!mvod_pinhole_pixel(K, c, uv))
		return false;
	double s = mvod_orb_sigma(kp->octave);
	double du = (uv[0] - kp->x) / s;
	double dv = (uv[1] - kp->y) / s;
	return du * du + dv * dv <= CHI2_GATE;
}

int mvod_mapping_add_frame(struct mvod_mapmode *m, const struct mvod_vo_frame *k,
			   const struct mvod_pose *c2w, mvod_map_id *out)
{
	struct mvod_pose w2c;
	mvod_pose_inverse(c2w, &w2c);
	for (int i = 0; i < k->f.n; i++)
		m->kp[i] = (struct mvod_map_kp){k->f.kp[i].x, k->f.kp[i].y, k->f.kp[i].response,
						k->f.kp[i].octave};
	struct mvod_map_kf_in in = {0};
	memcpy(in.Rcw, w2c.R, sizeof(in.Rcw));
	memcpy(in.tcw, w2c.t, sizeof(in.tcw));
	in.n = k->f.n;
	in.kp = m->kp;
	in.desc = k->f.desc;
	return mvod_map_add_keyframe(m->map, &in, out, NULL);
}

/*
 * Matchers without the cross-check (bf-ratio, flann, flann-ratio) pair a keypoint with two,
 * which stopped the whole run at the first map before the -EEXIST.
 */
int mvod_mapping_add_point(struct mvod_mapmode *m, const double X[3], mvod_map_id a, int ja,
			   mvod_map_id b, int jb, mvod_map_id *out)
{
	const struct mvod_map_keyframe *ka = mvod_map_keyframe(m->map, a);
	const struct mvod_map_keyframe *kb = mvod_map_keyframe(m->map, b);
	if (ka->pt[ja] != MVOD_MAP_NONE || kb->pt[jb] != MVOD_MAP_NONE)
		return -EEXIST;
	int ret = mvod_map_add_point(m->map, X, kb->desc + (size_t)jb * MVOD_MAP_DESC_BYTES, b,
				     out);
	if (!ret)
		ret = mvod_map_add_obs(m->map, *out, a, ja);
	if (!ret)
		ret = mvod_map_add_obs(m->map, *out, b, jb);
	return ret;
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

/* World ray (unnormalised) of keypoint kp in camera-from-world R; x its normalised point. */
static void ray(const struct mvod_camera *cam, const double R[9], const struct mvod_map_kp *kp,
		double r[3], double x[2])
{
	mvod_camera_normalise(cam, kp->x, kp->y, x);
	double c[3] = {x[0], x[1], 1};
	mvod_mat3_tvec(R, c, r);
}

/*
 * Triangulates keypoint ja of A with jb of B (midpoint, A to B motion R, t): true with world
 * X when the rays are far enough apart (cosine of their angle at most max_cos), the point in
 * front of both and within the gate in both.
 */
static bool triangulate(const struct mvod_mapmode *m, const struct mvod_map_keyframe *A,
			const struct mvod_map_keyframe *B, const double R[9], const double t[3],
			int ja, int jb, double max_cos, double X[3])
{
	double ra[3], rb[3], x1[2], x2[2], d1, d2;
	ray(m->c->cam, A->Rcw, &A->kp[ja], ra, x1);
	ray(m->c->cam, B->Rcw, &B->kp[jb], rb, x2);
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
	return mvod_mapping_reprojects(m->K, A->Rcw, A->tcw, X, &A->kp[ja]) &&
	       mvod_mapping_reprojects(m->K, B->Rcw, B->tcw, X, &B->kp[jb]);
}

/*
 * Keypoint ja of keyframe A (id a) with jb of B (id b), R, t the motion from A to B: a new point
 * when they triangulate with rays at most max_cos apart. 0 also when they do not or a keypoint
 * observes a point already (add_point), -ENOSPC when the map is full, or -errno.
 */
static int new_point(struct mvod_mapmode *m, mvod_map_id a, const struct mvod_map_keyframe *A,
		     int ja, mvod_map_id b, const struct mvod_map_keyframe *B, int jb,
		     const double R[9], const double t[3], double max_cos)
{
	double X[3];
	mvod_map_id id;
	if (!triangulate(m, A, B, R, t, ja, jb, max_cos, X))
		return 0;
	int ret = mvod_mapping_add_point(m, X, a, ja, b, jb, &id);
	return ret == -EEXIST ? 0 : ret;
}

/* New points from the unmatched keypoints of keyframes a (older) and b (the new one). */
static int triangulate_pair(struct mvod_mapmode *m, mvod_map_id a, mvod_map_id b)
{
	const struct mvod_map_keyframe *A = mvod_map_keyframe(m->map, a);
	const struct mvod_map_keyframe *B = mvod_map_keyframe(m->map, b);
	unmatched(A, &m->fa, m->ia);
	unmatched(B, &m->fb, m->ib);
	int nm, ret = mvod_fe_match(m->c->fe, &m->fa, &m->fb, m->pair, m->cap, &nm);
	if (ret)
		return ret;
	double R[9], t[3];
	mvod_motion_between(A->Rcw, A->tcw, B->Rcw, B->tcw, R, t);
	for (int i = 0; i < nm; i++) {
		int ja = m->ia[m->pair[i].a], jb = m->ib[m->pair[i].b];
		ret = new_point(m, a, A, ja, b, B, jb, R, t, MAX_COS_PARALLAX);
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
static int triangulate_tracks(struct mvod_mapmode *m, mvod_map_id b)
{
	const struct mvod_map_keyframe *B = mvod_map_keyframe(m->map, b);
	struct mvod_map_obs *firsts = m->c->fr->cur->first;
	for (int j = 0; j < B->n; j++) {
		struct mvod_map_obs *first = &firsts[j];
		const struct mvod_map_keyframe *A = mvod_map_keyframe(m->map, first->kf);
		if (B->pt[j] != MVOD_MAP_NONE)
			continue;
		if (!A || first->kf == b || A->pt[first->kp] != MVOD_MAP_NONE) {
			*first = (struct mvod_map_obs){b, j};
			continue;
		}
		double R[9], t[3];
		mvod_motion_between(A->Rcw, A->tcw, B->Rcw, B->tcw, R, t);
		int ret = new_point(m, first->kf, A, first->kp, b, B, j, R, t, KLT_MAX_COS_PARALLAX);
		if (ret == -ENOSPC)
			return 0;
		if (ret)
			return ret;
	}
	return 0;
}

/* Descriptors: the new keyframe b's unmatched keypoints against the window's last ones. */
static int triangulate_window(struct mvod_mapmode *m, mvod_map_id b)
{
	int nk = mvod_map_keyframes(m->map, m->kfs, m->mp.kf_cap);
	/* The widest baseline first: its points are the best placed; nearer ones fill in. */
	for (int i = nk - 1 - TRIANGULATE_WITH < 0 ? 0 : nk - 1 - TRIANGULATE_WITH; i < nk - 1; i++) {
		int ret = triangulate_pair(m, m->kfs[i], b);
		if (ret)
			return ret;
	}
	return 0;
}

/* The current frame's tracked points become the new keyframe's observations. */
static int observe(struct mvod_mapmode *m, mvod_map_id kf, mvod_map_id *pt, int n)
{
	int k = 0;
	for (int j = 0; j < n; j++) {
		/* A point the eviction just erased is stale: its add_obs fails, nothing changes. */
		if (mvod_map_add_obs(m->map, pt[j], kf, j) == 0)
			k += mvod_map_update_desc(m->map, pt[j]) == 0;
		else
			pt[j] = MVOD_MAP_NONE;
	}
	return k;
}

/*
 * After the keyframe's triangulation, scale and bundle adjustment: the frame takes the
 * keyframe's pose (rescaled, perhaps) and its points, the new ones too.
 */
static void take_keyframe(struct mvod_mapmode *m, mvod_map_id kf)
{
	struct mvod_vo_frame *cur = m->c->fr->cur;
	const struct mvod_map_keyframe *k = mvod_map_keyframe(m->map, kf);
	mvod_tracked_place(&m->cam, k->Rcw, k->tcw);
	int observed = 0;
	for (int j = 0; j < k->n; j++) {
		cur->pt[j] = k->pt[j];
		observed += k->pt[j] != MVOD_MAP_NONE;
	}
	/*
	 * KLT finds no point again once its track is gone, so the next keyframe is due when the
	 * tracks of all this keyframe's points, the new ones too, run low.
	 */
	if (m->c->klt)
		m->kf_tracked = observed;
	m->since_kf = 0;
}

int mvod_mapping_keyframe(struct mvod_mapmode *m, struct mvod_step *st, bool *added)
{
	struct mvod_vo_frame *cur = m->c->fr->cur;
	struct mvod_pose c2w;
	mvod_tracked_pose(&m->cam, &c2w);
	mvod_map_id kf;
	int ret = mvod_mapping_add_frame(m, cur, &c2w, &kf);
	if (ret)
		return ret;
	m->kf_tracked = observe(m, kf, cur->pt, cur->f.n);
	ret = m->c->klt ? triangulate_tracks(m, kf) : triangulate_window(m, kf);
	if (ret)
		return ret;
	mvod_map_cull(m->map, NULL);
	ret = mvod_mapscale_keyframe(m, kf, st);
	if (!ret)
		ret = mvod_mapping_ba(m);
	if (ret)
		return ret;
	take_keyframe(m, kf);
	*added = true;
	return 0;
}
