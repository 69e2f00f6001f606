/*
 * Map mode's windowed bundle adjustment, run on its own thread (ba_thread.h): at a keyframe
 * the window is copied into the thread's job and posted; at the start of a later frame the
 * result is written back into the map. Everything in between, the frame thread tracks on.
 */
#include "mapvo.h"

#include <string.h>

#include "mvod/geom.h"

/* Bundle adjustment's Levenberg-Marquardt iterations per keyframe. */
#define BA_ITERATIONS 5
/*
 * ... and it stops earlier once a step changes the cost by under this share of it (Ceres's
 * default is 1e-6): most of the drop comes in the first step or two, the later ones move it by
 * 1e-3 to 1e-5 (KITTI 07). Issue 13, KITTI 06 (callgrind, --mode map): 93.77e6 -> 92.34e6
 * instructions a frame, all on the BA thread; the KLT map rows of the clip table stay within
 * 0.004 m / 0.005 of drift free-scale and improve in height mode (BENCHMARKS.md, mapspeed2).
 * 1e-3 saves 2.7e6 but costs 06 and 07 height (SE(3) ATE 0.681 -> 0.758 m, 07 drift 1.068 ->
 * 1.087).
 */
#define BA_FUNCTION_TOLERANCE 1e-4
/*
 * Solved by ba_lm.c's Levenberg-Marquardt, not Ceres: the same steps (unit/ba compares them;
 * the KITTI clip table is unchanged, every map trajectory within 1e-7 m of Ceres's but 07 orb
 * auto's, 2e-5 m, and KITTI 00's free-scale t_rel is Ceres's 4.20 / 3.01 / 4.68 %) for about a
 * third of the instructions: KITTI 06 (callgrind, --scale gt) 92.3e6 -> 85.1e6 a frame,
 * two-view 83.7e6 (BENCHMARKS.md, mapspeed3).
 */
#define BA_OWN_SOLVER true

/* Index of kf among the window's keyframes (mv->kfs, nk of them), or -1. */
static int kf_index(const struct mvod_mapvo *mv, int nk, mvod_map_id kf)
{
	for (int i = 0; i < nk; i++)
		if (mv->kfs[i] == kf)
			return i;
	return -1;
}

/*
 * The gauge (mapvo.h): the oldest n_held keyframes held (never the newest), but in a map's
 * first window (its two keyframes) with free scale only the oldest. The second keyframe's pose
 * there is the two-view step's (essential matrix, length from the old map or the last speed),
 * never refined against the map's points: held, its rotation and direction stay as the step
 * left them for the whole map. Freed, they are refined; its distance (the map's unit, which two
 * keyframes alone do not observe) moves by what Levenberg-Marquardt's steps leave in that
 * direction, 0.1-1.2 % on KITTI 07. Free scale only: with --scale gt the step lengths come from
 * the truth and with --scale height the map is rescaled at its keyframes, and freeing it there
 * cost KITTI 07 map klt height scale drift 1.119 -> 1.168 and map orb height direction 3.88 ->
 * 4.72 deg (BENCHMARKS.md). Freeing it with free scale: mvod-synth's KITTI 00 t_rel 5.95 ->
 * 4.49 %. How many are held (n_held: 3 with KLT, 2 with descriptors): mapvo.c.
 */
bool mvod_mapping_ba_held(bool free_scale, int n_held, int nk, int i)
{
	if (nk == 2)
		return i == 0 || (i == 1 && !free_scale);
	return i < n_held && i < nk - 1;
}

/* The window into j: poses of the nk keyframes, points seen twice or more, observations. */
static void snapshot(struct mvod_mapvo *mv, int nk, struct mvod_ba_job *j)
{
	for (int i = 0; i < nk; i++) {
		const struct mvod_map_keyframe *k = mvod_map_keyframe(mv->map, mv->kfs[i]);
		mvod_rot_log(k->Rcw, j->poses + 6 * i);
		memcpy(j->poses + 6 * i + 3, k->tcw, sizeof(k->tcw));
		j->fixed[i] = mvod_mapping_ba_held(mv->free_scale, mv->n_held, nk, i);
		j->kf[i] = mv->kfs[i];
	}
	int np = mvod_map_points(mv->map, mv->ids, mv->mp.point_cap), nb = 0, no = 0;
	for (int i = 0; i < np; i++) {
		const struct mvod_map_point *pt = mvod_map_point(mv->map, mv->ids[i]);
		if (pt->n_obs < 2)
			continue;
		for (int o = 0; o < pt->n_obs; o++) {
			const struct mvod_map_keyframe *k = mvod_map_keyframe(mv->map, pt->obs[o].kf);
			const struct mvod_map_kp *kp = &k->kp[pt->obs[o].kp];
			j->obs[no] = (struct mvod_ba_obs){kf_index(mv, nk, pt->obs[o].kf), nb, kp->x,
							  kp->y, mvod_mapvo_sigma(kp->octave)};
			j->obs_kf[no++] = pt->obs[o].kf;
		}
		memcpy(j->points + 3 * nb, pt->pos, sizeof(pt->pos));
		j->pt[nb++] = mv->ids[i];
	}
	j->p = (struct mvod_ba_problem){nk, nb, no, j->poses, j->points, j->fixed, j->obs,
					j->outlier, mv->K[0], mv->K[1], mv->K[2], mv->K[3]};
	mvod_ba_options_default(&j->o);
	j->o.max_iterations = BA_ITERATIONS;
	j->o.function_tolerance = BA_FUNCTION_TOLERANCE;
	j->o.own_solver = BA_OWN_SOLVER;
}

