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

/* RMSE of dst - (s R src + t) after mvod_umeyama. */
double mvod_ate_rmse(const double *src, const double *dst, int n, const double R[9],
		     const double t[3], double s);

/* Relative pose error between consecutive frames. */
struct mvod_rpe {
	int n;                /* pairs counted */
	double rot_deg_mean, rot_deg_max; /* full rotation angle of dR_e dR_g^T */
	double dir_deg_mean, dir_deg_max; /* angle between translation directions (steps > 1 mm) */
	int n_dir;
};

/* Accumulates the RPE of one consecutive pair (estimate and ground truth, camera-to-world). */
void mvod_rpe_add(struct mvod_rpe *acc, const struct mvod_pose *e0, const struct mvod_pose *e1,
		  const struct mvod_pose *g0, const struct mvod_pose *g1);
void mvod_rpe_finish(struct mvod_rpe *acc);

#ifdef __cplusplus
}
#endif

#endif
