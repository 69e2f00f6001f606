/* Accuracy against ground truth. */
#ifndef MVOD_EVAL_H
#define MVOD_EVAL_H

#include <stdbool.h>

#include "mvod/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Umeyama alignment of src onto dst (n x 3 each): dst ~ s R src + t. With with_scale false,
 * s = 1 (SE(3)). Returns -EINVAL for n < 3 or degenerate input.
 */
int mvod_umeyama(const double *src, const double *dst, int n, bool with_scale, double R[9],
		 double t[3], double *s);

/* Moves the n points xyz in place to s R xyz + t (the alignment mvod_umeyama found). */
void mvod_sim3_apply(const double R[9], const double t[3], double s, double *xyz, int n);

/* Length of the path through n points (n x 3), and the farthest of them from the first. */
void mvod_path_motion(const double *xyz, int n, double *length, double *extent);

/* RMSE of dst - (s R src + t) after mvod_umeyama. */
double mvod_ate_rmse(const double *src, const double *dst, int n, const double R[9],
		     const double t[3], double s);

/* Steps per window of mvod_scale_drift: ../shared/eval.py's 20. */
#define MVOD_DRIFT_WINDOW 20

/*
 * Scale drift of a run, positions n x 3 as for mvod_umeyama, defined as ../shared/eval.py does:
 * the estimated path length over each whole window of MVOD_DRIFT_WINDOW steps divided by the
 * ground truth's (windows without ground-truth motion, <= 1 um, skipped), then the largest of
 * those ratios over the smallest. 1.0 = the scale held; a global scale cancels, so no alignment
 * is needed; INFINITY when the estimate stood still through a moving window. Returns -EINVAL
 * when no whole window has ground-truth motion (fewer than 21 frames, a standing camera) or the
 * estimate never moved.
 */
int mvod_scale_drift(const double *est, const double *gt, int n, double *drift);

/*
 * Y Euler angle of R in radians, in [-pi/2, pi/2]: atan2(-R20, sqrt(R00^2 + R10^2)), the middle
 * angle of R = Rz Ry Rx. With camera axes (y down) it is the heading change of a ground vehicle.
 * Sign as mvod_rot_exp: a rotation of +a about y gives +a.
 */
double mvod_rot_euler_y(const double R[9]);

/*
 * The bench's per-frame error of a consecutive pair (frames i-1, i; estimate e, ground truth g;
 * camera-to-world). Unlike the RPE it uses world-frame steps dt = t_i - t_{i-1}, dR = R_i R_{i-1}^T.
 */
struct mvod_frame_err {
	double r_deg; /* |mvod_rot_euler_y(dR_e dR_g^T)|, degrees: heading error only */
	double d_m;   /* |dt_g - (R_g,i R_e,i^T) dt_e|, metres */
	double e;     /* (r_deg + d_m) / (0.5 + r_deg + d_m), in [0, 1) */
	/* d_m's terms: the ground-truth step and the estimated one in its world, d_m = |gt - est| */
	double gt_step[3], est_step[3];
};
/*
 * e of the same pair with the estimate's translations multiplied by scale (a free-scale
 * estimate in metres through its Sim(3) alignment's scale): the one definition of err that
 * mvod bench and mvod run's summary share.
 */
double mvod_frame_err_scaled(const struct mvod_frame_err *fe, double scale);
void mvod_frame_err(const struct mvod_pose *e0, const struct mvod_pose *e1,
		    const struct mvod_pose *g0, const struct mvod_pose *g1,
		    struct mvod_frame_err *out);

/*
 * Errors between consecutive frames, accumulated online (no allocation); zero-initialise, add
 * each pair, finish once. Before mvod_rpe_finish the mean fields hold sums.
 */
struct mvod_rpe {
	int n;                /* pairs counted */
	double rot_deg_mean, rot_deg_max; /* full rotation angle of dR_e dR_g^T (relative poses) */
	double dir_deg_mean, dir_deg_max; /* angle between translation directions (ground-truth
					    * steps > 1 mm; a held estimate counts 90 deg) */
	int n_dir;
	double trans_pct_mean; /* |t_e - t_g| of the relative poses, % of |t_g| (steps > 1 mm) */
	int n_pct;
	/* mvod_frame_err e over the n + 1 frames: the first frame has no predecessor, e = 0 */
	double err_avg, err_max;
};

/*
 * Accumulates the errors of one consecutive pair (estimate and ground truth, camera-to-world).
 * Returns the pair's mvod_frame_err, for a caller that also keeps it per frame (the bench).
 */
struct mvod_frame_err mvod_rpe_add(struct mvod_rpe *acc, const struct mvod_pose *e0,
				   const struct mvod_pose *e1, const struct mvod_pose *g0,
				   const struct mvod_pose *g1);
void mvod_rpe_finish(struct mvod_rpe *acc);
/*
 * After mvod_rpe_finish: err_avg and err_max again, over the n pairs fe that were added, with
 * the estimate scaled (mvod_frame_err_scaled).
 */
void mvod_rpe_rescale_err(struct mvod_rpe *acc, const struct mvod_frame_err *fe, int n,
			  double scale);

/*
 * KITTI relative errors, as the official devkit (evaluate_odometry.cpp) computes them: from
 * every 10th frame, a segment of each length L = 100, 200, ..., 800 m of ground-truth path ends
 * at the first frame whose distance exceeds L (strictly); with dX = inv(X_first) X_last its error
 * is P = inv(dE) dG, t_err = |t(P)| / L, r_err = angle(P) / L (L, not the segment's actual
 * length, as the devkit does). Means over all segments of all lengths.
 */
struct mvod_kitti_rel {
	int n_segments;        /* 0 when the ground-truth path is no longer than 100 m */
	double t_rel_pct;      /* mean t_err, %; NAN without segments */
	double r_rel_deg_100m; /* mean r_err, degrees per 100 m; NAN without segments */
};
/* dist: caller-owned scratch of n doubles (cumulative ground-truth distance). */
void mvod_kitti_segments(const struct mvod_pose *est, const struct mvod_pose *gt, int n,
			 double *dist, struct mvod_kitti_rel *out);

#ifdef __cplusplus
}
#endif

#endif
