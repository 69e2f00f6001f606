/*
 * Map mode (--mode map): tracking against a local map of keyframes and points, refined by
 * windowed bundle adjustment, what the facade (vo.c) calls of it. Where it has no map (before
 * the first, from a loss until the next) the two-view algorithm takes the frames, and a
 * two-view step with enough well-triangulated points builds the next map (mvod_mapmode_init).
 * The inside: map/internal.h.
 */
#ifndef MVOD_VO_MAP_MAPMODE_H
#define MVOD_VO_MAP_MAPMODE_H

#include <stdbool.h>

#include "vo/core/ctx.h"

struct mvod_mapmode;

/*
 * For the VO of context c (kept: it must outlive the object): its camera and keypoint cap;
 * with descriptors, ORB only (-EINVAL otherwise). With the KLT front end the map's points ride
 * on the tracks: a track carries the id of the point it observes from frame to frame, and no
 * descriptor is computed.
 */
int mvod_mapmode_create(const struct mvod_vo_ctx *c, struct mvod_mapmode **out);
void mvod_mapmode_destroy(struct mvod_mapmode *m);

/* Forgets the map (a gap in the frames, or tracking lost): two-view until a new one is made. */
void mvod_mapmode_reset(struct mvod_mapmode *m);
/* The map was lost and a new one is being built (the state is LOST until then). */
bool mvod_mapmode_lost(const struct mvod_mapmode *m);
/* The map's points and keyframes into res (every frame reports them). */
void mvod_mapmode_counts(const struct mvod_mapmode *m, struct mvod_vo_result *res);

/*
 * Tracks the current frame against the map when one is active. Returns 1 when the frame was
 * handled: res's status (MOTION: tracked, its structure the map's points it sees; or
 * FEW_FEATURES: held), counts and scale source, st->pose. 0 when there is no map or it was
 * just lost (res->map_lost: the map is reset, and the two-view algorithm takes the frame from
 * the reference, the last tracked one, whose map points in its camera are the step's structure
 * to scale by: the pose does not jump); -errno on a real failure. gt: this frame's
 * ground-truth position (--scale gt) or NULL.
 */
int mvod_mapmode_track(struct mvod_mapmode *m, const double *gt, struct mvod_vo_result *res,
		       struct mvod_step *st);

/*
 * A map is built from a two-view step with at least this many well-triangulated points, so a
 * reference that shares fewer tracks with the current frame can no longer give one: the
 * facade moves it on earlier while map mode waits for a map (vo.c, settle).
 */
#define MVOD_MAPMODE_INIT_MIN_POINTS 100

/*
 * After a two-view estimate, before the frame settles: when it was a MOTION step with enough
 * well-triangulated points, builds the map from the step's two frames (the reference and the
 * current one, at st->pose) and returns 1; else 0. A MOTION step without enough becomes a
 * rotation-only frame (res->status ROTATION, st->pose's translation held) so that parallax
 * builds up against the kept reference (before the first map, and after a loss: the last
 * tracked frame, with the old map's points).
 */
int mvod_mapmode_init(struct mvod_mapmode *m, struct mvod_vo_result *res, struct mvod_step *st);

#endif
