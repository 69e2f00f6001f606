/*
 * Ids of map mode's keyframes and points (slot + generation, map/map.h), which frames (their
 * point ids: core/frame.h) and bundle adjustment's jobs (optim/ba_thread.h) hold too: a stale
 * id (its slot reused since) finds nothing, so no pointer into the map outlives a change.
 */
#ifndef MVOD_VO_CORE_ID_H
#define MVOD_VO_CORE_ID_H

#include <stdint.h>

/* Id: generation (>= 1) in the high 32 bits, slot in the low 32; 0 is never an id. */
typedef uint64_t mvod_map_id;
#define MVOD_MAP_NONE ((mvod_map_id)0)

/* An observation: keypoint kp of keyframe kf. */
struct mvod_map_obs {
	mvod_map_id kf;
	int kp; /* keypoint index in that keyframe */
};

#endif
