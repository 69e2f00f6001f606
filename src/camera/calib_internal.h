/* What the calibration readers and writers share inside src/calib/. */
#ifndef MVOD_CALIB_INTERNAL_H
#define MVOD_CALIB_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>

#include "mvod/calib.h"

/* The mount's keys in OpenCV and ROS camera files: height (m), pitch and roll (deg). */
extern const char *const mvod_calib_mount_keys[3];

/* A mount within every camera format's bounds: height in (0, MAX], pitch and roll within +-MAX. */
static inline bool mvod_calib_mount_ok(double height_m, double pitch_deg, double roll_deg)
{
	return height_m > 0 && height_m <= MVOD_MOUNT_MAX_HEIGHT_M &&
	       pitch_deg >= -MVOD_MOUNT_MAX_ANGLE_DEG && pitch_deg <= MVOD_MOUNT_MAX_ANGLE_DEG &&
	       roll_deg >= -MVOD_MOUNT_MAX_ANGLE_DEG && roll_deg <= MVOD_MOUNT_MAX_ANGLE_DEG;
}

#ifdef __cplusplus
extern "C" {
#endif

/* Whether fx, fy, cx, cy are finite and fx, fy > 0. */
bool mvod_calib_intrinsics_ok(const struct mvod_camera *c);
/*
 * Takes fx, fy, cx, cy from a row-major K, which must be [fx 0 cx; 0 fy cy; 0 0 1] with finite
 * entries and fx, fy > 0 (skew is not modelled). Returns 0 or -EINVAL; cam is untouched then.
 */
int mvod_calib_set_K(const double k[9], struct mvod_camera *cam);

/* Whether n coefficients make sense for the model (pinhole: 0 4 5 8 12 14; fisheye: 4). */
bool mvod_calib_dist_count_ok(enum mvod_cam_model model, int n);
/* The same, as words for a message. */
const char *mvod_calib_dist_counts(enum mvod_cam_model model);

/* Whether text's first line is a lens line of DSO's camera.txt (calib_dso.c). */
bool mvod_calib_is_dso(const char *text);

#ifdef __cplusplus
}
#endif

#endif
