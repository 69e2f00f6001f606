/*
 * The frame poses go out in (LCM and trajectory; the evaluation keeps the camera's): the
 * camera's own optical frame, or a robot body frame in ROS's convention (REP 103: x forward,
 * y left, z up), placed on the robot by an optional camera-to-body extrinsic.
 */
#ifndef MVOD_BODY_FRAME_H
#define MVOD_BODY_FRAME_H

#include <stdbool.h>
#include <stddef.h>

#include "mvod/geom.h"
#include "mvod/status.h"

struct mvod_body_frame {
	bool body;              /* false: camera poses go out as they are */
	struct mvod_pose bc;    /* camera-to-body: X_body = R X_cam + t, t in metres */
};

/*
 * axes camera: no change, and camera_to_body must be NULL. axes ros: the body's poses, world =
 * the body frame at the first frame; camera_to_body "x,y,z,qx,qy,qz,qw" (the camera optical
 * frame's pose in the body frame, metres, in the order of ROS's static_transform_publisher) or
 * NULL for a level camera looking forward at the body's origin. -EINVAL with why in err.
 */
int mvod_body_frame_init(enum mvod_axes axes, const char *camera_to_body,
			 struct mvod_body_frame *bf, char *err, size_t errlen);

/*
 * Whether camera_to_body is an extrinsic mvod_body_frame_init takes (for the configuration, so
 * that a bad value is a usage error): 0, or -EINVAL with what it takes in err.
 */
int mvod_body_frame_check(const char *camera_to_body, char *err, size_t errlen);

/*
 * out = the pose to publish for camera-to-world cam: T_bc cam T_cb, the extrinsic's
 * translation in output units (metres / unit_m; unit_m = metres per unit, 1 when unknown).
 * out may alias cam.
 */
void mvod_body_frame_apply(const struct mvod_body_frame *bf, const struct mvod_pose *cam,
			   double unit_m, struct mvod_pose *out);

#endif
