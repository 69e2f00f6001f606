/*
 * The local map of map mode: a ring of keyframes (the bundle-adjustment window) and a pool of
 * map points, both sized at create; nothing is allocated afterwards. Keyframes and points refer
 * to each other by id (slot + generation), never by pointer: when a slot is reused its
 * generation changes, so an id kept from before is stale and its lookup returns NULL.
 *
 * Poses are camera-from-world (X_cam = Rcw X_world + tcw), the form projection and bundle
 * adjustment use directly; mvod_pose (geom.h) is the inverse, camera-to-world.
 *
 * Every observation is stored twice and kept consistent by this module alone: the keyframe's
 * keypoint k names the point it sees (pt[k]), and the point lists (keyframe, k). A keyframe
 * observes a point at most once, so a point has at most kf_cap observations, all in the window:
 * when a keyframe leaves the ring its observations leave the points.
 */
#ifndef MVOD_MAP_H
#define MVOD_MAP_H

#include <stdbool.h>
#include <stdint.h>

#include "vo/core/id.h"

#define MVOD_MAP_DESC_BYTES 32 /* ORB */

/* A keypoint as map mode needs it: position in pixels, pyramid level (scale 1.2^octave). */
struct mvod_map_kp {
	float x, y;
	float response; /* detector score, for choosing among keypoints */
	int octave;     /* 0 = full resolution */
};

struct mvod_map_params {
	int kf_cap;    /* keyframes in the window (ring size), >= 2 */
	int kp_cap;    /* keypoints per keyframe */
	int point_cap; /* map points */
	/*
	 * Culling (ORB-SLAM's LocalMapping::MapPointCulling): a point in its probation (created
	 * less than 3 keyframes ago) is culled when found / visible < min_found_ratio (0.25 in
	 * ORB-SLAM: it is predicted in view but matched less than a quarter of the time, so it is
	 * probably a wrong triangulation or a moving thing), or, from 2 keyframes after its
	 * creation, when it has fewer than min_obs observations (3 in ORB-SLAM monocular: two rays
	 * always intersect, only a third keyframe confirms the point).
	 */
	double min_found_ratio;
	int min_obs;
	/*
	 * After a keyframe leaves the window, its points with fewer observations than this are
	 * erased (2: a point seen by one keyframe only has no depth constraint left in BA).
	 */
	int min_obs_keep;
};

/* ORB-SLAM's values above; sizes for KITTI: 7 keyframes of 2000 keypoints, 20 000 points. */
void mvod_map_params_default(struct mvod_map_params *p);

/* Read-only views; change them only through the functions below. */
struct mvod_map_keyframe {
	mvod_map_id id;
	uint64_t seq;     /* 0, 1, 2... in order of addition */
	int64_t utime;    /* source timestamp, microseconds */
	double Rcw[9];    /* camera from world, row-major */
	double tcw[3];    /* same units as the points (the map's scale) */
	int n;            /* keypoints */
	struct mvod_map_kp *kp; /* [kp_cap] */
	uint8_t *desc;    /* [kp_cap * 32] */
	mvod_map_id *pt;  /* [kp_cap]: the point keypoint k observes, or MVOD_MAP_NONE */
};

struct mvod_map_point {
	mvod_map_id id;
	double pos[3];                      /* world frame, map units */
	uint8_t desc[MVOD_MAP_DESC_BYTES]; /* representative descriptor */
	mvod_map_id created_by;             /* keyframe (may be stale by now) */
	uint64_t created_seq;               /* that keyframe's seq */
	uint32_t visible, found;            /* predicted in view / matched, for culling */
	int n_obs;
	struct mvod_map_obs *obs; /* [kf_cap] */
};

/* What add_keyframe copies in. */
struct mvod_map_kf_in {
	int64_t utime;
	double Rcw[9], tcw[3];
	int n;
	const struct mvod_map_kp *kp; /* [n] */
	const uint8_t *desc;          /* [n * 32] */
};

struct mvod_map_stats {
	int evicted_kf;    /* keyframes that left the ring (0 or 1) */
	int erased_points; /* points erased by eviction or culling */
};

struct mvod_map;

/* -EINVAL for bad params (message-free: the caller names them), -ENOMEM. */
int mvod_map_create(struct mvod_map **out, const struct mvod_map_params *p);
void mvod_map_destroy(struct mvod_map *m);

