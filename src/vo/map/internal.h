/*
 * Map mode's inside, shared by the files of map/ only (the facade sees map/mapmode.h): the
 * mode's state and the steps its files take for one another.
 *
 * Until a map exists (and again after the map is lost) frames go through the two-view
 * algorithm, which keeps the pose chain going; the first two-view MOTION step with enough
 * well-triangulated points builds the map from its two frames (init.c), so the map's unit is
 * that step's length (the unit, the ground truth's with --scale gt; after a loss the old
 * map's, through the map points the last tracked frame saw, else the last speed: the scale
 * carries over). From then on each frame's pose comes from the map (track.c: predict, match
 * by projection, pose-only refinement, PnP-RANSAC to re-find) and some frames become keyframes
 * (mapping.c: triangulation against the window, culling; mapping_ba.c: windowed bundle
 * adjustment on its thread; mapscale.c: the metric scale).
 *
 * Everything is allocated at create; nothing per frame.
 */
#ifndef MVOD_VO_MAP_INTERNAL_H
#define MVOD_VO_MAP_INTERNAL_H

#include <stdbool.h>

#include "map.h"
#include "project_match.h"
#include "vo/core/ctx.h"
#include "vo/core/tracked.h"
#include "vo/geom/pnp_shim.h"
#include "vo/optim/ba_thread.h"

struct mvod_mapmode {
	const struct mvod_vo_ctx *c;
	struct mvod_map *map;
	struct mvod_map_params mp;
	struct mvod_pm *pm;
	struct mvod_pnp *pnp;
	struct mvod_ba_thread *bat; /* bundle adjustment's thread */
	bool ba_sync; /* each result is waited for at the frame after its keyframe */
	bool free_scale; /* --scale auto: nothing but bundle adjustment's gauge holds the unit */
	int n_held; /* keyframes bundle adjustment holds at the old end of the window (the gauge) */
	int cap;            /* keypoints per frame (the VO's cap) */
	double K[4];        /* fx, fy, cx, cy of the preprocessed image */
	struct mvod_map_kp *kp; /* [cap] the current frame's keypoints in the map's form */
	/* The map's points gathered for a frame: ids, positions, descriptors, matches. */
	mvod_map_id *ids; /* [point_cap] */
	double *pos;      /* [point_cap * 3] */
	uint8_t *desc;    /* [point_cap * 32] */
	int *match;       /* [point_cap] */
	/* 2D-3D pairs for PnP: world point, pixel, sigma, and the local point index. */
	double *X, *uv, *sigma; /* [cap * 3], [cap * 2], [cap] */
	int *pidx;              /* [cap] */
	int n_pairs;            /* pairs of the last tracking by projection */
	uint8_t *inlier;        /* [cap] */
	/* The tracks without a point, for the pose's refinement: normalised, used, sigma. */
	double *x1, *x2;        /* [cap * 2] last frame, this one */
	uint8_t *epi_use;       /* [cap] */
	double *scratch;        /* [cap] sigmas, depths, heights */
	double *pts;            /* [cap * 3] the road band's points (mapscale.c) */
	/* Triangulation: the unmatched keypoints of two keyframes as feature sets, matched. */
	struct mvod_features fa, fb;
	int *ia, *ib; /* [cap] keypoint index in the keyframe of each entry of fa, fb */
	struct mvod_match *pair; /* [cap] their matches */
	mvod_map_id *kfs; /* [kf_cap] the window's keyframes */
	/* State. */
	bool active;           /* a map exists and the last frames tracked against it */
	bool had_map;          /* a map existed: later ones carry its scale */
	bool lost;             /* the map was lost, a new one is being built: state LOST */
	struct mvod_tracked cam; /* the last tracked frame and its velocity */
	int since_kf;          /* frames since the last keyframe */
	int kf_tracked;        /* points tracked into the last keyframe (before it triangulated) */
};

/*
 * Mapping (mapping.c): the current frame, tracked at m->cam, becomes a keyframe. With KLT,
 * its tracks without a point are triangulated from their first keyframe (the frame's first).
 * st->pose: the pose to publish, moved with the map when it is rescaled (mapscale.c).
 */
int mvod_mapping_keyframe(struct mvod_mapmode *m, struct mvod_step *st, bool *added);
/* The frame of slot k, at camera-to-world pose c2w, as a new keyframe (init.c, mapping.c). */
int mvod_mapping_add_frame(struct mvod_mapmode *m, const struct mvod_vo_frame *k,
			   const struct mvod_pose *c2w, mvod_map_id *out);
/*
 * A new point at world X seen by keypoint ja of keyframe a and jb of b; -EEXIST, and no point,
 * when either keypoint observes one already.
 */
int mvod_mapping_add_point(struct mvod_mapmode *m, const double X[3], mvod_map_id a, int ja,
			   mvod_map_id b, int jb, mvod_map_id *out);
/*
 * Whether world point X, seen by keypoint kp from camera-from-world R, t, lies in front of
 * it and within the chi-square gate in kp's sigma.
 */
bool mvod_mapping_reprojects(const double K[4], const double R[9], const double t[3],
			     const double X[3], const struct mvod_map_kp *kp);
/*
 * Windowed bundle adjustment (mapping_ba.c), the oldest n_held keyframes held (the gauge:
 * position and scale; with free scale, only the oldest in a map's first window): posts the
 * window to the BA thread, after waiting for the last keyframe's solve and landing it when
 * that is still running.
 */
int mvod_mapping_ba(struct mvod_mapmode *m);
/*
 * Whether keyframe i (0: the oldest) of a window of nk is held in bundle adjustment, for a map
 * that holds n_held at the window's old end.
 */
bool mvod_mapping_ba_held(bool free_scale, int n_held, int nk, int i);
/*
 * At the start of a frame: writes a finished bundle adjustment into the map (its keyframes and
 * points still alive) and moves the tracked pose with the newest of its keyframes. With
 * ba_sync it waits for a posted one, so a result always lands at the frame after its keyframe
 * whatever the machine's speed: runs are reproducible. The solver's error, else 0.
 */
int mvod_mapping_ba_poll(struct mvod_mapmode *m);
/* Waits for a posted bundle adjustment and lands it: none runs on the map after this. */
int mvod_mapping_ba_settle(struct mvod_mapmode *m);

/*
 * --scale height and external (mapscale.c), at keyframe kf, after its triangulation and
 * before bundle adjustment: lands any running bundle adjustment, measures the map's unit
 * (height: the camera's height over the road band from kf; external: the odometer's distance
 * over the map's path since the last measurement) and, when the filtered scale says the
 * map's unit has drifted, rescales the map (and st->pose with it) about the current camera
 * (about the origin at the first measurement). 0 or -errno.
 */
int mvod_mapscale_keyframe(struct mvod_mapmode *m, mvod_map_id kf, struct mvod_step *st);
/*
 * --scale external, each frame tracked against the map (after its pose and velocity are
 * set): the step from the last frame into the odometer's and the map's path when the
 * odometer says the robot moved (a standstill measures nothing); without speed at this
 * frame, the scale's confidence decays a step. Returns the frame's scale source: external
 * when the frame has speed, else map (the map keeps the last scale).
 */
enum mvod_scale_source mvod_mapscale_frame(struct mvod_mapmode *m);

#endif
