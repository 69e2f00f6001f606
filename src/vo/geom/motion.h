/*
 * Two-view geometry in plain C: cheirality among the essential-matrix decompositions,
 * midpoint triangulation, relative scale from structure, and rotation-only fits.
 * Points are normalised image coordinates (x, y) with z = 1; motion is X2 = R X1 + t.
 */
#ifndef MVOD_MOTION_H
#define MVOD_MOTION_H

#include <stdbool.h>
#include <stdint.h>

/*
 * Points farther than this many baselines (a parallax under 0.3 deg) are too close to
 * infinity to vote: their side of the camera is noise. recoverPose uses 50, which at robot
 * speeds (0.1 m per frame) drops everything beyond 5 m and leaves too few votes.
 */
#define MVOD_MOTION_MAX_DEPTH 200.0
/*
 * Only points within this many baselines (a parallax over 1 deg) are triangulated well enough
 * to carry scale from one step to the next; farther ones made free-scale drift 4x worse on
 * the KITTI paths.
 */
#define MVOD_MOTION_SCALE_DEPTH 50.0

/* E = [t]x R: the essential matrix of the motion X2 = R X1 + t. */
void mvod_motion_essential(const double R[9], const double t[3], double E[9]);
/* Sampson distance of x1 -> x2 under E (normalised units), signed; 0 when degenerate. */
double mvod_motion_sampson(const double E[9], const double x1[2], const double x2[2]);

/*
 * Depths of one correspondence along its two rays: d1 in camera 1, d2 in camera 2, from the
 * midpoint of the closest approach of the rays. False when the rays are parallel.
 */
bool mvod_triangulate_midpoint(const double R[9], const double t[3], const double x1[2],
			       const double x2[2], double *d1, double *d2);

/*
 * Resolves the fourfold ambiguity of an essential matrix: for each of (R1, t), (R1, -t),
 * (R2, t), (R2, -t), triangulates the points with mask[i] set, and keeps the candidate with
 * the most points in front of both cameras (0 < d <= MAX_DEPTH). Writes R, t, for each
 * point depth1[i] (> 0 in front, 0 otherwise; may be NULL), and the runner-up's count (may be
 * NULL). Returns the number in front.
 */
int mvod_motion_cheirality(const double R1[9], const double R2[9], const double t[3],
			   const double *x1, const double *x2, const uint8_t *mask, int n,
			   double R[9], double t_out[3], double *depth1, int *runner_up);

/*
 * Relative scale s of the current unit-baseline structure against the previous structure:
 * prev[i] and cur[i] are the same n points in the same camera frame (previous in absolute
 * units, current with |t| = 1). s = median over disjoint point pairs of
 * |prev_i - prev_j| / |cur_i - cur_j|. scratch holds n / 2 doubles. Returns -ENODATA when
 * fewer than min_pairs pairs are usable.
 */
int mvod_motion_relative_scale(const double *prev, const double *cur, int n, int min_pairs,
			       double *scratch, double *s);

/*
 * Best rotation with x2 ~ R x1 for the points with mask set (Kabsch on unit bearings), for
 * frames with no measurable translation. Returns -EINVAL for fewer than 2 points.
 */
int mvod_motion_rotation_only(const double *x1, const double *x2, const uint8_t *mask, int n,
			      double R[9]);

/* Distance in the normalised image plane between R x1 (projected) and x2; INFINITY behind. */
double mvod_motion_rotation_residual(const double R[9], const double x1[2], const double x2[2]);

/*
 * Robust rotation-only model: RANSAC over two-point Kabsch samples (a fixed sample sequence,
 * so runs repeat exactly), then two refits on the inliers (residual < thresh, normalised
 * units). Sets mask and R; returns the inlier count (0 when nothing fits).
 */
int mvod_motion_rotation_ransac(const double *x1, const double *x2, int n, double thresh,
				int iterations, uint8_t *mask, double R[9]);

/*
 * Refines a two-view motion X2 = R X1 + t (t normalised on return) on the points with mask
 * set: Levenberg-Marquardt over the rotation and the unit translation's direction (5
 * parameters) on the Sampson distance of E = [t]x R, each residual times w[i] (1 / its
 * point's sigma; NULL = all 1), with Huber's weight beyond k (normalised units), at most
 * iterations steps. Returns the steps taken (0: (R, t) was already the minimum), -EINVAL for
 * a zero t or k <= 0.
 */
int mvod_motion_refine(double R[9], double t[3], const double *x1, const double *x2,
		       const double *w, const uint8_t *mask, int n, double k, int iterations);

/*
 * Marks in mask the points whose Sampson distance under E = [t]x R, times w[i] (NULL = 1), is
 * below thresh (normalised units); returns how many.
 */
int mvod_motion_epipolar_inliers(const double R[9], const double t[3], const double *x1,
				 const double *x2, const double *w, int n, double thresh,
				 uint8_t *mask);

/*
 * The points with mask set in front of both cameras of R, t (as mvod_motion_cheirality counts
 * them); their depths in camera 1 into depth1 (0 for the others; may be NULL).
 */
int mvod_motion_depths(const double R[9], const double t[3], const double *x1, const double *x2,
		       const uint8_t *mask, int n, double *depth1);

#endif
