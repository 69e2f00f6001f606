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

/* Index of kf among the window's keyframes (mv->kfs, nk of them), or -1. */
static int kf_index(const struct mvod_mapvo *mv, int nk, mvod_map_id kf)
{
	for (int i = 0; i < nk; i++)
		if (mv->kfs[i] == kf)
			return i;
	return -1;
}

/* The window into j: poses of the nk keyframes, points seen twice or more, observations. */
static void snapshot(struct mvod_mapvo *mv, int nk, struct mvod_ba_job *j)
{
	for (int i = 0; i < nk; i++) {
		const struct mvod_map_keyframe *k = mvod_map_keyframe(mv->map, mv->kfs[i]);
		mvod_rot_log(k->Rcw, j->poses + 6 * i);
		memcpy(j->poses + 6 * i + 3, k->tcw, sizeof(k->tcw));
		j->fixed[i] = i < 2; /* the gauge: position, orientation and scale */
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
}

/*
 * The tracked frame keeps its pose relative to keyframe kf as bundle adjustment moves kf to
 * R, t (all camera from world): Rc' = Rc Rk^T R, tc' = Rc Rk^T (t - tk) + tc. Inline, the
 * keyframe's frame took the refined pose itself; this is the same for it, and for the frames
 * tracked since, it moves them with their keyframe.
 */
static void follow(struct mvod_mapvo *mv, mvod_map_id kf, const double R[9], const double t[3])
{
	const struct mvod_map_keyframe *k = mvod_map_keyframe(mv->map, kf);
	if (!k)
		return; /* left the map (evicted, or the map was lost) */
	double C[9], d[3], dc[3];
	mvod_mat3_mul_bt(mv->Rcw, k->Rcw, C);
	mvod_mat3_mul(C, R, mv->Rcw);
	for (int i = 0; i < 3; i++)
		d[i] = t[i] - k->tcw[i];
	mvod_mat3_vec(C, d, dc);
	for (int i = 0; i < 3; i++)
		mv->tcw[i] += dc[i];
}

/*
 * The solution back into the map, where its ids are still alive (a stale id's set or remove
 * fails and changes nothing); outlying observations leave their points.
 */
static void apply(struct mvod_mapvo *mv, const struct mvod_ba_job *j)
{
	for (int i = j->p.n_poses - 1; i >= 0; i--) {
		double R[9];
		mvod_rot_exp(j->poses + 6 * i, R);
		if (i == j->p.n_poses - 1)
			follow(mv, j->kf[i], R, j->poses + 6 * i + 3);
		mvod_map_set_pose(mv->map, j->kf[i], R, j->poses + 6 * i + 3);
	}
	for (int i = 0; i < j->p.n_points; i++)
		mvod_map_set_point(mv->map, j->pt[i], j->points + 3 * i);
	for (int o = 0; o < j->p.n_obs; o++)
		if (j->outlier[o])
			mvod_map_remove_obs(mv->map, j->pt[j->obs[o].point], j->obs_kf[o]);
}

int mvod_mapping_ba(struct mvod_mapvo *mv)
{
	if (!mv->bat)
		return 0;
	struct mvod_ba_job *j = mvod_ba_thread_job(mv->bat);
	if (!j)
		return 0; /* the last keyframe's is still running: the next keyframe has one */
	snapshot(mv, mvod_map_keyframes(mv->map, mv->kfs, mv->mp.kf_cap), j);
	mvod_ba_thread_post(mv->bat);
	return 0;
}

int mvod_mapping_ba_poll(struct mvod_mapvo *mv)
{
	struct mvod_ba_job *j;
	if (!mv->bat || !mvod_ba_thread_take(mv->bat, mv->ba_sync, &j))
		return 0;
	if (j->ret)
		return j->ret;
	apply(mv, j);
	return 0;
}
