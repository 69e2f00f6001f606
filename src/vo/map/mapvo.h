/*
 * Map mode (--mode map): tracking against a local map of keyframes and points.
 *
 * Until a map exists (and again after the map is lost) frames go through the two-view
 * algorithm, which keeps the pose chain going; the first two-view MOTION step with enough
 * well-triangulated points builds the map from its two frames, so the map's unit is that step's
 * length (the unit, the ground truth's with --scale gt; after a loss the old map's, through the
 * map points the last tracked frame saw, else the last speed: the scale carries over). From then on each frame's pose comes from the map (mapvo.c: predict,
 * match by projection, pose-only refinement, PnP-RANSAC to re-find) and some frames become
 * keyframes (mapping.c: triangulation against the window, culling, windowed BA).
 *
 * Everything is allocated at create; nothing per frame.
 */
#ifndef MVOD_MAPVO_H
#define MVOD_MAPVO_H

#include <stdbool.h>

#include "vo/optim/ba_thread.h"
#include "map.h"
#include "vo/geom/pnp_shim.h"
#include "project_match.h"
#include "vo/vo_internal.h"

/*
 * --scale height, map mode: after this many height measurements, the rescales of any this many
 * keyframes in a row move the map's unit by at most MAP_RESCALE_CAP (mapscale.c).
 */
#define MVOD_MAPSCALE_WINDOW 20

struct mvod_mapvo {
	struct mvod_map *map;
	struct mvod_map_params mp;
	struct mvod_pm *pm;
	struct mvod_pnp *pnp;
	/* Bundle adjustment's thread (map mode runs only with Ceres: vo.c) */
	struct mvod_ba_thread *bat;
	bool ba_sync; /* each result is waited for at the frame after its keyframe */
	bool free_scale; /* --scale auto: nothing but bundle adjustment's gauge holds the unit */
	int n_held; /* keyframes bundle adjustment holds at the old end of the window (the gauge) */
	int cap;            /* keypoints per frame (the VO's cap) */
	double K[4];        /* fx, fy, cx, cy of the preprocessed image */
	/* The current frame, in the map's form: keypoints, and the point each one tracks. */
	struct mvod_map_kp *kp;  /* [cap] */
	mvod_map_id *cur_pt;     /* [cap] */
	mvod_map_id *ref_pt;     /* [cap] the same for the reference frame (vo->ref) */
	/*
	 * --frontend klt: where each track of the current (reference) frame was first seen on a
	 * keyframe (keyframe id and keypoint), or kf MVOD_MAP_NONE: a track with no point yet is
	 * triangulated from there, the widest baseline it has.
	 */
	struct mvod_map_obs *cur_first, *ref_first; /* [cap] */
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
	/* Triangulation: the unmatched keypoints of two keyframes as feature sets. */
	struct mvod_features fa, fb;
	int *ia, *ib; /* [cap] keypoint index in the keyframe of each entry of fa, fb */
	mvod_map_id *kfs; /* [kf_cap] the window's keyframes */
	/* State. */
	bool active;           /* a map exists and the last frames tracked against it */
	bool had_map;          /* a map existed: later ones carry its scale */
	bool lost;             /* the map was lost, a new one is being built: state LOST */
	double Rcw[9], tcw[3]; /* the last tracked frame, camera from world */
	double vR[9], vt[3];   /* its motion from the frame before (constant-velocity model) */
	int since_kf;          /* frames since the last keyframe */
	int kf_tracked;        /* points tracked into the last keyframe (before it triangulated) */
	/*
	 * --scale height: log of the metres per map unit the filtered height measures (0: the
	 * map is metric, or as metric as the chain it was built from).
	 */
	double unit_log;
	/*
	 * --scale height's bounded gain (mapscale.c): the log rescale of each of the last
	 * MVOD_MAPSCALE_WINDOW keyframes since the first measurement (0: none), a ring written
	 * at kf_scaled's slot, and the measurements taken. Kept across a loss: the published
	 * unit carries on into the next map.
	 */
	double rescale_log[MVOD_MAPSCALE_WINDOW];
	uint64_t kf_scaled;
	int n_measured;
	/*
	 * --scale external: over the tracked frames since the last measurement that the
	 * odometer says moved, its distance (metres) and the map's steps (|vt|, map units).
	 */
	double odo_path, map_path;
};

