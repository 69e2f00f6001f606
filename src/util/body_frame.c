#include "util/body_frame.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/errbuf.h"

/* ROS body axes in the camera's: x = forward = camera z, y = left = -camera x, z = up = -camera y. */
static const double ROS_FROM_CAMERA[9] = {0, 0, 1, -1, 0, 0, 0, -1, 0};

/* What --camera-to-body takes, for messages. */
static const char EXTRINSIC[] = "7 numbers x,y,z,qx,qy,qz,qw: the camera optical frame's "
				"position (metres) and unit quaternion in the body frame, e.g. "
				"0,0,0,-0.5,0.5,-0.5,0.5 for a level camera looking forward";

/* The 7 numbers of "x,y,z,qx,qy,qz,qw" into bc; -EINVAL with what it takes in err. */
static int parse_extrinsic(const char *text, struct mvod_pose *bc, char *err, size_t errlen)
{
	double v[7];
	const char *p = text;
	for (int i = 0; i < 7; i++) {
		char *end;
		v[i] = strtod(p, &end);
		if (end == p || !isfinite(v[i]) || *end != (i < 6 ? ',' : '\0'))
			return mvod_errf(err, errlen, -EINVAL, "%s", EXTRINSIC);
		p = end + 1;
	}
	double norm = sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
	/* A quaternion read from a file is unit to its digits; far from 1, it is something else. */
	if (fabs(norm - 1.0) > 1e-3)
		return mvod_errf(err, errlen, -EINVAL, "%s (this quaternion's norm is %g)",
				 EXTRINSIC, norm);
	const double q[4] = {v[6], v[3], v[4], v[5]}; /* w, x, y, z */
	mvod_quat_to_rot(q, bc->R);
	for (int k = 0; k < 3; k++)
		bc->t[k] = v[k];
	return 0;
}

int mvod_body_frame_check(const char *camera_to_body, char *err, size_t errlen)
{
	struct mvod_pose bc;
	return parse_extrinsic(camera_to_body, &bc, err, errlen);
}

int mvod_body_frame_init(enum mvod_axes axes, const char *camera_to_body,
			 struct mvod_body_frame *bf, char *err, size_t errlen)
{
	*bf = (struct mvod_body_frame){.body = axes == MVOD_AXES_ROS};
	if (!bf->body && camera_to_body)
		return mvod_errf(err, errlen, -EINVAL, "--camera-to-body %s places a body frame, but "
				 "--frame is camera: pass --frame ros to publish the body's poses, "
				 "or drop --camera-to-body", camera_to_body);
	if (!bf->body)
		return 0;
	mvod_pose_identity(&bf->bc);
	memcpy(bf->bc.R, ROS_FROM_CAMERA, sizeof(bf->bc.R));
	char want[256];
	if (camera_to_body && parse_extrinsic(camera_to_body, &bf->bc, want, sizeof(want)))
		return mvod_errf(err, errlen, -EINVAL, "--camera-to-body %s: expected %s",
				 camera_to_body, want);
	return 0;
}

void mvod_body_frame_apply(const struct mvod_body_frame *bf, const struct mvod_pose *cam,
			   double unit_m, struct mvod_pose *out)
{
	if (!bf->body) {
		*out = *cam;
		return;
	}
	struct mvod_pose bc = bf->bc, cb;
	for (int k = 0; k < 3; k++)
		bc.t[k] /= unit_m;
	mvod_pose_inverse(&bc, &cb);
	mvod_pose_compose(&bc, cam, out);
	mvod_pose_compose(out, &cb, out);
}
