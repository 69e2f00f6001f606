/*
 * The VO below its detector: the same matching, two-view estimate and state machine as
 * mvod_vo_process, fed with features instead of an image. Used by tests/unit/test_vo.c to
 * assert the state machine on synthetic projections, and ready for a front end that brings its
 * own features (KLT tracks).
 */
#ifndef MVOD_VO_SEAM_H
#define MVOD_VO_SEAM_H

#include <stdbool.h>

#include "mvod/vo.h"
#include "vo/core/types.h"

/*
 * Processes one frame's features: f->kp in pixels of the VO's camera (the one given to
 * mvod_vo_create, when resize is 1: the preprocessing does not touch keypoints given here),
 * f->desc of the VO's detector's size. f is copied (borrowed for the call). Stage times of
 * preprocessing and detection are 0. -EINVAL when f has more features than the VO's capacity
 * (max_features + max_features / 4 + 16), descriptors of another size, or a VO with
 * the KLT front end, which tracks images, not features; otherwise as
 * mvod_vo_process.
 */
int mvod_vo_process_features(struct mvod_vo *vo, const struct mvod_features *f,
			     const double *gt_position, struct mvod_vo_result *res);

/*
 * The VO's own pose (camera-to-world), which mvod_vo_result's hides while --scale height or
 * external has no measurement yet: for tests of what the chain does before it is published.
 */
const struct mvod_pose *mvod_vo_seam_pose(const struct mvod_vo *vo);
/* Whether the VO runs map mode (has a map, or is waiting for one). */
bool mvod_vo_seam_has_map(const struct mvod_vo *vo);

#endif
