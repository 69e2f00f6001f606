/*
 * Map mode's first map (and each after a loss) from a two-view step: its two frames become
 * keyframes, its well-triangulated points the map's points, once the step has the points and
 * the parallax for it; until then the step keeps only its rotation (hold_translation).
 */
#include <errno.h>
#include <math.h>
#include <string.h>

#include "internal.h"
#include "mapmode.h"
#include "util/linalg.h"

/* A two-view step builds the map from at least this many well-placed points (mapmode.h). */
#define INIT_MIN_POINTS MVOD_MAPMODE_INIT_MIN_POINTS
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
 * (the two-view step's free_parallax_px). A rotation fitted to the flow leaves less of it than the
 * true one (it absorbs part of a translation's flow), but a wrong rotation adds a whole
 * parallax of its own: while the car pulls away (KITTI 07, ORB, frames 0-3, 9 cm a frame) the
 * essential matrix took a rotation 3.25 deg wrong and a sideways translation, triangulated at
 * 37.7 px where the rotation-only fit left 2.4 (15.8 times), and that map was tracked 35
 * frames at 40-120 deg of direction error (dir_deg_mean 16.5, err_avg 0.359). Every map
 * KITTI 06 and 07 built otherwise, either front end, had 0.95-3.9 times.
 */
#define INIT_MAX_PARALLAX_RATIO 6.0

/* The two-view step's structure (in the current camera) as points of keyframes a and b. */
static int init_points(struct mvod_mapmode *m, int n, const struct mvod_pose *pose,
		       mvod_map_id a, mvod_map_id b)
{
	const struct mvod_frames *fr = m->c->fr;
	const struct mvod_map_keyframe *ka = mvod_map_keyframe(m->map, a);
	const struct mvod_map_keyframe *kb = mvod_map_keyframe(m->map, b);
	int made = 0;
	for (int j = 0; j < fr->cur->f.n; j++)
		fr->cur->pt[j] = MVOD_MAP_NONE;
	for (int i = 0; i < n; i++) {
		int ia = fr->matches[i].a, ib = fr->matches[i].b;
		if (!fr->cur->has_pt[ib])
			continue;
		double X[3];
		mvod_rigid_apply(pose->R, pose->t, fr->cur->pts + 3 * ib, X);
		if (!mvod_mapping_reprojects(m->K, ka->Rcw, ka->tcw, X, &ka->kp[ia]) ||
		    !mvod_mapping_reprojects(m->K, kb->Rcw, kb->tcw, X, &kb->kp[ib]))
			continue;
		int ret = mvod_mapping_add_point(m, X, a, ia, b, ib, &fr->cur->pt[ib]);
		if (ret == -ENOSPC)
			break;
		if (ret && ret != -EEXIST)
			return ret;
		made += !ret;
	}
	return made;
}

/*
 * --frontend klt: the first keyframe of each track of b (the current frame, about to be the
 * reference) that got no point: a for the step's matches (the widest baseline they have),
 * else b.
 */
static void init_first(struct mvod_mapmode *m, int n, mvod_map_id a, mvod_map_id b)
{
	const struct mvod_frames *fr = m->c->fr;
	for (int j = 0; j < fr->cur->f.n; j++)
		fr->cur->first[j] = (struct mvod_map_obs){b, j};
	for (int i = 0; i < n; i++)
		if (fr->cur->pt[fr->matches[i].b] == MVOD_MAP_NONE)
			fr->cur->first[fr->matches[i].b] =
				(struct mvod_map_obs){a, fr->matches[i].a};
}

/* The tracking state once a map exists: the last frame b and the step that led to it. */
static void start_tracking(struct mvod_mapmode *m, mvod_map_id a, mvod_map_id b)
{
	const struct mvod_map_keyframe *ka = mvod_map_keyframe(m->map, a);
	const struct mvod_map_keyframe *kb = mvod_map_keyframe(m->map, b);
	mvod_tracked_start(&m->cam, ka->Rcw, ka->tcw, kb->Rcw, kb->tcw);
	m->since_kf = 0;
	m->kf_tracked = mvod_map_n_points(m->map);
	m->active = true;
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
 * on (fewer than vo.c's keep_overlap() matches, as in every fast frame) was lost for good: mvod-synth
 * forward at 14.5 m/s in KITTI's field of view (640x192, fx 369), --scale height, lost its map
 * 7 times and 11 frames' travel, 5.4 % of the path (SE(3) ATE 4.07 -> 1.93 m); the drive along
 * KITTI 06's ground truth held 62 frames at zero, t_rel 6.89 -> 2.05 % (KITTI 00: 2.44 ->
 * 2.78 % over three track caps, each under 3 %).
 */
static void hold_translation(struct mvod_mapmode *m, struct mvod_vo_result *res,
			     struct mvod_step *st)
{
	res->status = MVOD_FRAME_ROTATION;
	if (m->c->scale->mode == MVOD_SCALE_MODE_GT)
		return;
	const struct mvod_pose *ref = &m->c->fr->ref->pose;
	struct mvod_pose inv, rel;
	mvod_pose_inverse(ref, &inv);
	mvod_pose_compose(&inv, &st->pose, &rel); /* the reference camera from this one */
	double len = mvod_vec3_norm(rel.t), d[3];
	mvod_mat3_tvec(m->cam.vR, m->cam.vt, d); /* minus the last tracked frame's centre in the one before */
	double dn = mvod_vec3_norm(d);
	bool travel = m->had_map && dn > 0 && isfinite(len);
	for (int k = 0; k < 3; k++)
		rel.t[k] = travel ? -d[k] * len / dn : 0;
	mvod_pose_compose(ref, &rel, &st->pose);
	if (travel)
		return;
	res->scale_source = MVOD_SCALE_NONE;
	res->step_m = 0;
	if (!m->had_map)
		mvod_scale_forget_speed(m->c->scale); /* the map's first step is still to define the unit */
}

/*
 * After a loss the reference may lie several frames back (held while the baseline grows, or
 * frames between that were not tracked); a step without structure to scale by is the last
 * speed times the frames it spans, not one frame's step (which made a rebuilt map 3 times too
 * small after a 3-frame hold in the seam test). Scales the step's pose and structure by that.
 */
static void speed_over_frames(struct mvod_mapmode *m, struct mvod_vo_result *res,
			      struct mvod_step *st)
{
	const struct mvod_frames *fr = m->c->fr;
	double k = (double)(fr->cur->seq - fr->ref->seq);
	if (!m->had_map || res->scale_source != MVOD_SCALE_CONSTANT_SPEED || !(k > 1))
		return;
	struct mvod_pose inv, rel;
	mvod_pose_inverse(&fr->ref->pose, &inv);
	mvod_pose_compose(&inv, &st->pose, &rel);
	for (int i = 0; i < 3; i++)
		rel.t[i] *= k;
	mvod_pose_compose(&fr->ref->pose, &rel, &st->pose);
	for (int j = 0; j < fr->cur->f.n * 3; j++)
		fr->cur->pts[j] *= k;
	res->step_m *= k;
}

/*
 * The pair's parallax: the median angle under which the step's well-triangulated points (has_pt
 * of vo->cur, in its camera) see the reference's and the current camera's centres, times the
 * focal length, in pixels. 0 without points.
 */
static double init_parallax_px(struct mvod_mapmode *m, int n, const struct mvod_pose *pose)
{
	const struct mvod_frames *fr = m->c->fr;
	double d[3], c[3]; /* the reference camera's centre in the current camera */
	for (int k = 0; k < 3; k++)
		d[k] = fr->ref->pose.t[k] - pose->t[k];
	mvod_mat3_tvec(pose->R, d, c);
	int np = 0;
	for (int i = 0; i < n; i++) {
		int b = fr->matches[i].b;
		if (!fr->cur->has_pt[b])
			continue;
		const double *X = fr->cur->pts + 3 * b;
		double r[3] = {X[0] - c[0], X[1] - c[1], X[2] - c[2]};
		m->scratch[np++] = mvod_vec3_angle(X, r);
	}
	return np ? mvod_median(m->scratch, np) * 0.5 * (m->c->cam->fx + m->c->cam->fy) : 0;
}

/* Whether the step (n matches, st) has the points and the parallax a map needs. */
static bool ready(struct mvod_mapmode *m, int n, const struct mvod_step *st)
{
	const struct mvod_frames *fr = m->c->fr;
	int good = 0;
	for (int i = 0; i < n; i++)
		good += fr->cur->has_pt[fr->matches[i].b];
	double par = good ? init_parallax_px(m, n, &st->pose) : 0;
	return !(good < INIT_MIN_POINTS || par < INIT_MIN_PARALLAX_PX ||
		 par > INIT_MAX_PARALLAX_RATIO * st->free_parallax_px);
}

/* The map from the step's two frames: 0 when its points fall short, -errno. */
static int build(struct mvod_mapmode *m, int n, const struct mvod_step *st, mvod_map_id *a,
		 mvod_map_id *b)
{
	const struct mvod_frames *fr = m->c->fr;
	mvod_map_reset(m->map);
	int ret = mvod_mapping_add_frame(m, fr->ref, &fr->ref->pose, a);
	if (!ret)
		ret = mvod_mapping_add_frame(m, fr->cur, &st->pose, b);
	if (!ret)
		ret = init_points(m, n, &st->pose, *a, *b);
	if (ret < INIT_MIN_POINTS) {
		mvod_map_reset(m->map);
		return ret < 0 ? ret : 0;
	}
	return 1;
}

int mvod_mapmode_init(struct mvod_mapmode *m, struct mvod_vo_result *res, struct mvod_step *st)
{
	int n = res->matches;
	if (res->status != MVOD_FRAME_MOTION)
		return 0;
	speed_over_frames(m, res, st);
	if (!ready(m, n, st)) {
		hold_translation(m, res, st);
		return 0;
	}
	mvod_map_id a, b;
	int ret = build(m, n, st, &a, &b);
	if (ret <= 0)
		return ret;
	if (m->c->klt)
		init_first(m, n, a, b);
	ret = mvod_mapping_ba(m);
	if (ret)
		return ret;
	start_tracking(m, a, b);
	m->had_map = true;
	m->lost = false;
	res->keyframe = true;
	return 1;
}
