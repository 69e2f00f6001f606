/*
 * The camera model helpers every layer of the VO shares: a keypoint's normalised coordinates,
 * a keypoint's pixel sigma from its ORB pyramid level, the ground's normal from the camera's
 * mount and the road band (where --scale height measures the ground) in the image. The camera
 * is the preprocessed one: pinhole, no distortion (struct mvod_camera's fx, fy, cx, cy).
 */
#ifndef MVOD_VO_CORE_CAMERA_H
#define MVOD_VO_CORE_CAMERA_H

#include <math.h>
#include <stdbool.h>

#include "mvod/calib.h"

/*
 * ORB's pyramid: each level 1.2 times smaller than the one below (OpenCV's ORB default,
 * frontend/cv_shim.cpp), so a keypoint found on level o is located 1.2^o times less precisely
 * (ORB-SLAM's sigma; matching by projection widens its radius as much: map/project_match.c).
 */
#define MVOD_ORB_SCALE 1.2

/* Pixel sigma of a keypoint on pyramid level octave (KLT's tracks are all on level 0: 1). */
static inline double mvod_orb_sigma(int octave)
{
	return pow(MVOD_ORB_SCALE, octave);
}

/* Pixel (x, y) in normalised image coordinates: ((x - cx) / fx, (y - cy) / fy). */
static inline void mvod_camera_normalise(const struct mvod_camera *c, float x, float y,
					 double out[2])
{
	out[0] = (x - c->cx) / c->fx;
	out[1] = (y - c->cy) / c->fy;
}

/*
 * The ground's normal in the camera frame (unit, pointing down) of a camera mounted with
 * pitch_deg (positive looking down: n = (cos p sin r, cos p cos r, sin p)) and roll_deg.
 */
void mvod_ground_normal(double pitch_deg, double roll_deg, double n[3]);

/*
 * The road band: the part of the ground where a car's own lane lies, where the height is
 * measured. In units of the camera's height, along the ground: from MVOD_BAND_NEAR to
 * MVOD_BAND_FAR ahead and MVOD_BAND_HALF_WIDTH to either side. Near: KITTI's image
 * bottom sees the road from 3.9 heights (6.4 m) and mvod-synth's from 3.8; 2 heights keeps
 * the band's near edge below any image. Far: 15 heights (25 m on KITTI, 10-25 baselines at
 * 1 m a step) where the depth noise of 0.3 px flow is ~1 %, a quarter of the inlier band.
 * Half width: 2 heights (3.3 m) holds the 3.5 m lane and its edges, not parked cars.
 */
#define MVOD_BAND_NEAR 2.0
#define MVOD_BAND_FAR 15.0
#define MVOD_BAND_HALF_WIDTH 2.0
/*
 * The band seen through cam (pinhole) whose ground normal is n (camera frame, unit, pointing
 * down): quad receives its 4 corners (x, y) in order around it, pixels. -EINVAL when the band
 * is not in front of the camera (a normal more than ~86 deg from down).
 */
int mvod_camera_band_quad(const struct mvod_camera *cam, const double n[3], float quad[8]);
/* Whether (x, y) lies inside or on the convex quadrilateral quad (4 corners in order). */
bool mvod_quad_contains(const float quad[8], float x, float y);

#endif
