/*
 * The ground plane among triangulated points, and --scale height's measurement from it: the
 * camera's height over the road band's points along the scale filter's expected normal
 * (core/scale.h), which learns from the fits. Plain C, no state outside the caller's structs:
 * two-view mode and map mode measure with it.
 */
#ifndef MVOD_VO_GEOM_GROUND_H
#define MVOD_VO_GEOM_GROUND_H

#include "vo/core/scale.h"

/* The ground below the camera: the plane n . X = h, n unit, pointing from the camera down. */
struct mvod_ground {
	double n[3];  /* the inliers' own least-squares normal (for the normal's estimate) */
	double h;     /* the camera's height above them along the expected normal, in the
			 points' unit (> 0) */
	int inliers;  /* points within the inlier band */
	double c[3];  /* their centroid, in the points' unit */
};

/*
 * The ground among n points X (n x 3, camera frame, OpenCV axes: y down), any unit, given the
 * normal expected (prior, unit: the estimate over earlier frames). Only points below the
 * optical centre (y > 0) take part. The height is the one with the most points within a band
 * of +-MVOD_GROUND_BAND of it along prior (hypotheses from a fixed subsample: repeatable), then
 * the median over them; the normal is refitted to those points. scratch holds n doubles.
 * Returns 0, or -ENODATA when no height has min_inliers points.
 *
 * The normal is not fitted afresh each frame because a fit to one frame's points tilts: the
 * far ground points (20-50 baselines) are 2 % deep-noisy, and free 3-point fits on the
 * mvod-synth street came out tilted by up to 13 deg with heights 60 % off.
 */
int mvod_ground_fit(const double *X, int n, const double prior[3], int min_inliers,
		    double *scratch, struct mvod_ground *g);
/*
 * Moves the expected normal (camera pitch and roll) towards a fit's by MVOD_GROUND_NORMAL_GAIN
 * when within MVOD_GROUND_MAX_TURN_DEG of it: a slow estimate of the mount's pitch that
 * follows a car's pitching under braking (~1 deg over a second) and not one frame's noise.
 * The scale filter's own learning (mvod_ground_height_ratio) averages its first fits instead
 * (gain 1/k for the k-th, down to this gain), unless a mount was given (MVOD_GROUND_MOUNT_FITS).
 */
#define MVOD_GROUND_NORMAL_GAIN 0.1
#define MVOD_GROUND_MAX_TURN_DEG 5.0
void mvod_ground_prior_update(double prior[3], const struct mvod_ground *g);
/*
 * Fewer ground points than this give no height: three points always span a plane, and a
 * patch of road under a car's bonnet on KITTI has 15-60 of them.
 */
#define MVOD_GROUND_MIN_INLIERS 20
/*
 * Before the first scale, and after this many tilted fits in a row, the expected normal learns
 * from tilted fits too (within MVOD_GROUND_MAX_TURN_DEG): the mount's pitch, not a turn, is
 * then what differs. On mvod-synth's street seen by a camera pitched 3 deg with no mount in
 * its camera file, learning only from fits within 2 deg of level held the output for 25
 * frames (SE(3) ATE 10 % of the path in two-view mode, 16 % in map mode). KITTI 07's turns
 * gave at most 8 tilted fits in a row.
 */
#define MVOD_GROUND_TILTED_RUN 20
/*
 * --scale height's measurement: the ground among the n road-band points X (n x 3, camera
 * frame, any unit), fitted along f's expected normal, which then learns from it. Returns
 * height_m over the inliers' height (metres per unit of X), NAN when no ground was found;
 * *q the fit's quality (0-1). scratch holds n doubles.
 *
 * The height is the inliers' centroid along the expected normal, not the distance of their
 * own least-squares plane: that plane's tilt is noisy (the far band points are the noisiest)
 * and its distance is its value extrapolated from the band (2-15 heights ahead) back to the
 * camera, so each degree of tilt moved it by ~9 % (KITTI 06 and 07 two-view: the log error
 * of each step's ratio against the truth correlated with the fit's pitch at -0.91 and -0.61,
 * slope -0.11 and -0.08 per degree). At the centroid a tilt costs nothing; the expected
 * normal, learnt over many fits, carries the pitch.
 */
double mvod_ground_height_ratio(struct mvod_scale_filter *f, const double *X, int n,
				double height_m, double *scratch, double *q);

#endif
