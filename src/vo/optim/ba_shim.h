/*
 * The Ceres door of map mode: windowed bundle adjustment over caller-owned fixed arrays.
 * Plain C. Without Ceres (meson -Dceres=disabled, or libceres-dev absent) ba_none.c says so
 * (mvod_ba_present false, -ENOTSUP to every call), and map mode is not run
 * (vo.c, mvod_vo_run_mode).
 *
 * Poses are camera-from-world, X_cam = R(r) X_world + t, stored as 6 doubles: the angle-axis
 * vector r (radians; Ceres's AngleAxisRotatePoint) then t (map units). Pinhole projection
 * without distortion (mvod's preprocessed images): u = fx X/Z + cx, v = fy Y/Z + cy.
 */
#ifndef MVOD_BA_SHIM_H
#define MVOD_BA_SHIM_H

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
	/*
	 * Who solves in mvod_ba_thread (ba_thread.h): false Ceres (mvod_ba_solve), true
	 * ba_lm.c's own Levenberg-Marquardt (mvod_ba_lm_solve). mvod_ba_solve ignores it.
	 */
	bool own_solver;
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
	o->own_solver = false;
}

/* Whether bundle adjustment is built in (Ceres); without it vo.c runs map mode as two-view. */
extern const bool mvod_ba_present;

struct mvod_ba;
/* -ENOTSUP when built without Ceres. */
int mvod_ba_create(struct mvod_ba **out);
/*
 * Solves p in place. An observation whose point is behind its camera before solving is
 * flagged and left out. Poses not held and points observed are refined; the others are left
 * as they are. -EINVAL for an index out of range or a sigma <= 0; -EIO when Ceres fails.
 */
int mvod_ba_solve(struct mvod_ba *ba, const struct mvod_ba_problem *p,
		  const struct mvod_ba_options *o, struct mvod_ba_result *r);
void mvod_ba_destroy(struct mvod_ba *ba);

/*
 * For tests: the reprojection residual of observation o (its pose and point indices unused)
 * at pose and X, with the hand-written Jacobians bundle adjustment uses and with Ceres's
 * AutoDiff; how many of the 2 residuals and 18 Jacobian entries differ (a zero's sign aside), or
 * -1 when one of them evaluates and the other does not. *evaluated: both did (the point is in
 * front of the camera). -ENOTSUP without Ceres.
 */
int mvod_ba_jacobian_mismatches(const double pose[6], const double X[3],
				const struct mvod_ba_obs *o, double fx, double fy, double cx,
				double cy, bool *evaluated);

#ifdef __cplusplus
}
#endif

#endif
