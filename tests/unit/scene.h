/*
 * Exact synthetic scenes for the map-mode unit tests (bundle adjustment, PnP): a KITTI-like
 * pinhole camera (f = 500 px, 640 x 480) driving forward 1 unit per keyframe with a slow yaw,
 * points 8-40 units ahead, and a fixed-seed generator so every run sees the same numbers.
 */
#ifndef MVOD_TEST_SCENE_H
#define MVOD_TEST_SCENE_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>

#include "mvod/geom.h"

#define SCENE_F 500.0
#define SCENE_CX 320.0
#define SCENE_CY 240.0
#define SCENE_W 640
#define SCENE_H 480

/* Uniform in [lo, hi), from a linear congruential state (fixed seed: repeatable runs). */
static inline double scene_uniform(uint32_t *s, double lo, double hi)
{
	*s = *s * 1664525u + 1013904223u;
	return lo + (hi - lo) * (double)(*s >> 8) / (double)(1u << 24);
}

/* Normal(0, 1) by Box-Muller. */
static inline double scene_normal(uint32_t *s)
{
	double u1 = scene_uniform(s, 1e-12, 1.0), u2 = scene_uniform(s, 0.0, 1.0);
	return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

/* Camera-from-world pose of keyframe k as angle-axis (rad) + translation: centre (0.1 k, 0, k),
 * yaw 0.02 k rad. */
static inline void scene_pose(int k, double pose[6])
{
	double w[3] = {0, -0.02 * k, 0}, R[9], C[3] = {0.1 * k, 0, (double)k}, RC[3];
	mvod_rot_exp(w, R);
	mvod_mat3_vec(R, C, RC);
	for (int i = 0; i < 3; i++) {
		pose[i] = w[i];
		pose[3 + i] = -RC[i];
	}
}

static inline void scene_point(uint32_t *s, double X[3])
{
	X[0] = scene_uniform(s, -12, 12);
	X[1] = scene_uniform(s, -4, 3);
	X[2] = scene_uniform(s, 8, 40);
}

/* Projects world point X with a camera-from-world pose; false when behind or off the image. */
static inline bool scene_project(const double pose[6], const double X[3], double uv[2])
{
	double R[9], c[3];
	mvod_rot_exp(pose, R);
	mvod_mat3_vec(R, X, c);
	for (int i = 0; i < 3; i++)
		c[i] += pose[3 + i];
	if (c[2] <= 0.1)
		return false;
	uv[0] = SCENE_F * c[0] / c[2] + SCENE_CX;
	uv[1] = SCENE_F * c[1] / c[2] + SCENE_CY;
	return uv[0] >= 0 && uv[0] < SCENE_W && uv[1] >= 0 && uv[1] < SCENE_H;
}

#endif
