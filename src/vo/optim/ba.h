/*
 * Map mode's windowed bundle adjustment problem: caller-owned fixed arrays of poses, points and
 * observations, its options and result. ba_lm.h solves it (Ceres's trust-region
 * Levenberg-Marquardt written for this problem); Ceres itself solves it only in the tests, as
 * the reference ba_lm.c is compared with (tests/unit/ba_ceres.cpp).
 *
 * Poses are camera-from-world, X_cam = R(r) X_world + t, stored as 6 doubles: the angle-axis
 * vector r (radians; Ceres's AngleAxisRotatePoint) then t (map units). Pinhole projection
 * without distortion (mvod's preprocessed images): u = fx X/Z + cx, v = fy Y/Z + cy.
 */
#ifndef MVOD_VO_OPTIM_BA_H
#define MVOD_VO_OPTIM_BA_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

struct mvod_ba_obs {
	int pose, point; /* indices into the problem's poses and points */
	double u, v;     /* measured pixel */
	/*
	 * Standard deviation of the measurement, pixels: ORB-SLAM's 1.2^octave (a keypoint found
	 * on pyramid level o is located 1.2^o times less precisely). Residuals are divided by it.
	 */
	double sigma;
};

struct mvod_ba_problem {
	int n_poses, n_points, n_obs;
	double *poses;            /* [n_poses * 6], refined in place */
	double *points;           /* [n_points * 3] world, refined in place */
	const uint8_t *fixed;     /* [n_poses]: 1 = held (the gauge); NULL = none held */
	const struct mvod_ba_obs *obs; /* [n_obs] */
	uint8_t *outlier;         /* [n_obs] out: 1 = chi2 above the threshold after solving */
	double fx, fy, cx, cy;    /* pixels */
};

struct mvod_ba_options {
	/*
	 * Huber delta in sigma units (= pixels at octave 0): ORB-SLAM's sqrt(5.991) = 2.45, the
	 * 95 % quantile of a 2-dof chi2; residuals beyond it weigh linearly, not quadratically.
	 */
	double huber;
	int max_iterations;  /* Levenberg-Marquardt iterations */
	/*
	 * Levenberg-Marquardt also stops once a step changes the cost by less than this share
	 * of it (Ceres's function_tolerance); 0: Ceres's default, 1e-6.
	 */
	double function_tolerance;
	double chi2_outlier; /* squared residual in sigma units above which an observation is
			      * flagged (5.991: 95 % of inliers with 1-sigma noise pass) */
};

struct mvod_ba_result {
	double initial_cost, final_cost; /* Ceres's 0.5 sum rho(|r / sigma|^2) */
	int iterations;
	int n_outliers;  /* flagged, including those behind a camera before solving */
	bool converged;  /* Ceres stopped on a tolerance, not on the iteration limit */
};

static inline void mvod_ba_options_default(struct mvod_ba_options *o)
{
	o->huber = 2.4477; /* sqrt(5.991) */
	o->max_iterations = 10;
	o->function_tolerance = 0;
	o->chi2_outlier = 5.991;
}

#ifdef __cplusplus
}
#endif

#endif
