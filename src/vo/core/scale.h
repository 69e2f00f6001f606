/*
 * Metric scale for the VO: the ground plane among triangulated points (camera height), and a
 * filter that fuses metric measurements (height, the robot's odometer) into a scale that
 * structure alone carries between them. Plain C with no state outside the caller's structs, so
 * two-view mode (twoview.c) and map mode can share it.
 */
#ifndef MVOD_VO_SCALE_H
#define MVOD_VO_SCALE_H

#include <stdbool.h>

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
 * The scale filter's own learning (mvod_scale_height_ratio) averages its first fits instead
 * (gain 1/k for the k-th, down to this gain), unless a mount was given (MVOD_GROUND_MOUNT_FITS).
 */
#define MVOD_GROUND_NORMAL_GAIN 0.1
/*
 * A mount from the camera file counts as this many fits already learnt: the normal then
 * learns at MVOD_GROUND_NORMAL_GAIN from the first fit on (1 / (9 + 1)).
 */
#define MVOD_GROUND_MOUNT_FITS 9
#define MVOD_GROUND_MAX_TURN_DEG 5.0
void mvod_ground_prior_update(double prior[3], const struct mvod_ground *g);
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
 * The band seen through a pinhole camera (pixels, fx fy cx cy) whose ground normal is n (camera
 * frame, unit, pointing down): quad receives its 4 corners (x, y) in order around it. -EINVAL
 * when the band is not in front of the camera (a normal more than ~86 deg from down).
 */
int mvod_ground_band_quad(const double n[3], double fx, double fy, double cx, double cy,
			  float quad[8]);
/* Whether (x, y) lies inside or on the convex quadrilateral quad (4 corners in order). */
bool mvod_quad_contains(const float quad[8], float x, float y);

/*
 * The scale filter: each measurement is a ratio, metric value / predicted value (for
 * two-view mode, the step length in metres / the step structure predicts). The first one is
 * taken whole; later ones move the scale by gain in log space, and a ratio beyond the gate
 * (one bad frame: a car's roof taken for the road) is refused, the gate widening with each
 * refusal in a row so that a real change is followed within a few frames.
 */
#define MVOD_SCALE_FIRST_MAX 5
struct mvod_scale_filter {
	double gain;    /* fraction of a measurement's log ratio applied, (0, 1] */
	double gate;    /* largest |log ratio| accepted; INFINITY = all */
	double quality; /* 0-1, of the last accepted measurement */
	int since;      /* steps since the last accepted measurement; -1 before the first */
	int refused;    /* measurements refused in a row */
	double ground_n[3]; /* --scale height: the ground's expected normal in the camera frame
			       (the mount's pitch and roll), from (0, 1, 0) on */
	double max_tilt_deg; /* --scale height: MVOD_GROUND_MAX_TILT_DEG at init; 180: none */
	int tilted;     /* --scale height: ground fits in a row tilted beyond max_tilt_deg
			   from ground_n */
	int normal_fits; /* --scale height: fits ground_n has learnt from (MVOD_GROUND_MOUNT_FITS
			    from a mount); the next moves it by 1 / (normal_fits + 1), at least
			    MVOD_GROUND_NORMAL_GAIN */
	/*
	 * The first scale is the median of this many measurements (1 at init, at most
	 * MVOD_SCALE_FIRST_MAX); until then the output is not metric. Their ratios are alike:
	 * metres per unit of the same chain, which structure carries between them.
	 */
	int first_n;
	int n_first;
	double first[MVOD_SCALE_FIRST_MAX];
	/*
	 * --scale height: the camera's mean direction of travel in its own frame (unit), learnt
	 * from motion steps (mvod_scale_filter_motion), and how many; ground_n is kept
	 * perpendicular to it once there is one (map mode only: mapscale.c).
	 */
	double motion[3];
	int motion_n;
};
void mvod_scale_filter_init(struct mvod_scale_filter *f, double gain, double gate);
/*
 * One step: ratio (NAN when there was no measurement) and its quality (0-1). Returns the
 * factor to multiply the prediction by (1 without an accepted measurement); *used says
 * whether a measurement was accepted.
 */
double mvod_scale_filter_step(struct mvod_scale_filter *f, double ratio, double quality,
			      bool *used);
/*
 * The same step with a gain and a gate of its own for this measurement instead of f->gain and
 * f->gate (map mode's: mapscale.c); the gate still doubles with each refusal in a row.
 */
double mvod_scale_filter_step_gain(struct mvod_scale_filter *f, double ratio, double quality,
				   double gain, double gate, bool *used);
/*
 * Fewer ground points than this give no height: three points always span a plane, and a
 * patch of road under a car's bonnet on KITTI has 15-60 of them.
 */
#define MVOD_GROUND_MIN_INLIERS 20
/*
 * The expected normal does not learn from a ground fit whose own normal is more than this from
 * it (its height along the expected normal still counts). On KITTI 07 the fits' pitch was
 * 1.9 deg on average (sd 1.3) on straight road and 4.0 deg (sd 2.7) in its two turns (3-4 deg
 * of yaw a frame: the band's far part on the kerb and pavement inside the bend); learnt, they
 * pitched the expected normal 4.5 deg and made each height 10-30 % high (steps short) through
 * the second turn and after it. Gates of 1.5, 2, 3 deg and none (BENCHMARKS.md, issue 14's
 * third section): 2 the best on both clips. While heights were the fit's own plane's, a
 * tilted fit was no measurement either; along the expected normal it is one (KITTI 07
 * two-view scale drift 1.123 -> 1.097). Two-view mode only (vo.c): in map mode it made
 * mvod-synth's whole KITTI 00 drive worse (t_rel 6.3 % -> 11.3 %).
 */
#define MVOD_GROUND_MAX_TILT_DEG 2.0
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
double mvod_scale_height_ratio(struct mvod_scale_filter *f, const double *X, int n,
			       double height_m, double *scratch, double *q);
/*
 * --scale height: a motion step's direction of travel in the current camera's frame (any
 * length; ignored when not finite, zero or backwards). The mean direction (the k-th moves it
 * by 1/k, down to MVOD_MOTION_GAIN) is parallel to the road a car drives on, so it carries the
 * camera's pitch to the road better than the ground fits do. Map mode feeds it (mapscale.c);
 * two-view mode does not: levelled with its essential matrices' directions, mvod-synth's
 * KITTI 00 drive went from t_rel 9.01 % to 11.59 %.
 */
#define MVOD_MOTION_GAIN 0.02
void mvod_scale_filter_motion(struct mvod_scale_filter *f, const double dir[3]);
/*
 * Bounded gain (map mode's rescales, mapscale.c): the log rescale s cut so that, with the n
 * recent ones (logs), the unit moves by at most cap (log) either way; 0 when they already
 * moved it that far s's way.
 */
double mvod_scale_bounded(const double *recent, int n, double s, double cap);
/* Whether any measurement was accepted yet (the output is metric). */
bool mvod_scale_filter_metric(const struct mvod_scale_filter *f);
/* 0-1: the last measurement's quality, decaying by MVOD_SCALE_DECAY per step without one. */
#define MVOD_SCALE_DECAY 0.95
double mvod_scale_filter_confidence(const struct mvod_scale_filter *f);

#endif
