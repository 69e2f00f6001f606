/*
 * Tracking against the map: a camera pose from 2D-3D matches, by OpenCV's robust PnP and a
 * pose-only refinement on the inliers. Plain C; the caller owns every array. Poses are
 * camera-from-world (X_cam = R X_world + t), as in map.h; pixels are of the preprocessed,
 * distortion-free image.
 */
#ifndef MVOD_PNP_SHIM_H
#define MVOD_PNP_SHIM_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The hypothesis generator; tests/unit/test_pnp.c measures them against each other. */
enum mvod_pnp_method {
	MVOD_PNP_RANSAC_AP3P,  /* classic RANSAC, AP3P minimal solver (4-point samples) */
	MVOD_PNP_RANSAC_EPNP,  /* classic RANSAC, EPnP on 5-point samples */
	MVOD_PNP_RANSAC_P3P,   /* classic RANSAC, Gao's P3P */
	MVOD_PNP_USAC_DEFAULT, /* OpenCV's USAC (P3P, local optimisation) */
	MVOD_PNP_USAC_MAGSAC,  /* USAC with MAGSAC++ scoring */
};

struct mvod_pnp_params {
	enum mvod_pnp_method method;
	/* RANSAC inlier threshold, pixels at octave 0: 2.45 = sqrt(5.991), ORB-SLAM's 95 % chi2
	 * gate for 1 px noise. */
	double thresh_px;
	double confidence;  /* RANSAC stopping confidence */
	int max_iterations; /* RANSAC hypotheses at most */
	/*
	 * Refinement rounds: Levenberg-Marquardt on the inliers, then the inliers chosen again by
	 * chi2 against each point's sigma with the refined pose (ORB-SLAM's PoseOptimization
	 * does 4 rounds of optimise and re-classify; a truncated quadratic loss).
	 */
	int refine_rounds;
	int min_inliers; /* fewer after refinement: -ENODATA */
};

void mvod_pnp_params_default(struct mvod_pnp_params *p);

struct mvod_pnp;
/* Scratch for up to cap matches, allocated once. */
int mvod_pnp_create(const struct mvod_pnp_params *p, int cap, struct mvod_pnp **out);
void mvod_pnp_destroy(struct mvod_pnp *pnp);

/*
 * X: n world points (n x 3), uv: their pixels (n x 2), sigma: each one's pixel sigma
 * (1.2^octave; NULL = all 1), K = fx, fy, cx, cy. Writes R, t and inlier[n] (1 = inlier after
 * refinement) and returns the inlier count. -EINVAL for n > cap or n < 4, -ENODATA when no
 * pose with min_inliers inliers is found, -EIO for an OpenCV error.
 */
int mvod_pnp_solve(struct mvod_pnp *pnp, const double *X, const double *uv,
		   const double *sigma, int n, const double K[4], double R[9], double t[3],
		   uint8_t *inlier);

/*
 * Pose-only refinement from a predicted pose (R, t in and out), without RANSAC: what tracking
 * with a constant-velocity prediction needs per frame (ORB-SLAM's TrackWithMotionModel does no
 * RANSAC either). The first round gates at 4 x thresh_px around the prediction (it may be a
 * few pixels off), the next refine_rounds at thresh_px. Same returns as mvod_pnp_solve.
 */
int mvod_pnp_refine(struct mvod_pnp *pnp, const double *X, const double *uv,
		    const double *sigma, int n, const double K[4], double R[9], double t[3],
		    uint8_t *inlier);

#ifdef __cplusplus
}
#endif

#endif