/* A keyframe's camera-from-world pose before (Rk, tk) and after (R, t) bundle adjustment. */
struct move {
	double Rk[9], tk[3], R[9], t[3];
};

/* Camera Rc, tc keeps its pose relative to the keyframe: Rc Rk^T R, Rc Rk^T (t - tk) + tc. */
static void move_camera(const struct move *m, double Rc[9], double tc[3])
{
	double C[9], d[3], dc[3];
	mvod_mat3_mul_bt(Rc, m->Rk, C);
	mvod_mat3_mul(C, m->R, Rc);
	for (int i = 0; i < 3; i++)
		d[i] = m->t[i] - m->tk[i];
	mvod_mat3_vec(C, d, dc);
	for (int i = 0; i < 3; i++)
		tc[i] += dc[i];
}

/*
 * The tracked frame moves with the snapshot's newest keyframe, as inline, where the keyframe's
 * frame took the refined pose itself. Keyframes and points made since the snapshot stay where
 * they are: moving them rigidly with it too was worse on KITTI 07 (free scale, BA on its
 * thread: scale drift 6.1 and 9.1 in two runs, against 5.3 and 2.9 without).
 */
static void move_tracked(struct mvod_mapvo *mv, const struct mvod_ba_job *j)
{
	int last = j->p.n_poses - 1;
	const struct mvod_map_keyframe *k = last >= 0 ? mvod_map_keyframe(mv->map, j->kf[last]) : NULL;
	if (!k)
		return; /* left the map (evicted, or the map was lost) */
	struct move m;
	memcpy(m.Rk, k->Rcw, sizeof(m.Rk));
	memcpy(m.tk, k->tcw, sizeof(m.tk));
	mvod_rot_exp(j->poses + 6 * last, m.R);
	memcpy(m.t, j->poses + 6 * last + 3, sizeof(m.t));
	move_camera(&m, mv->Rcw, mv->tcw);
}

/*
 * The solution back into the map, where its ids are still alive (a stale id's set or remove
 * fails and changes nothing); outlying observations leave their points.
 */
static void apply(struct mvod_mapvo *mv, const struct mvod_ba_job *j)
{
	move_tracked(mv, j);
	for (int i = 0; i < j->p.n_poses; i++) {
		double R[9];
		mvod_rot_exp(j->poses + 6 * i, R);
		mvod_map_set_pose(mv->map, j->kf[i], R, j->poses + 6 * i + 3);
	}
	for (int i = 0; i < j->p.n_points; i++)
		mvod_map_set_point(mv->map, j->pt[i], j->points + 3 * i);
	for (int o = 0; o < j->p.n_obs; o++)
		if (j->outlier[o])
			mvod_map_remove_obs(mv->map, j->pt[j->obs[o].point], j->obs_kf[o]);
}

/* A finished bundle adjustment into the map; with wait, a running one is waited for. */
static int land(struct mvod_mapvo *mv, bool wait)
{
	struct mvod_ba_job *j;
	if (!mvod_ba_thread_take(mv->bat, wait, &j))
		return 0;
	if (j->ret)
		return j->ret;
	apply(mv, j);
	return 0;
}

/*
 * A keyframe whose predecessor's bundle adjustment is still running waits for it and lands it
 * first: skipping instead left the first keyframes of KITTI 07 (frames 18, 25, 29, in its
 * opening turn) unrefined, and its scale drift went from 1.38 (inline) to 5.3; waiting, 2.3.
 */
int mvod_mapping_ba_settle(struct mvod_mapvo *mv)
{
	return !mvod_ba_thread_job(mv->bat) ? land(mv, true) : 0;
}

int mvod_mapping_ba(struct mvod_mapvo *mv)
{
	int ret = mvod_mapping_ba_settle(mv);
	if (ret)
		return ret;
	struct mvod_ba_job *j = mvod_ba_thread_job(mv->bat);
	snapshot(mv, mvod_map_keyframes(mv->map, mv->kfs, mv->mp.kf_cap), j);
	mvod_ba_thread_post(mv->bat);
	return 0;
}

int mvod_mapping_ba_poll(struct mvod_mapvo *mv)
{
	return land(mv, mv->ba_sync);
}
