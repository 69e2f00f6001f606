/* euroc:DIR's camera file (the EuRoC MAV, ASL, layout: mav0/camN/{data.csv,data/,sensor.yaml}). */
#ifndef MVOD_CAPTURE_EUROC_SENSOR_H
#define MVOD_CAPTURE_EUROC_SENSOR_H

#include <stddef.h>

#include "mvod/calib.h"
#include "mvod/geom.h"

/*
 * Reads a camN/sensor.yaml: the camera (pinhole with radial-tangential or equidistant
 * distortion, and its resolution) and T_BS, the camera-to-body transform (X_body =
 * body_cam * X_cam). -errno with a reason naming the file and line in err.
 */
int mvod_euroc_sensor_load(const char *path, struct mvod_camera *cam, struct mvod_pose *body_cam,
			   char *err, size_t errlen);

#endif
