/*
 * The essential matrix of two views, through OpenCV (five-point solver inside MAGSAC++ or
 * RANSAC), and its decomposition. Plain C; every function catches every exception and
 * returns 0 or -errno.
 */
#ifndef MVOD_VO_GEOM_ESSENTIAL_SHIM_H
#define MVOD_VO_GEOM_ESSENTIAL_SHIM_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Essential matrix (five-point) from normalised correspondences x1 -> x2 (n x 2 each), so
 * that x2^T E x1 = 0, by MAGSAC++ or by classic RANSAC; thresh is in normalised units (pixels
 * over focal length). mask[n] gets 1 for inliers. -ENODATA when no model is found.
 */
int mvod_essential_find(const double *x1, const double *x2, int n, bool magsac, double thresh,
			double conf, double E[9], uint8_t *mask, int *n_inliers);
/* The four candidates are (R1, t), (R1, -t), (R2, t), (R2, -t); |t| = 1. */
int mvod_essential_decompose(const double E[9], double R1[9], double R2[9], double t[3]);

#ifdef __cplusplus
}
#endif

#endif
