/*
 * Map mode's windowed bundle adjustment, run on its own thread (ba_thread.h): at a keyframe
 * the window is copied into the thread's job and posted; at the start of a later frame the
 * result is written back into the map. Everything in between, the frame thread tracks on.
 */
#include <string.h>

#include "internal.h"
#include "mvod/geom.h"
#include "vo/core/camera.h"

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

/* Index of kf among the window's keyframes (m->kfs, nk of them), or -1. */
static int kf_index(const struct mvod_mapmode *m, int nk, mvod_map_id kf)
{
	for (int i = 0; i < nk; i++)
		if (m->kfs[i] == kf)
			return i;
	return -1;
}

/*
 * The gauge (internal.h): the oldest n_held keyframes held (never the newest), but in a map's
 * first window (its two keyframes) with free scale only the oldest. The second keyframe's pose
 * there is the two-view step's (essential matrix, length from the old map or the last speed),
 * never refined against the map's points: held, its rotation and direction stay as the step
 * left them for the whole map. Freed, they are refined; its distance (the map's unit, which two
 * keyframes alone do not observe) moves by what Levenberg-Marquardt's steps leave in that
 * direction, 0.1-1.2 % on KITTI 07. Free scale only: with --scale gt the step lengths come from
 * the truth and with --scale height the map is rescaled at its keyframes, and freeing it there
 * cost KITTI 07 map klt height scale drift 1.119 -> 1.168 and map orb height direction 3.88 ->
 * 4.72 deg (BENCHMARKS.md). Freeing it with free scale: mvod-synth's KITTI 00 t_rel 5.95 ->
 * 4.49 %. How many are held (n_held: 3 with KLT, 2 with descriptors): mapmode.c.
 */
bool mvod_mapping_ba_held(bool free_scale, int n_held, int nk, int i)
{
	if (nk == 2)
		return i == 0 || (i == 1 && !free_scale);
	return i < n_held && i < nk - 1;
}

/* The window into j: poses of the nk keyframes, points seen twice or more, observations. */
static void snapshot(struct mvod_mapmode *m, int nk, struct mvod_ba_job *j)
{
	for (int i = 0; i < nk; i++) {
		const struct mvod_map_keyframe *k = mvod_map_keyframe(m->map, m->kfs[i]);
		mvod_rot_log(k->Rcw, j->poses + 6 * i);
		memcpy(j->poses + 6 * i + 3, k->tcw, sizeof(k->tcw));
		j->fixed[i] = mvod_mapping_ba_held(m->free_scale, m->n_held, nk, i);
		j->kf[i] = m->kfs[i];
	}
	int np = mvod_map_points(m->map, m->ids, m->mp.point_cap), nb = 0, no = 0;
	for (int i = 0; i < np; i++) {
		const struct mvod_map_point *pt = mvod_map_point(m->map, m->ids[i]);
		if (pt->n_obs < 2)
			continue;
		for (int o = 0; o < pt->n_obs; o++) {
			const struct mvod_map_keyframe *k = mvod_map_keyframe(m->map, pt->obs[o].kf);
			const struct mvod_map_kp *kp = &k->kp[pt->obs[o].kp];
			j->obs[no] = (struct mvod_ba_obs){kf_index(m, nk, pt->obs[o].kf), nb, kp->x,
							  kp->y, mvod_orb_sigma(kp->octave)};
			j->obs_kf[no++] = pt->obs[o].kf;
		}
		memcpy(j->points + 3 * nb, pt->pos, sizeof(pt->pos));
		j->pt[nb++] = m->ids[i];
	}
	j->p = (struct mvod_ba_problem){nk, nb, no, j->poses, j->points, j->fixed, j->obs,
					j->outlier, m->K[0], m->K[1], m->K[2], m->K[3]};
	mvod_ba_options_default(&j->o);
	j->o.max_iterations = BA_ITERATIONS;
	j->o.function_tolerance = BA_FUNCTION_TOLERANCE;
}

/*
 * The tracked frame moves with the snapshot's newest keyframe, as inline, where the keyframe's
 * frame took the refined pose itself. Keyframes and points made since the snapshot stay where
 * they are: moving them rigidly with it too was worse on KITTI 07 (free scale, BA on its
 * thread: scale drift 6.1 and 9.1 in two runs, against 5.3 and 2.9 without).
 */
static void move_tracked(struct mvod_mapmode *m, const struct mvod_ba_job *j)
{
	int last = j->p.n_poses - 1;
	const struct mvod_map_keyframe *k = last >= 0 ? mvod_map_keyframe(m->map, j->kf[last]) : NULL;
	if (!k)
		return; /* left the map (evicted, or the map was lost) */
	double R[9];
	mvod_rot_exp(j->poses + 6 * last, R);
	mvod_tracked_follow(&m->cam, k->Rcw, k->tcw, R, j->poses + 6 * last + 3);
}

/*
 * The solution back into the map, where its ids are still alive (a stale id's set or remove
 * fails and changes nothing); outlying observations leave their points.
 */
static void apply(struct mvod_mapmode *m, const struct mvod_ba_job *j)
{
	move_tracked(m, j);
	for (int i = 0; i < j->p.n_poses; i++) {
		double R[9];
		mvod_rot_exp(j->poses + 6 * i, R);
		mvod_map_set_pose(m->map, j->kf[i], R, j->poses + 6 * i + 3);
	}
	for (int i = 0; i < j->p.n_points; i++)
		mvod_map_set_point(m->map, j->pt[i], j->points + 3 * i);
	for (int o = 0; o < j->p.n_obs; o++)
		if (j->outlier[o])
			mvod_map_remove_obs(m->map, j->pt[j->obs[o].point], j->obs_kf[o]);
}

/* A finished bundle adjustment into the map; with wait, a running one is waited for. */
static int land(struct mvod_mapmode *m, bool wait)
{
	struct mvod_ba_job *j;
	if (!mvod_ba_thread_take(m->bat, wait, &j))
		return 0;
	if (j->ret)
		return j->ret;
	apply(m, j);
	return 0;
}

/*
 * A keyframe whose predecessor's bundle adjustment is still running waits for it and lands it
 * first: skipping instead left the first keyframes of KITTI 07 (frames 18, 25, 29, in its
 * opening turn) unrefined, and its scale drift went from 1.38 (inline) to 5.3; waiting, 2.3.
 */
int mvod_mapping_ba_settle(struct mvod_mapmode *m)
{
	return !mvod_ba_thread_job(m->bat) ? land(m, true) : 0;
}

int mvod_mapping_ba(struct mvod_mapmode *m)
{
	int ret = mvod_mapping_ba_settle(m);
	if (ret)
		return ret;
	struct mvod_ba_job *j = mvod_ba_thread_job(m->bat);
	snapshot(m, mvod_map_keyframes(m->map, m->kfs, m->mp.kf_cap), j);
	mvod_ba_thread_post(m->bat);
	return 0;
}

int mvod_mapping_ba_poll(struct mvod_mapmode *m)
{
	return land(m, m->ba_sync);
}
