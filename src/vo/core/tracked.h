/*
 * The camera map mode tracks: the last tracked frame's pose, camera from world (X_cam = Rcw
 * X_world + tcw, in the map's unit: map/map.h's form), and its velocity, the motion from the
 * frame before, which predicts the next frame (the constant-velocity model). One owner: map
 * mode changes it only through these functions; its fields are read directly.
 */
#ifndef MVOD_VO_CORE_TRACKED_H
#define MVOD_VO_CORE_TRACKED_H

#include "mvod/geom.h"

struct mvod_tracked {
	double Rcw[9], tcw[3]; /* the last tracked frame */
	double vR[9], vt[3];   /* its motion from the frame before: X_cur = vR X_prev + vt */
};

/* Tracking starts at camera b (Rb, tb), having come from a (Ra, ta): a map's first step. */
void mvod_tracked_start(struct mvod_tracked *c, const double Ra[9], const double ta[3],
			const double Rb[9], const double tb[3]);
/* A new frame tracked at R, t: its velocity is the motion from the last one. */
void mvod_tracked_set(struct mvod_tracked *c, const double R[9], const double t[3]);
/* The same frame placed anew at R, t (a keyframe's pose, refined): the velocity is kept. */
void mvod_tracked_place(struct mvod_tracked *c, const double R[9], const double t[3]);
/*
 * The frame keeps its pose relative to a keyframe that moved from (Rk, tk) to (R, t) (bundle
 * adjustment): Rcw Rk^T R, Rcw Rk^T (t - tk) + tcw.
 */
void mvod_tracked_follow(struct mvod_tracked *c, const double Rk[9], const double tk[3],
			 const double R[9], const double t[3]);
/* The map's world scaled by s about centre (world frame): the pose with it, the velocity's step. */
void mvod_tracked_rescale(struct mvod_tracked *c, const double centre[3], double s);
/* The next frame's camera-from-world R, t at constant velocity. */
void mvod_tracked_predict(const struct mvod_tracked *c, double R[9], double t[3]);
/* The last step's length (map units): |vt|. */
double mvod_tracked_speed(const struct mvod_tracked *c);
/* The last frame's camera-to-world pose. */
void mvod_tracked_pose(const struct mvod_tracked *c, struct mvod_pose *c2w);

#endif
