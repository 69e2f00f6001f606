/* PNG plots of trajectories. */
#ifndef MVOD_PLOT_H
#define MVOD_PLOT_H

#include "mvod/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Top-down view (x right, z forward: the ground plane of a camera frame) of an estimated path
 * against ground truth: metric axes with ticks, equal aspect, start and end markers, a heading
 * arrow at the end of the estimate (from heading, the last camera-to-world rotation; may be
 * NULL), a legend and a title. gt may be NULL / n_gt 0. Written through a temporary file and
 * rename(). Returns 0 or -errno.
 */
int mvod_plot_topdown(const char *path, const char *title, const double *est_xyz, int n_est,
		      const double heading[9], const double *gt_xyz, int n_gt);

#ifdef __cplusplus
}
#endif

#endif
