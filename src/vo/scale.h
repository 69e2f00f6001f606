/*
 * Metric scale for the VO: the ground plane among triangulated points (camera height), and a
 * filter that fuses metric measurements (height, the robot's odometer) into a scale that
 * structure alone carries between them. Plain C with no state outside the caller's structs, so
 * two-view mode (twoview.c) and map mode can share it.
 */
#ifndef MVOD_VO_SCALE_H
#define MVOD_VO_SCALE_H

#include <stdbool.h>

/* A plane n . X = h below the camera: n unit, pointing from the camera down to the ground. */
struct mvod_ground {
	double n[3];
	double h;     /* the camera's height above the plane, in the points' unit (> 0) */
	int inliers;  /* points within the inlier band */
};

/*
 * The ground plane among n points X (n x 3, camera frame, OpenCV axes: y down), any unit.
 * Only points below the optical centre (y > 0) take part; the plane's normal must be within
 * MVOD_GROUND_MAX_TILT_DEG of the camera's y axis (the pitch and roll are estimated, not
 * assumed). RANSAC over a fixed sample sequence (runs repeat exactly), then a least-squares
 * refit on the inliers. Returns 0, or -ENODATA when no plane has min_inliers points.
 */
#define MVOD_GROUND_MAX_TILT_DEG 20.0
int mvod_ground_fit(const double *X, int n, int min_inliers, struct mvod_ground *g);

/*
 * The scale filter: each measurement is a ratio, metric value / predicted value (for
 * two-view mode, the step length in metres / the step structure predicts). The first one is
 * taken whole; later ones move the scale by gain in log space, and a ratio beyond the gate
 * (one bad frame: a car's roof taken for the road) is refused, the gate widening with each
 * refusal in a row so that a real change is followed within a few frames.
 */
struct mvod_scale_filter {
	double gain;    /* fraction of a measurement's log ratio applied, (0, 1] */
	double gate;    /* largest |log ratio| accepted; INFINITY = all */
	double quality; /* 0-1, of the last accepted measurement */
	int since;      /* steps since the last accepted measurement; -1 before the first */
	int refused;    /* measurements refused in a row */
};
void mvod_scale_filter_init(struct mvod_scale_filter *f, double gain, double gate);
/*
 * One step: ratio (NAN when there was no measurement) and its quality (0-1). Returns the
 * factor to multiply the prediction by (1 without an accepted measurement); *used says
 * whether a measurement was accepted.
 */
double mvod_scale_filter_step(struct mvod_scale_filter *f, double ratio, double quality,
			      bool *used);
/* Whether any measurement was accepted yet (the output is metric). */
bool mvod_scale_filter_metric(const struct mvod_scale_filter *f);
/* 0-1: the last measurement's quality, decaying by MVOD_SCALE_DECAY per step without one. */
#define MVOD_SCALE_DECAY 0.95
double mvod_scale_filter_confidence(const struct mvod_scale_filter *f);

#endif
