/*
 * kitti-raw:DRIVE, a drive of the KITTI raw data as downloaded (the raw data devkit's readme;
 * pykitti's raw.py reads the same): DATE/DATE_drive_NNNN_sync/image_00/{data/,timestamps.txt},
 * oxts/data/NNNNNNNNNN.txt, and the date's calib_cam_to_cam.txt, calib_imu_to_velo.txt and
 * calib_velo_to_cam.txt beside the drive: its OXTS packets and calibration files (oxts.c), the
 * parts kitti_raw.c, tests and fuzzing reach.
 */
#ifndef MVOD_CAPTURE_OXTS_H
#define MVOD_CAPTURE_OXTS_H

#include <stddef.h>

#include "mvod/calib.h"
#include "mvod/geom.h"

/*
 * The devkit's conversion of an OXTS packet (lat, lon in degrees, alt in metres, roll, pitch,
 * yaw in radians: the first 6 of its 30 values) to the IMU's pose T_w_imu: x east, y north
 * (a Mercator projection on a sphere of 6378137 m at scale, the cosine of the drive's first
 * latitude), z up (the altitude); R = Rz(yaw) Ry(pitch) Rx(roll), the IMU x forward, y left,
 * z up (roll positive left side up, pitch positive front down, yaw 0 east, counter-clockwise).
 */
void mvod_oxts_pose(const double packet[6], double scale, struct mvod_pose *imu);
/* The Mercator scale of a drive whose first packet is at lat_deg: cos(lat). */
double mvod_oxts_scale(double lat_deg);

/*
 * One oxts/data/NNNNNNNNNN.txt: a line of 30 numbers (dataformat.txt's, the last five counts)
 * into packet's first 6. -errno with a reason naming path and line.
 */
int mvod_oxts_read(const char *path, double packet[6], char *err, size_t errlen);

/*
 * The date's calibration in dir: camera 0's rectified intrinsics (P_rect_00, size S_rect_00,
 * no distortion) from calib_cam_to_cam.txt, and cam_imu = T_cam0_imu, the IMU's pose in the
 * rectified camera 0: R_rect_00 (calib_cam_to_cam.txt) times calib_velo_to_cam.txt's R|T
 * times calib_imu_to_velo.txt's, its rotation the nearest one (the files' 7 significant
 * digits leave it 1e-7 off). -errno with a reason naming the file and line.
 */
int mvod_kitti_raw_calib(const char *dir, struct mvod_camera *cam, struct mvod_pose *cam_imu,
			 char *err, size_t errlen);

#endif
