/*
 * Visual odometry: preprocess (resize, blur, undistort, grey), frontend (ORB or SIFT, matched
 * by brute force or FLANN with Lowe's ratio test and/or a cross-check), motion (essential matrix by
 * RANSAC, cheirality among the four decompositions, relative scale), and the pose chain.
 */
#ifndef MVOD_VO_H
#define MVOD_VO_H

#include <stdbool.h>
#include <stddef.h>

#include "mvod/calib.h"
#include "mvod/image.h"
#include "mvod/vo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

struct mvod_vo;

/*
 * cam: intrinsics at the source's resolution (width x height); the VO undistorts and scales
 * internally. All buffers are allocated here: mvod_vo_process does not allocate.
 */
int mvod_vo_create(const struct mvod_vo_params *params, const struct mvod_camera *cam,
		   struct mvod_vo **out);
void mvod_vo_destroy(struct mvod_vo *vo);

/*
 * Processes one frame. gt_position: this frame's ground-truth camera position in metres,
 * required when scale_mode is GT (NULL otherwise). Degenerate frames hold the pose and return 0
 * with res->status saying why; a negative errno means a real failure (bad image format).
 */
int mvod_vo_process(struct mvod_vo *vo, const struct mvod_image *img, const double *gt_position,
		    struct mvod_vo_result *res);

/*
 * Forgets the scene (the reference frame and its structure) after a gap in the frames, such as
 * a camera that went away and came back; the next frame starts tracking again (INITIALIZING).
 * The pose is kept, so the poses that follow continue from the last one instead of jumping to
 * the identity, and the first step after is scaled by the last step's length (constant speed),
 * as after a loss of tracking. Does not allocate.
 */
void mvod_vo_restart(struct mvod_vo *vo);

/*
 * --scale external: the distance the robot travelled (metres, from any origin) at the time of
 * the next frame given to mvod_vo_process, NAN when unknown (speed stale or missing: the
 * scale then carries on from structure in two-view mode, as the map's own unit in map mode,
 * its confidence decaying). Does not allocate.
 */
void mvod_vo_set_odometer(struct mvod_vo *vo, double metres);

#ifdef __cplusplus
}
#endif

#endif