/* Empties the map: every keyframe and point leaves; ids kept from before are stale. */
void mvod_map_reset(struct mvod_map *m);

/*
 * Copies a keyframe in (no keypoint observes a point yet). When the ring is full the oldest
 * keyframe is evicted first: its observations leave their points, and points left with fewer
 * than min_obs_keep observations are erased (counted in st, which may be NULL).
 * -EINVAL when in->n exceeds kp_cap.
 */
int mvod_map_add_keyframe(struct mvod_map *m, const struct mvod_map_kf_in *in, mvod_map_id *out,
			  struct mvod_map_stats *st);
/* NULL for a stale or unknown id. */
const struct mvod_map_keyframe *mvod_map_keyframe(const struct mvod_map *m, mvod_map_id id);
int mvod_map_set_pose(struct mvod_map *m, mvod_map_id kf, const double Rcw[9],
		      const double tcw[3]);
/*
 * Scales the whole map by s (> 0) about centre (world frame): every point and every keyframe's
 * centre moves to centre + s (X - centre); observations and rotations stay (a map's unit is
 * free: its reprojections do not change). -EINVAL for s not finite and positive.
 */
int mvod_map_rescale(struct mvod_map *m, const double centre[3], double s);
/* The window's keyframes, oldest first; returns how many (<= cap). */
int mvod_map_keyframes(const struct mvod_map *m, mvod_map_id *ids, int cap);
int mvod_map_n_keyframes(const struct mvod_map *m);

/*
 * A new point with no observations, created by keyframe kf (a live one). -ENOSPC when the pool
 * is full (nothing changed), -ENOENT for a stale kf.
 */
int mvod_map_add_point(struct mvod_map *m, const double pos[3],
		       const uint8_t desc[MVOD_MAP_DESC_BYTES], mvod_map_id kf, mvod_map_id *out);
const struct mvod_map_point *mvod_map_point(const struct mvod_map *m, mvod_map_id id);
int mvod_map_set_point(struct mvod_map *m, mvod_map_id pt, const double pos[3]);
/*
 * Sets the point's descriptor to that of its observation with the least median Hamming
 * distance to the others (ORB-SLAM's ComputeDistinctiveDescriptors), after observations
 * change. Unchanged without observations.
 */
int mvod_map_update_desc(struct mvod_map *m, mvod_map_id pt);
/* visible += n_visible, found += n_found (Tracking's IncreaseVisible / IncreaseFound). */
int mvod_map_count(struct mvod_map *m, mvod_map_id pt, int n_visible, int n_found);
/* Removes the point and all its observations; its slot becomes free (its id stale). */
int mvod_map_erase_point(struct mvod_map *m, mvod_map_id pt);
/*
 * Live points in slot order; returns how many (<= cap). These are the window's points: every
 * observation is from a keyframe in the ring (those of evicted keyframes are removed), so only
 * a point just added and not yet observed has none.
 */
int mvod_map_points(const struct mvod_map *m, mvod_map_id *ids, int cap);
int mvod_map_n_points(const struct mvod_map *m);

/*
 * Keypoint kp of keyframe kf observes point pt. -ENOENT stale id, -EINVAL kp out of range,
 * -EEXIST when that keypoint already observes a point or kf already observes pt.
 */
int mvod_map_add_obs(struct mvod_map *m, mvod_map_id pt, mvod_map_id kf, int kp);
/* -ENOENT when an id is stale or kf does not observe pt. The point stays, even with none. */
int mvod_map_remove_obs(struct mvod_map *m, mvod_map_id pt, mvod_map_id kf);

/*
 * Merges drop into keep (ORB-SLAM's MapPoint::Replace): drop's observations move to keep unless
 * keep is already seen by that keyframe (then that keypoint is freed), counters add, drop is
 * erased. -EINVAL when keep == drop.
 */
int mvod_map_fuse(struct mvod_map *m, mvod_map_id keep, mvod_map_id drop);

/* Applies the culling rules of mvod_map_params to every point; counts erasures in st. */
int mvod_map_cull(struct mvod_map *m, struct mvod_map_stats *st);

/*
 * Checks every invariant (both sides of each observation agree, ids live, no keyframe twice in
 * a point, the free list and live slots partition the pool). 0 or -EUCLEAN. For tests.
 */
int mvod_map_check(const struct mvod_map *m);

#endif
