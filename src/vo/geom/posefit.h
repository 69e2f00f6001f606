/*
 * Map mode's pose-only refinement on KLT tracks or ORB matches: the map points' reprojection
 * errors and, for the tracks (matches with the last frame) that carry no point, their Sampson
 * distances to the epipolar lines of the step
 * from the previous frame (whose pose is held). Plain C, no allocation.
 */
#ifndef MVOD_VO_POSEFIT_H
#define MVOD_VO_POSEFIT_H

#include <stdbool.h>
#include <stdint.h>

struct mvod_posefit {
	const double *X;       /* n_pts world points, 3 each */
	const double *uv;      /* their pixels in the current frame, 2 each */
	const uint8_t *use;    /* which of them take part (PnP's inliers) */
	int n_pts;
	const double *pt_sigma; /* their keypoints' sigma, pixels (NULL: 1): residuals in sigmas */
	const double *x1, *x2; /* n_epi tracks, normalised: previous frame, current frame */
	uint8_t *epi_use;      /* out: the tracks within epi_gate_px at the start pose */
	int n_epi;
	const double *epi_sigma; /* each track's sigma, pixels (NULL: 1) */
	double Rp[9], tp[3];   /* the previous frame's camera-from-world, held */
	double K[4];           /* fx, fy, cx, cy */
	/* With sigmas given, the next three are in sigmas instead of pixels. */
	double epi_weight;     /* a Sampson pixel's weight against a reprojection pixel's */
	double epi_gate_px;    /* tracks farther from their epipolar line at the start are out */
	double huber_px;       /* Huber's threshold, pixels */
	int iterations;
};

/*
 * Refines the current camera-from-world R, t (in and out) from the start given. Returns the
 * epipolar tracks used, or -EINVAL (nothing to refine on). The pose is changed only when the
 * cost went down.
 */
int mvod_posefit_refine(struct mvod_posefit *p, double R[9], double t[3]);

#endif