/*
 * For the VO's camera (vo->cam) and feature cap (vo->cap); with descriptors, ORB only (-EINVAL
 * otherwise). With the KLT front end (vo->klt) the map's points ride on the tracks: a track
 * carries the id of the point it observes from frame to frame, and no descriptor is computed.
 */
int mvod_mapvo_create(const struct mvod_vo *vo, struct mvod_mapvo **out);
void mvod_mapvo_destroy(struct mvod_mapvo *mv);

/* Forgets the map (a gap in the frames, or tracking lost): two-view until a new one is made. */
void mvod_mapvo_reset(struct mvod_mapvo *mv);

/*
 * Tracks the current slot against the map when one is active. Returns 1 when the frame was
 * handled (res filled: pose, status, state); 0 when there is no map or it was just lost (the
 * map is reset, and the caller runs the two-view algorithm from the reference frame, the last
 * tracked one, whose map points in its camera are the step's structure to scale by: the pose
 * does not jump); -errno on a real failure.
 */
int mvod_mapvo_track(struct mvod_vo *vo, const double *gt, struct mvod_vo_result *res);

/*
 * A map is built from a two-view step with at least this many well-triangulated points, so a
 * reference that shares fewer tracks with the current frame can no longer give one: vo.c
 * moves it on earlier while map mode waits for a map (settle).
 */
#define MVOD_MAPVO_INIT_MIN_POINTS 100

/*
 * After a two-view estimate, before the frame settles: when it was a MOTION step with enough
 * well-triangulated points, builds the map from the step's two frames (vo->ref and vo->cur,
 * at vo->pose) and returns 1; else 0. A MOTION step without enough becomes a rotation-only
 * frame (translation held) so that parallax builds up against the kept reference (before
 * the first map, and after a loss: the last tracked frame, with the old map's points).
 */
int mvod_mapvo_init(struct mvod_vo *vo, struct mvod_vo_result *res);

/*
 * Mapping (mapping.c): the current frame, tracked at mv->Rcw, tcw, becomes a keyframe. With
 * KLT, its tracks without a point are triangulated from their first keyframe (cur_first).
 */
int mvod_mapping_keyframe(struct mvod_vo *vo, bool *added);
/*
 * Windowed bundle adjustment (mapping_ba.c), the oldest n_held keyframes held (the gauge:
 * position and scale; with free scale, only the oldest in a map's first window): posts the
 * window to the BA thread, after waiting for the last keyframe's solve and landing it when
 * that is still running.
 */
int mvod_mapping_ba(struct mvod_mapvo *mv);
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
int mvod_mapping_ba_poll(struct mvod_mapvo *mv);

/* Waits for a posted bundle adjustment and lands it: none runs on the map after this. */
int mvod_mapping_ba_settle(struct mvod_mapvo *mv);

/*
 * --scale height and external (mapscale.c), at keyframe kf, after its triangulation and
 * before bundle adjustment: lands any running bundle adjustment, measures the map's unit
 * (height: the camera's height over the road band from kf; external: the odometer's distance
 * over the map's path since the last measurement) and, when the filtered scale says the
 * map's unit has drifted, rescales the map about the current camera (about the origin at the
 * first measurement). 0 or -errno.
 */
int mvod_mapscale_keyframe(struct mvod_vo *vo, mvod_map_id kf);
/*
 * --scale external, each frame tracked against the map (after its pose and velocity are
 * set): the step from the last frame into the odometer's and the map's path when the
 * odometer says the robot moved (a standstill measures nothing); without speed at this
 * frame, the scale's confidence decays a step. Returns the frame's scale source: external
 * when the frame has speed, else map (the map keeps the last scale).
 */
enum mvod_scale_source mvod_mapscale_frame(struct mvod_vo *vo);

/* Pixel sigma of a keypoint on pyramid level octave: ORB's scale step 1.2 per level. */
double mvod_mapvo_sigma(int octave);

#endif
